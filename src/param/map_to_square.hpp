// The map of a disk onto the unit square (paper §4.2): Alg. 1 boundary, Alg. 2 harmonic map, and
// beyond the paper the density maps.
#pragma once
#include <vector>

#include "param/boundary.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// Maps a topological disk onto the unit square, boundary counter-clockwise (paper §4.2).
/// 1. Alg. 1 (map_boundary_to_square): corners by options.corners, each side by arc length, chords'
///    ends lifted off their side by a bump of options.bump_texels.
/// 2. Alg. 2 (fold_free_harmonic_map): the harmonic map with cotangent weights and the boundary fixed;
///    if any triangle folds (cotangent weights go negative on obtuse triangles), recomputed with the
///    negative weights clamped positive, which gives a bijection onto a convex boundary
///    (Tutte/Floater); uniform weights are the last resort for numerically extreme meshes.
/// Without a density target, a triangle too small for the written texture coordinates' rounding
/// counts as folded (count_collapsed) and its region as crowded (stats->crowded_vertex).
/// 3. With a density target (options.face_target), from a fold-free map: the boundary is placed by
///    target length instead of arc length, the interior is re-solved with reweighted positive edge
///    weights (reweight_towards_density), moved by the density-equalising flow where that stalled
///    (flow_towards_targets, options.density_flow) and refined by symmetric Dirichlet steps
///    (refine_towards_targets), in which a chord's bump and the chord's ends may move inwards, off
///    their side, so the triangles beyond the chord are not left the bump's sliver. Each keeps the map
///    fold-free.
/// 4. A large disk with a density target (options.multilevel_from) is mapped by multilevel_map: steps
///    1-3 on a coarse copy, then carried to the full mesh; where that cannot be done fold-free, as above.
/// Requires a disk (one boundary loop of at least 3 vertices) and, if given, one face target per face.
/// Guarantees one UV per disk vertex; stats->flipped counts the triangles that fold (0 unless every
/// weighting folded). Throws InternalError if the requirements do not hold or no weighting could be
/// solved (a factorisation failed for each).
std::vector<Vec2> map_to_square(const Disk& disk, const SquareMapOptions& options, SquareMapStats* stats);

}  // namespace tightex
