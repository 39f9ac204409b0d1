// What each stage reports of its work (the report shows them), and the rectangle of texels a chart
// gets: plain records that the stages fill and src/report writes, kept here so that the report depends
// on no stage's interface.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/surface.hpp"

namespace tightex {

struct RepairStats {
  size_t input_vertices = 0;
  size_t welded_vertices = 0;       // vertices after welding equal positions
  size_t zero_area_triangles = 0;   // dropped: repeated vertex or exactly zero 3D area
  size_t repeated_triangles = 0;    // set aside: an exact repeat of an earlier triangle (the output repeats its copy)
  size_t layered_triangles = 0;     // the corners of an earlier triangle with other texture coordinates or material: a surface of their own
  size_t reoriented_triangles = 0;  // wound against the rest of their patch: corners 1 and 2 swapped
  size_t non_manifold_edges = 0;    // edges used by more than two triangles, sliced apart
  size_t inconsistent_edges = 0;    // edges whose two triangles disagree on orientation, sliced apart
  size_t sliced_vertices = 0;       // welded vertices that became more than one vertex
  size_t slits_closed = 0;          // sliced edges glued back within one sheet (see prepare_surface)
};

/// What cut_to_disk did to a component (the report shows it).
struct CutStats {
  Topology before;  // of the component as given (holes not yet filled)
  size_t holes_filled = 0;
  size_t holes_cut = 0;              // joined into the disk boundary
  double fill_budget = 0;            // the cap budget it was cut with (fraction of the component's area)
  double filled_area = 0;            // the caps' area (fraction of the component's area)
  size_t cut_edges = 0;              // interior edges cut open
  double cut_length = 0;             // their 3D length
  double seam_length = 0;            // 3D length of the seam the output gets here (handle loops, holes joined, cut, slits)
  double seam_on_input_seams = 0;    // the part of it on the input's texture seams
  std::string method;                // CutGraph::method, with "+slit" when deep parts were slit (see cut_to_disk)
  size_t slits = 0;                  // slits from the boundary to deep vertices
  std::string fallback_reason;       // non-empty: the full method failed here and the plain cut was used
  std::vector<double> handle_loops;  // 3D length of each handle loop cut (see remove_handles)
  size_t longest_loop_edges = 0;     // edges of the longest boundary loop (handles removed, before any cap; 0: closed)
  bool longest_loop_capped = false;  // cap_longest_loop asked for it and the longest loop was capped too
  // Set by the pipeline where a small longest hole was tried both ways (kept as the boundary, then
  // capped too): each map's estimated colour error (resampling_mse); empty where not tried.
  std::vector<double> compared_mse;
};

struct SquareMapStats {
  std::string weights;                    // "cotangent", "clamped-cotangent" or "uniform": the first that gave no fold
  size_t flipped = 0;                     // triangles with UV area <= 0 in the returned map (0 unless every weight failed)
  size_t negative_weights = 0;            // interior edges whose cotangent weight was negative
  std::array<uint32_t, 4> corners{};      // boundary vertices at (0,0), (1,0), (1,1), (0,1)
  std::vector<size_t> folds_per_attempt;  // folded triangles of each weighting tried, in order
  size_t bumped_vertices = 0;
  /// A vertex of a triangle that folded even with positive weights: the map crowded a region below
  /// floating-point precision there (harmonic maps crowd exponentially in protrusions). kNone if none.
  uint32_t crowded_vertex = kNone;
  // Density iterations (face_target given): P5/P95 of log2(area / target), weighted by target, before
  // (the harmonic map with the density-placed boundary) and after.
  int iterations = 0;
  double spread_before_p5 = 0, spread_before_p95 = 0, spread_p5 = 0, spread_p95 = 0;
  std::string stopped;                 // "converged", "iterations", "stalled" or "fold" (the last fold-free iterate is kept)
  std::vector<double> blended_target;  // internal: the targets the iterations aimed at (cleared on return)
  int refine_iterations = 0, correction_rounds = 0;
  double refine_energy_before = 0, refine_energy = 0;
  std::string refine_stopped;
  int flow_steps = 0;
  int flow_lead_steps = 0;   // symmetric Dirichlet steps before the flow (fewer than asked if they converged)
  int flow_shape_steps = 0;  // symmetric Dirichlet steps towards the flowed shapes (0: each flowed map was kept as it was)
  std::string flow_stopped;  // FlowStats::stopped, ", reverted" added if it was undone; empty if not run
  /// Multilevel maps: the coarse copy's vertices (0: mapped at full resolution) and the reweighting and
  /// symmetric Dirichlet steps on the full mesh (iterations and refine_iterations count the coarse copy's).
  size_t coarse_vertices = 0;
  int fine_reweighting = 0, fine_steps = 0;
  /// The output's float texture coordinates (keep_orientation_in_float): vertices moved a few float
  /// steps so that a sliver keeps its orientation, and triangles no such move fixed.
  size_t float_moved = 0, float_unfixed = 0;
};

struct BakeStats {
  size_t texels_filled = 0;              // texel centres inside some triangle
  size_t texels_dilated = 0;             // texels of a rectangle that no triangle covers (scaffolding, rounding)
  size_t texels_footprint_filtered = 0;  // texels averaged over more than one sample (minified input)
  size_t tiles_fitted = 0, tiles = 0;    // least-squares fit
};

/// A rectangle of texels: columns [x, x+w), rows [y, y+h) (row 0 at the top of the image).
struct Rect {
  int image = 0;
  int x = 0, y = 0, w = 0, h = 0;
};

}  // namespace tightex
