// Beyond the paper: the density-equalising flow of Gastner & Newman (2004) on a map of a disk.
#pragma once
#include <string>
#include <vector>

#include "core/surface.hpp"

namespace tightex {

struct FlowOptions {
  int grid = 0;  // cells along the rectangle's mean side; 0: 2 sqrt(faces), within 32..256
  int max_steps = 300;
  double tolerance = 0.02;  // stop once the diffused density is within +-this of its mean everywhere
  double time_scale = 1.0;  // diffusion time, in units of the rectangle's longer side squared
  double start_cells = 1;   // the density starts diffused over this many cells (time: its square x a cell's)
  /// true: a step is taken only if every face keeps more than half its area. false: the vertices follow
  /// the flow whatever becomes of the faces between them (a face spanning many cells of a field that
  /// bends across it can fold): the result is a shape to aim at (refine_map's `shapes`), not a map.
  bool fold_free = true;
};

struct FlowStats {
  int steps = 0;
  std::string stopped;  // "converged", "time", "steps" or "fold" (no step short enough kept every face)
};

/// The density-equalising flow of Gastner & Newman (2004, "Diffusion-based method for producing
/// density-equalizing maps", PNAS 101:7499) in the texel rectangle of width/height `aspect` (uv in
/// the unit square): each face's target is its population, the density diffuses with zero flux
/// through the sides, and the vertices move with -grad(rho)/rho until the density is even, so each
/// face tends to its target area. fixed[v] as for refine_map (bit 0 holds u, bit 1 v); side vertices
/// slide along their side and stay exactly on it. Fold-free: a step is taken only if every face keeps
/// more than half its area (else it is halved), and the flow stops ("fold") where no step would;
/// unless options.fold_free is false.
/// `tracers` (optional, unit square like uv): further points carried by the same flow, unconstrained.
/// Requires one target per face and one uv per vertex (otherwise, or without a positive target, uv
/// is left as it is and no step is reported).
FlowStats flow_density(const Surface& mesh, const std::vector<char>& fixed, const std::vector<double>& target, double aspect,
                       std::vector<Vec2>& uv, const FlowOptions& options = {}, std::vector<Vec2>* tracers = nullptr);

/// The cells along the flow grid's mean side for a map of `faces` faces (FlowOptions::grid, or its default).
int flow_grid(size_t faces, const FlowOptions& options = {});

}  // namespace tightex
