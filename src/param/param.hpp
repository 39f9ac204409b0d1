// The map of a disk onto the unit square (paper §4.2): Alg. 1 boundary, Alg. 2 harmonic map.
#pragma once
#include <string>
#include <vector>

#include "topology/topology.hpp"

namespace tightex {

struct SquareMapOptions {
  // Size of the texel rectangle the square will be stretched to. Used only to size the boundary bumps
  // (see map_to_square) in texels; the map itself is computed on the unit square.
  int rect_width = 1024, rect_height = 1024;
  double bump_texels = 0.3;  // < 0.5: a bump stays inside the chart's own outermost texels
};

struct SquareMapStats {
  std::string weights;          // "cotangent", "clamped-cotangent" or "uniform": the first that gave no fold
  size_t flipped = 0;           // triangles with UV area <= 0 in the returned map (0 unless every weight failed)
  size_t negative_weights = 0;  // interior edges whose cotangent weight was negative
  std::array<uint32_t, 4> corners{};  // boundary vertices at (0,0), (1,0), (1,1), (0,1)
  std::vector<size_t> folds_per_attempt;  // folded triangles of each weighting tried, in order
  size_t bumped_vertices = 0;
  /// A vertex of a triangle that folded even with positive weights: the map crowded a region below
  /// floating-point precision there (harmonic maps crowd exponentially in protrusions). kNone if none.
  uint32_t crowded_vertex = kNone;   // boundary vertices lifted off a side to keep a chord's triangles open
};

/// Maps a topological disk onto the unit square, boundary counter-clockwise.
/// Corners: the four boundary vertices that split the boundary into four arcs of (nearly) equal length,
/// snapped to an "ear" (a boundary vertex with a single triangle, which must sit on a corner or its
/// triangle collapses) when one lies within 5% of the boundary length. Boundary: arc length between
/// corners (Alg. 1). Interior: harmonic with cotangent weights, boundary rows eliminated, one CHOLMOD
/// factorisation for u and v (Alg. 2).
/// Fold-free guarantee: if any triangle folds (cotangent weights go negative on obtuse triangles), the
/// map is recomputed with the negative weights clamped positive, which gives a bijection onto a convex
/// boundary (Tutte/Floater); uniform weights are the last resort for numerically extreme meshes.
/// A chord (interior edge between two boundary vertices on one side of the square) would squash every
/// triangle beyond it onto the side; the boundary between its ends is lifted outward by a sine bump of
/// `bump_texels`, so those triangles keep positive area.
std::vector<Vec2> map_to_square(const Disk& disk, const SquareMapOptions& options, SquareMapStats* stats);

/// Number of triangles whose UV signed area is not strictly positive.
size_t count_folds(const Surface& mesh, const std::vector<Vec2>& uv);

}  // namespace tightex
