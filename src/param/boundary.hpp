// Alg. 1 of the paper (§4.2): the disk's boundary onto the unit square's sides.
#pragma once
#include <array>
#include <vector>

#include "core/disk.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// The unit square's corners in boundary order: (0,0), (1,0), (1,1), (0,1). Side k runs from corner k
/// to corner k + 1.
inline const std::array<Vec2, 4> kSquareCorners{Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};

/// A disk's boundary placed on the unit square. Position i stands for boundary vertex
/// disk.boundary[i].
struct SquareBoundary {
  std::vector<Vec2> uv;             // where each boundary position goes
  std::array<size_t, 4> corner{};   // the positions at kSquareCorners (choose_corners)
  std::vector<int> side_of;         // the side (0 bottom, 1 right, 2 top, 3 left) each position starts
  std::vector<uint32_t> edge_face;  // the face of boundary edge (i, i + 1); kNone without a density target
  std::vector<char> pinned;         // corners and bumped positions: fixed in both coordinates
  size_t bumped_vertices = 0;
};

/// Alg. 1: chooses the four corners (choose_corners with options.corners) and places each side's
/// vertices by arc length between its corners. With a density target (options.face_target), each
/// boundary edge's 3D length is scaled by the square root of its face's target density (target area
/// / 3D area, to the power options.balance), so the sides are measured in the units the target asks
/// for, and the corners share the boundary out as options' rectangle shares its perimeter.
/// A chord (interior edge between two boundary vertices on one side of the square) would squash every
/// triangle beyond it onto the side; the boundary between its ends is lifted outward by a sine bump of
/// options.bump_texels, so those triangles keep positive area (their vertices are then pinned).
/// Requires a disk whose boundary has at least 3 vertices and, if options.face_target is given, one
/// target per face. Guarantees: the corners at kSquareCorners, every other position on its side or
/// (bumped) just outside it, in boundary order. Throws InternalError from choose_corners.
SquareBoundary map_boundary_to_square(const Disk& disk, const SquareMapOptions& options);

}  // namespace tightex
