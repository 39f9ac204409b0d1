// Checks that a map of a disk is fit to be written: no folded triangle, none collapsed below what
// the output's texture coordinates can hold.
#pragma once
#include <vector>

#include "param/square_map_options.hpp"

namespace tightex {

/// Number of triangles whose UV signed area is not strictly positive.
size_t count_folds(const Surface& mesh, const std::vector<Vec2>& uv);

/// Triangles of a unit-square map that would not survive being written: placed in options' rectangle,
/// their area in texels is below what rounding the texture coordinates (2^-52 of the texel extent)
/// can move per unit of their perimeter, so a reader may find them folded or empty. Folded ones count
/// too. `worst_vertex` (optional) gets a vertex of the worst one; untouched when none.
size_t count_collapsed(const Surface& mesh, const std::vector<Vec2>& uv, const SquareMapOptions& options, uint32_t* worst_vertex = nullptr);

}  // namespace tightex
