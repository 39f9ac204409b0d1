// The models report.html's 3D views show: above a triangle cap, a copy decimated by vertex clustering
// that keeps what the views show (the texture through its coordinates, the seams, the density).
#pragma once
#include <cstddef>

#include "core/mesh.hpp"

namespace tightex {

/// `mesh` decimated by vertex clustering on a grid of cubic cells of side `cell` (every vertex in a cell
/// becomes one, at their mean). A corner keeps its material; its texture coordinate is the mean over
/// its "patch": the corners in its cell that share its material and are joined to it by equal
/// coordinates at a vertex or by a triangle's edge inside the cell, so that the coordinates stay
/// continuous inside a chart and jump where the chart does (its seams stay seams). A triangle whose
/// corners fall in fewer than three cells is dropped, as is a repeat of one already kept on the same
/// three cells. The copy's textures hold their sizes, not their pixels. Throws only std::bad_alloc.
TexturedMesh clustered_mesh(const TexturedMesh& mesh, double cell);

/// The cell of clustered_mesh that leaves `mesh` at most `max_triangles` triangles (0 when it has no more
/// than that already): a first guess from its area, grown until the count is under the cap.
double cluster_cell(const TexturedMesh& mesh, size_t max_triangles);

}  // namespace tightex
