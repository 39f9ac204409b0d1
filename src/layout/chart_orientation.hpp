// Which way up a component's square goes into its rectangle: the turn by a multiple of a quarter that
// keeps the input texture's axes pointing the way they did (printed matter comes out upright).
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "core/mesh.hpp"
#include "core/stage_stats.hpp"
#include "core/surface.hpp"

namespace tightex {

/// Where a triangle's affine map from its input texels to its output texels takes the input's u axis
/// (1, 0) and v axis (0, 1): corner k's input uv `in_uv[k]` times `in_texels` (the image's width and
/// height) goes to `out_uv[k]` times `out_texels`, uv "v up" on both sides. nullopt where either
/// triangle has no texture area. docs/metrics.md's texture axes angle and orient_chart read it.
std::optional<std::array<Vec2, 2>> texel_axes_images(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels,
                                                     const std::array<Vec2, 3>& out_uv, const Vec2& out_texels);

/// What orient_chart chose and why.
struct ChartTurn {
  int quarter_turns = 0;  // counter-clockwise about the square's centre, 0..3
  /// The input's texture axes in the output's texels before the turn: their area-weighted mean
  /// direction, in degrees counter-clockwise from the output's axes (0: upright); NaN where no real
  /// triangle has texture area on both sides.
  double mean_turn_deg = 0;
};

/// Turns the unit-square map `uv` of `disk` (input_face, input_corner set; one uv per disk vertex) by
/// the multiple of a quarter turn that brings the input's texture axes, read through each real
/// triangle's affine map from its input texels to its texels in rectangle r, closest on average to
/// the output's own axes: the input's u axis towards +u, its v axis towards +v. A quarter turn would
/// swap the texel stretch the map was made for, so it is tried only where r is square (within 1%);
/// otherwise only the half turn is. Mirrors are not: the map keeps the surface's handedness, as the input's charts do (a mirror
/// would reverse every triangle's texture winding).
/// Guarantees: uv is the same map turned exactly ((x, y) -> (1 - y, x) per quarter turn), so it stays
/// on the unit square and fold-free if it was. Throws nothing but std::bad_alloc.
ChartTurn orient_chart(const TexturedMesh& input, const Surface& disk, const Rect& r, std::vector<Vec2>& uv);

}  // namespace tightex
