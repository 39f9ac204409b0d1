// Beyond the paper: the symmetric Dirichlet refinement of a fold-free map (SLIM).
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "param/square_map_options.hpp"

namespace tightex {

struct SlimStats {
  int iterations = 0;
  double energy_before = 0, energy = 0;  // area-weighted symmetric Dirichlet energy (2 per unit area = isometric)
  std::string stopped;                   // "converged", "iterations", "no descent" or "solver"
  int proxy_steps = 0;                   // steps whose Newton system did not solve: SLIM's proxy instead
  int capped_steps = 0;                  // of those, steps whose proxy solved only with its weights capped
};

/// refine_map's linear system over one mesh's free coordinates: its pattern (where each face's entries
/// land) and CHOLMOD's analysis, the same for every step and for every refinement of that mesh that
/// frees the same coordinates.
class RefinementSystem;
struct VertexAggregates;

/// A triangle's shape in the plane (its corners in the face's order; position and rotation do not matter).
using FaceShape = std::array<Vec2, 3>;

/// A free coordinate that may move to one side of a line only: coordinate `axis` (0: u, 1: v) of
/// `vertex` stays at most `bound` (sign +1) or at least `bound` (sign -1).
struct CoordinateBound {
  uint32_t vertex = 0;
  int axis = 0;
  double bound = 0;
  int sign = 1;
};

/// Lowers the symmetric Dirichlet energy |J|^2 + |J^-1|^2 of every face, measured against its target
/// shape (the 3D triangle scaled to area target[f]; a face of zero 3D area keeps its start shape and
/// area; `shapes`, optional: face f's shapes[f] instead, where that has a positive area), weighted by
/// target area; fixed[v] bit 0 holds the vertex's u, bit 1 its v (3: the vertex stays; 1 or 2: it
/// slides along a side). Each step solves the projected Newton system (SLIM's reweighted proxy,
/// Rabinovich, Lipman and Sorkine-Hornung 2017, where that fails) with CHOLMOD (pattern analysed once;
/// in `vertex_order`, nested_dissection_order's, where given), then a line search.
/// Requires uv fold-free, one target per face. Guarantees uv stays fold-free (the line search stops
/// short of any triangle's collapse) and its energy never rises. Stops after `iterations` steps, when a
/// step gains less than 0.1%, or when no step lowers the energy; on_step (optional) hears each step.
/// `system` (optional): the system of an earlier refinement of this mesh, or prepare_refinement's,
/// used where its free coordinates are this refinement's (their pattern and analysis are then not made
/// again), replaced otherwise; it must have been made with the same supernodal_from and vertex_order.
/// `bounds` (optional): free coordinates that must stay on one side of a line, which uv meets: the line
/// search stops a coordinate at its line (projected), and one on its line that the energy presses
/// across is held for the step (projected Newton's active set).
SlimStats refine_map(const Surface& mesh, const std::vector<char>& fixed, const std::vector<double>& target, int iterations,
                     std::vector<Vec2>& uv, long supernodal_from = kSupernodalFrom, const std::function<void(int step)>& on_step = {},
                     const std::vector<FaceShape>* shapes = nullptr, const std::vector<int>* vertex_order = nullptr,
                     std::shared_ptr<RefinementSystem>* system = nullptr, const std::vector<CoordinateBound>* bounds = nullptr);

/// The system refine_map(mesh, fixed, target, ..., supernodal_from, ..., vertex_order) solves from a
/// fold-free start map, built and analysed before that map exists (every face with a positive target
/// then has a frame): for a caller with a core to spare while it makes the start. Null where no
/// coordinate is free. aggregates (optional): its steps are solved by conjugate gradients
/// preconditioned over these aggregates of the mesh's vertices (MultilevelSolver), not factorised:
/// memory linear in the mesh.
std::shared_ptr<RefinementSystem> prepare_refinement(const Surface& mesh, const std::vector<char>& fixed, const std::vector<double>& target,
                                                     long supernodal_from = kSupernodalFrom, const std::vector<int>* vertex_order = nullptr,
                                                     const VertexAggregates* aggregates = nullptr);

}  // namespace tightex
