// Beyond the paper: the square map's texel density brought towards per-face targets by an
// iteratively reweighted Tutte embedding.
#pragma once
#include <vector>

#include "param/boundary.hpp"
#include "param/harmonic.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// Iteratively reweighted Tutte embedding towards options.face_target (in the spirit of Yoshizawa,
/// Belyaev and Seidel 2004's stretch minimisation). Each step multiplies an edge's weight by the
/// square root of the area ratio (UV area / target) of its two faces, so a squeezed region's springs
/// slacken and it expands, and re-solves the interior; with `sliding` given, the boundary vertices
/// also slide along their sides (each boundary edge scaled by the square root of its face's
/// target/area). Every step is a convex-combination map onto the convex square, so by Tutte/Floater it
/// cannot fold; a step that folds numerically stops the iterations. Keeps the iterate closest to the
/// targets.
/// Requires: `uv` a fold-free map with the boundary placed (vertices `boundary`), `weights` positive
/// (edge_weights), `solver` the one that solved for them (the sparsity pattern never changes).
/// Reports in stats: blended_target, spread_before_*, spread_*, iterations and stopped ("converged",
/// "iterations", "stalled", "fold" or "solver"). Calls options.progress up to 0.4.
void reweight_towards_density(const Surface& mesh, const std::vector<uint32_t>& boundary, const SquareMapOptions& options,
                              const SquareBoundary* sliding, std::vector<double> weights, DirichletSolver& solver, std::vector<Vec2>& uv,
                              SquareMapStats& stats);

}  // namespace tightex
