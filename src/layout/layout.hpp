// Where each component's unit square goes in texture space: rectangles of texels in one shared atlas,
// or one texture per component as in the paper.
#pragma once
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "core/mesh.hpp"
#include "core/stage_stats.hpp"

namespace tightex {

/// Where the unit square's point s (u right, v up) lands in rectangle r, in pixel coordinates (x right,
/// y down, texel centres at +0.5): the square's corners on the corner texels' centres, pushed outward
/// by kChartInset so that the outermost texel centres lie strictly inside the chart. Exactly on its
/// edge they would count as covered or not by an ulp of the stored texture coordinate (u = x / W read
/// back as u * W), and whole rows of texels could miss docs/metrics.md's utilization.
constexpr double kChartInset = 1e-6;
inline Vec2 rect_pixel(const Rect& r, const Vec2& s) {
  return Vec2(r.x + 0.5 - kChartInset + s.x() * (r.w - 1 + 2 * kChartInset),
              r.y + 0.5 - kChartInset + (1.0 - s.y()) * (r.h - 1 + 2 * kChartInset));
}

/// A texture side at `scale` of `side` (the rate search's smaller or larger textures): a multiple of 4,
/// at least 8; never more than the side itself for a scale below 1, never less above it; the side
/// itself at 1.
inline int texture_side_at(int side, double scale) {
  if (scale == 1) return side;
  const int rounded = std::max(8, int(std::lround(side * scale / 4)) * 4);
  return scale < 1 ? std::min(side, rounded) : std::max(side, rounded);
}

/// How layout_atlas shares the texture out between components.
enum class AtlasShares {
  /// Proportional to area, except where that squeezes a group into a strip (a main surface beside a
  /// fragment of 1% of its area: a 100:1 strip): there the cut moves to where a model of the colour
  /// error (texel spacing squared, times the loss of a stretched sampling) is least, giving the strip
  /// more than its share.
  kLeastError,
  /// Exactly proportional to area: the area map's promise of the same texels per unit area everywhere.
  kExact,
};

/// One texture of width x height shared by all components (beyond the paper, whose layout is
/// layout_per_component): each component gets a rectangle whose area is proportional to its surface
/// area (as `shares` says) and the rectangles tile the texture exactly, without a gap.
/// Method: recursive bisection (a slice-and-dice treemap): the components, largest first, are split
/// into two groups of nearly equal area and the rectangle is cut across its longer side in that
/// proportion, which keeps aspect ratios near 1; where the minimum sizes forbid that cut, across the
/// other side, then at other split points.
/// Requires: min_side >= 1; areas >= 0 (negative ones count as 0).
/// Guarantees: rectangle i (image 0) belongs to areas[i]; every rectangle is at least min_side texels
/// on each side (a component too small for that still gets min_side x min_side: its share is rounded
/// up); together they tile the texture. Deterministic.
/// Throws: InputError when the texture cannot hold that many components of min_side x min_side.
std::vector<Rect> layout_atlas(const std::vector<double>& areas, int width, int height, int min_side = 4,
                               AtlasShares shares = AtlasShares::kLeastError);

/// layout_atlas where a texture too small for the components is an expected answer, not an error:
/// std::nullopt instead of the InputError, the same rectangles otherwise.
std::optional<std::vector<Rect>> try_layout_atlas(const std::vector<double>& areas, int width, int height, int min_side = 4,
                                                  AtlasShares shares = AtlasShares::kLeastError);

/// The paper's layout (§4.3: every component's unit square becomes a texture of its own): the largest
/// component size x size texels (aspect 1: the paper's square; otherwise as many texels with
/// width/height `aspect`) and the others scaled by the square root of their area share.
/// Requires: areas >= 0 (negative ones count as 0); aspect > 0 (anything else counts as 1).
/// Guarantees: rectangle i is image i, at (0, 0), at least min_side texels on each side. Throws nothing
/// but std::bad_alloc.
std::vector<Rect> layout_per_component(const std::vector<double>& areas, int size, int min_side = 4, double aspect = 1.0);

}  // namespace tightex
