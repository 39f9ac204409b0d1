// Where each component's unit square goes in texture space.
#pragma once
#include <vector>

#include "core/mesh.hpp"

namespace tightex {

/// A rectangle of texels: columns [x, x+w), rows [y, y+h) (row 0 at the top of the image).
struct Rect {
  int image = 0;
  int x = 0, y = 0, w = 0, h = 0;
};

/// Where the unit square's point s (u right, v up) lands in rectangle r, in pixel coordinates (x right,
/// y down, texel centres at +0.5): the square's corners on the corner texels' centres, pushed outward
/// by kChartInset so that the outermost texel centres lie strictly inside the chart. Exactly on its
/// edge they would count as covered or not by an ulp of the stored texture coordinate (u = x / W read
/// back as u * W): before this, a whole row of texels of the fuze and bust outputs (368 and 1672)
/// missed METRICS.md's utilization.
constexpr double kChartInset = 1e-6;
inline Vec2 rect_pixel(const Rect& r, const Vec2& s) {
  return Vec2(r.x + 0.5 - kChartInset + s.x() * (r.w - 1 + 2 * kChartInset), r.y + 0.5 - kChartInset + (1.0 - s.y()) * (r.h - 1 + 2 * kChartInset));
}

/// One texture of width x height shared by all components: each component gets a rectangle whose area
/// is proportional to its surface area and the rectangles tile the texture exactly, without a gap.
/// Method: recursive bisection (a slice-and-dice treemap): the components, largest first, are split
/// into two groups of nearly equal area and the rectangle is cut across its longer side in that
/// proportion, which keeps aspect ratios near 1; where that proportion would squeeze a group into a
/// strip (a main surface beside a fragment of 1% of its area: a 100:1 strip), the cut moves to where a
/// model of the colour error (texel spacing squared, times the loss of a stretched sampling) is least,
/// giving the strip more than its share (`exact_shares` keeps the proportion: the area map's promise of
/// the same texels per unit area everywhere). Every rectangle is at least min_side texels on each
/// side (a component too small for that still gets min_side x min_side: its share is rounded up).
/// Throws InputError when the texture cannot hold that many components.
std::vector<Rect> layout_atlas(const std::vector<double>& areas, int width, int height, int min_side = 4,
                               bool exact_shares = false);

/// The paper's layout: one image per component, the largest component size x size texels (aspect 1:
/// the paper's square; otherwise as many texels with width/height `aspect`) and the others scaled by the
/// square root of their area share (at least min_side on a side). Image i = component i.
std::vector<Rect> layout_per_component(const std::vector<double>& areas, int size, int min_side = 4, double aspect = 1.0);

}  // namespace tightex
