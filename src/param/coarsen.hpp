// A coarse copy of a disk for the multilevel density map (multilevel.hpp): interior vertices removed by
// half-edge collapses, the boundary (and with it the cut, the corners and every chord) kept as it is.
#pragma once
#include <vector>

#include "core/disk.hpp"
#include "param/multigrid.hpp"

namespace tightex {

/// A coarse disk whose vertices are a subset of a fine disk's.
struct CoarseDisk {
  Disk disk;                          // vertex_parent / face_parent: the fine disk's parents (as the fine disk's own)
  std::vector<uint32_t> fine_vertex;  // per coarse vertex, the fine vertex it is
  std::vector<double> face_target;    // per coarse face, the fine faces' targets it took over (their sum is kept)
};

/// Removes interior vertices of `fine` (shortest edge first, each moved onto a neighbour) until at most
/// `max_vertices` remain or no collapse is allowed. A collapse is allowed where the surface stays a
/// manifold disk (the link condition), no edge joins two boundary vertices that were not joined (no new
/// chord, so the boundary maps to the square as the fine one does), no face touching scaffolding
/// changes, and every changed face keeps its orientation (normal within 70 degrees) and a fair shape.
/// The targets of the two faces a collapse removes go to the faces around it, so each region keeps its
/// share. Requires a disk (one boundary loop) and one target per face. Guarantees: the boundary vertices
/// all kept, in the same order; fine_vertex strictly increasing.
CoarseDisk coarsen_disk(const Disk& fine, const std::vector<double>& face_target, size_t max_vertices);

/// coarsen_disk's copy for each of `max_vertices` (in decreasing order), from one run of collapses: the
/// collapses stop at each size in turn and go on from there, so each copy is the one coarsen_disk gives
/// for that size, for the cost of one. With `aggregates` given, the collapses also stop at each of
/// `aggregate_sizes` (decreasing; they may go below the copies' sizes) and record there which vertex
/// stands for each fine vertex: the nested aggregates of the full mesh's iterative solves
/// (MultilevelSolver), one level per size.
std::vector<CoarseDisk> coarsen_disk_in_steps(const Disk& fine, const std::vector<double>& face_target,
                                              const std::vector<size_t>& max_vertices, const std::vector<size_t>& aggregate_sizes = {},
                                              VertexAggregates* aggregates = nullptr);

}  // namespace tightex
