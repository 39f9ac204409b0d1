// Which four boundary vertices of a disk go to the square's corners (docs/corners.md).
#pragma once
#include <array>
#include <vector>

#include "core/disk.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// The four boundary positions (indices into disk.boundary, in boundary order, distinct unless the
/// boundary has 3 vertices: {0, 1, 2, 2}) that map_boundary_to_square sends to (0,0), (1,0), (1,1),
/// (0,1). `arc`: cumulative boundary length, arc[i] at boundary vertex i, arc[nb] the total
/// (map_boundary_to_square passes density-scaled lengths when it has a density target).
/// kEqualArcs: the vertices that share the length out as a rectangle of width/height `aspect` shares
/// its perimeter (the quarters for the square, aspect 1), from the first "ear" (a boundary vertex
/// with a single triangle, which must sit on a corner or its triangle collapses) or vertex 0, snapped to
/// an ear within 5% of the length. kTurningAngle: the vertices where the boundary turns most (pi minus
/// the interior angle sum, integrated over +-2.5% of the length with tent weights, so zigzags cancel),
/// ears first, greedily, skipping any closer than 10% of the length to one already chosen (`aspect` is
/// not used: the turning decides).
/// Throws InternalError if the boundary has fewer than 3 vertices, `arc` does not have nb + 1 entries
/// or `aspect` is not a positive finite number.
std::array<size_t, 4> choose_corners(const Disk& disk, const std::vector<double>& arc, CornerRule rule, double aspect = 1.0);

}  // namespace tightex
