// The map's texture coordinates as the output stores them: glTF and PLY hold them as 32-bit floats.
// A map that is fold-free in doubles can still have a sliver whose float coordinates fold or collapse
// (a triangle a ten-thousandth of a texel high, at millions of triangles per texture): those vertices
// are moved by a few float steps to where every triangle around them keeps its orientation.
#pragma once
#include <vector>

#include "core/stage_stats.hpp"
#include "core/surface.hpp"

namespace tightex {

/// What keep_orientation_in_float did.
struct FloatGuard {
  size_t moved = 0;    // vertices moved (each by a few float steps)
  size_t unfixed = 0;  // real triangles still folded or collapsed in floats
};

/// The real triangles of `disk` (input_face set) whose texture coordinates, as written (rect_pixel of
/// `uv` in rectangle r of an image width x height, divided by its size and rounded to float), fold or
/// collapse: for each, one of its vertices is moved to a float position a few steps away where every
/// real triangle around it is positive in floats; `uv` gets the moved vertices (exactly the unit-square
/// point of that float position, up to rounding). A map with no such triangle is left as it is.
FloatGuard keep_orientation_in_float(const Surface& disk, const Rect& r, int width, int height, std::vector<Vec2>& uv);

}  // namespace tightex
