// Beyond the paper: the density maps' last stages, after the reweighting (density_reweighting.hpp):
// the density-equalising flow and the symmetric Dirichlet refinement, both in the texel rectangle.
#pragma once
#include <memory>
#include <vector>

#include "param/boundary.hpp"
#include "param/slim.hpp"
#include "param/square_map_options.hpp"

namespace tightex {

/// What the density maps' last stages hold fixed, and the rectangle they work in. Per vertex, bit 0
/// holds u, bit 1 holds v (refine_map's and flow_density's `fixed`).
struct DensityConstraints {
  const Surface& mesh;
  const SquareMapOptions& options;
  double aspect = 1;                                     // the texel rectangle's width/height (map_aspect)
  std::vector<char> fixed;                               // for the refinement: see density_constraints
  std::vector<CoordinateBound> bounds;                   // for the refinement: bumps and their chords' ends move inwards only
  std::vector<char> fixed_on_sides;                      // for a refinement with no bounds: corners, bumps and chords' ends stay
  std::vector<char> flow_fixed;                          // for the flow: only the corners stay
  std::shared_ptr<const std::vector<int>> vertex_order;  // the systems' fill-reducing order (optional)
  /// The refinements' system (refine_map's `system`): made by the first, or ahead by the caller
  /// (prepare_refinement with `fixed`), and reused by every refinement that frees the same coordinates.
  mutable std::shared_ptr<RefinementSystem> refinement = {};
};

/// The constraints for a disk whose boundary map_boundary_to_square placed. Every other boundary
/// vertex slides along its side (a horizontal side holds v, a vertical one u); all stay when
/// options.slide_boundary is false. A bump's neighbours on the side (the ends of its chords) keep
/// their place along the side in the refinement: a free vertex beside a bump could slide past it
/// without any triangle collapsing (the bump is off the line) and turn the boundary back on itself.
/// With options.chords_move_inwards (and no flow) the bumps and the chords' ends move inwards instead
/// (bounds): the faces beyond a chord lie between it and the side, so with its ends on the side they
/// keep only the bump's sliver of area, however large their targets; the chords' ends' next
/// neighbours are held, so every boundary vertex from one to the other keeps its place along the side
/// and the boundary there cannot cross itself (fixed_on_sides: the constraints without that). In the
/// flow every side vertex slides with the field, the bumps' too (a continuous flow along a line keeps
/// its points in order, so none passes a bump). vertex_order (optional): the systems' fill-reducing
/// order (vertex_order_from).
DensityConstraints density_constraints(const Disk& disk, const SquareBoundary& boundary, const SquareMapOptions& options,
                                       std::shared_ptr<const std::vector<int>> vertex_order = {});

/// The density error of uv against stats.blended_target (scaled to the map's area) into
/// stats.spread_p5 and stats.spread_p95 (P5 / P95 of log2(area / target), weighted by target).
/// Requires stats.blended_target set, one per face.
void measure_density_spread(const Surface& mesh, const std::vector<Vec2>& uv, SquareMapStats& stats);

/// Where the reweighting stalled short of the targets (options.density_flow; the density error in
/// stats above options.tolerance_log2; at least kFlowMinFaces faces), the density-equalising flow
/// (flow_density) moves the whole map on towards stats.blended_target, in rounds from a coarser to a
/// finer start, each kept only if it narrows the density error; if none does, the map stays as it
/// was. Requires uv fold-free and stats.blended_target set (reweight_towards_density). Guarantees uv
/// stays fold-free. Reports flow_steps, flow_lead_steps, flow_shape_steps, flow_stopped and the density
/// error (spread_p5, spread_p95).
void flow_towards_targets(const DensityConstraints& constraints, std::vector<Vec2>& uv, SquareMapStats& stats);

/// The symmetric Dirichlet refinement towards stats.blended_target (options.refine_iterations steps
/// of refine_map in the rectangle's proportions; with options.refine_keeps_density a step at a time,
/// the first that would widen the density error by more than 0.1 (log2) beyond the start map's
/// shortened until it does not, or undone, and the last); then options.correction_rounds rounds of
/// target correction. Where the chords' ends moved inwards (constraints.bounds) and the notches beside
/// them leave the real faces less than 99% of the square, it is made again with them on their sides
/// (constraints.fixed_on_sides). Requires uv fold-free and stats.blended_target set. Guarantees uv
/// stays fold-free. Reports refine_*, correction_rounds and the density error. Calls options.progress from 0.4 on.
void refine_towards_targets(const DensityConstraints& constraints, std::vector<Vec2>& uv, SquareMapStats& stats);

}  // namespace tightex
