// The multilevel density map: the expensive non-linear steps (reweighting, flow, symmetric Dirichlet
// refinement) on a coarse copy of a large disk, carried to the full mesh fold-free.
#pragma once
#include <optional>
#include <vector>

#include "param/coarsen.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// The options a coarse copy of a disk is mapped with (step 1 below): `options` with the copy's own face
/// targets, its density steps made despite any crowding (no reason to re-cut the full mesh).
SquareMapOptions coarse_options(const SquareMapOptions& options, const CoarseDisk& coarse);

/// Where options ask for it (a density target, balance 1, more than options.multilevel_from vertices):
/// 1. coarsen_disk to at most options.coarse_vertices (boundary, cut and chords kept) and map that with
///    map_disk (the same steps as a small disk gets; its crowding does not stop the density steps);
///    where that map folds, again from a copy of twice the vertices (up to three copies, each within
///    multilevel_from and a quarter of the disk); the full mesh's Laplacians of steps 2 and 3 (their
///    patterns and CHOLMOD's analyses) are made beside that map, which does not need them, and the
///    symmetric Dirichlet steps' system beside step 2 and the reweighting;
/// 2. carry it to the full mesh: the harmonic map between the coarse vertices (held where the coarse
///    map put them) is a target that follows the coarse map but may fold; the Tutte map with that
///    target's own cotangent weights (clamped positive) and only the boundary held reproduces it where
///    its triangles are unfolded and not obtuse, and cannot fold (positive weights, convex boundary);
/// 3. up to options.fine_reweighting reweighting steps (reweight_towards_density, the boundary held)
///    and options.fine_steps symmetric Dirichlet steps (refine_towards_targets, the boundary sliding
///    along the sides as in the coarse map) on the full mesh: both keep the map fold-free.
/// Returns nullopt, with stats untouched, where it does not apply or cannot give a fold-free map (the
/// coarse map folds, a solve fails, the Tutte map folds numerically): the caller then maps the full
/// mesh itself. Otherwise guarantees a fold-free map of every vertex with the boundary on the square as
/// the coarse map placed it, and fills stats (the coarse map's figures, the full mesh's density spread,
/// corners, coarse_vertices, fine_reweighting, fine_steps). Throws InternalError from map_disk.
std::optional<std::vector<Vec2>> multilevel_map(const Disk& disk, const SquareMapOptions& options, SquareMapStats& stats);

}  // namespace tightex
