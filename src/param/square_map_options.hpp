// What the caller asks of the square map (paper §4.2 and the density maps beyond it) and what it
// reports back.
#pragma once
#include <algorithm>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/stage_stats.hpp"
#include "core/surface.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// From this many unknowns on, a map's linear systems are factorised supernodally (dense BLAS kernels
/// on column blocks); below it, simplicially, which is as fast there. Chosen by measurement:
/// docs/decisions.md.
constexpr long kSupernodalFrom = 40000;
/// From this many disk vertices on, a map orders its systems by one nested dissection of the disk
/// (nested_dissection_order) instead of CHOLMOD's minimum degree per system. Chosen by measurement:
/// BENCHMARKS.md, "Scale".
constexpr size_t kVertexOrderFrom = 200000;

struct SquareMapOptions {
  /// Size of the texel rectangle the square will be stretched to. Sizes the boundary bumps in texels;
  /// maps with a density target (face_target given) also take the rectangle's shape into account: the
  /// corners share the boundary out as the rectangle's perimeter (choose_corners' aspect), and the
  /// symmetric Dirichlet refinement measures each triangle in texels, so a triangle isometric to its
  /// target is isometric in the texture, not in the unit square. The paper's harmonic map keeps the
  /// quarters. The map itself is computed on the unit square.
  int rect_width = 1024, rect_height = 1024;
  double bump_texels = 0.3;  // < 0.5: a bump stays inside the chart's own outermost texels
  /// The largest texel coordinate the rectangle reaches in its texture (0: the rectangle's own size):
  /// what the written texture coordinates' rounding is relative to (see count_collapsed).
  double texel_extent = 0;
  CornerRule corners = CornerRule::kEqualArcs;

  /// Beyond the paper: the texel density. Empty: the paper's harmonic map. Otherwise a target UV area
  /// for every disk face (any common scale; > 0), e.g. its 3D area (uniform density) or the texels the
  /// input gave it. The harmonic map is then only the start: see map_to_square.
  std::vector<double> face_target;
  /// The trade-off between angle and area distortion: 0 keeps the harmonic map's density (least angle
  /// distortion), 1 aims at face_target exactly; in between, the target is the geometric blend
  /// harmonic^(1-balance) * target^balance per face.
  double balance = 1.0;
  int max_iterations = 60;
  double tolerance_log2 = 0.15;  // stop once P5..P95 of log2(area / target) lies within +-this
  /// Symmetric Dirichlet steps after the reweighting (refine_map); each costs one factorisation of
  /// twice the interior's size. Chosen by measurement: docs/decisions.md.
  int refine_iterations = 4;
  /// true: the refinement is undone if it widens the density error by more than 0.1 (log2) — a map
  /// whose promise is its density (area). false: it runs to convergence (up to refine_iterations),
  /// trading density for shear wherever that lowers the energy.
  bool refine_keeps_density = true;
  /// The boundary's vertices (all but the four corners and chord bumps) slide along their side of the
  /// square: between reweighting steps each boundary edge grows or shrinks with the square root of its
  /// face's target/area, and the refinement moves them along the side.
  bool slide_boundary = true;
  /// In the symmetric Dirichlet steps, a chord's bump and the chord's ends move inwards off their side
  /// where that lowers the energy (density_constraints), so the triangles beyond the chord are not left
  /// the bump's sliver. Not with density_flow (the flow slides the side vertices, which stay in order
  /// only on their sides), nor on multilevel_map's coarse copy (the full mesh's Tutte fill holds the
  /// coarse map's boundary, which must stay convex for it not to fold).
  bool chords_move_inwards = true;
  /// Rounds of target correction after the refinement (each: the targets scaled by target/area, 2 more
  /// steps). Off by default: chosen by measurement, docs/decisions.md.
  int correction_rounds = 0;
  /// After the reweighting, where it stalled short of tolerance_log2: the density-equalising flow
  /// (flow_towards_targets), kept if it narrows the density error. The area map's (set_face_targets).
  bool density_flow = false;
  /// Linear systems of this many unknowns or more are factorised supernodally, smaller ones
  /// simplicially (see kSupernodalFrom). Tests set it low to run the supernodal path on small meshes.
  long supernodal_from = kSupernodalFrom;
  /// A disk of this many vertices or more orders its systems by its nested dissection (kVertexOrderFrom).
  size_t vertex_order_from = kVertexOrderFrom;
  /// A disk of more than this many vertices with a density target (and balance 1) is mapped multilevel
  /// (multilevel_map): the reweighting, flow and refinement on a copy of at most coarse_vertices
  /// vertices, carried to the full mesh, then up to fine_reweighting reweighting steps and fine_steps
  /// symmetric Dirichlet steps there. Chosen by measurement: BENCHMARKS.md, "Scale".
  size_t multilevel_from = 100000;
  size_t coarse_vertices = 30000;
  int fine_reweighting = 4, fine_steps = 2;
  /// A multilevel disk of this many vertices or more solves its full mesh's symmetric Dirichlet steps
  /// by conjugate gradients preconditioned over the coarsening's aggregates (MultilevelSolver) instead
  /// of factorising them: memory linear in the mesh. Chosen by measurement: BENCHMARKS.md, "Scale".
  size_t iterative_from = 200000;
  /// With iterative_from: the full mesh's Laplacians (the fill and the reweighting) too. Off: they must
  /// be solved to a relative residual of 1e-12 (a Tutte map must not fold where the map is crowded),
  /// which the preconditioner reaches 10 to 30 times slower than CHOLMOD's factorisation and solve
  /// (BENCHMARKS.md, "Scale").
  bool iterative_laplacians = false;
  /// The density steps start from whichever weighting gave a fold-free harmonic map, even where the
  /// clamped cotangent weights crowded a region (which otherwise stops the map there, for the caller
  /// to slit): multilevel_map's coarse copy, whose crowding is no reason to re-cut the full mesh.
  bool density_despite_crowding = false;
  /// Optional: called from the mapping thread with an estimate of the fraction of this map done (the
  /// density reweighting up to 0.4, the symmetric Dirichlet steps from there; each step counts as if
  /// the reweighting took 20 and the steps 15, so the estimate may jump to 1 at the end).
  std::function<void(double)> progress;
};

/// The width/height of the texel rectangle the map is computed for (texel spacing the same both ways):
/// the options' rectangle for a map with a density target, 1 (the square) for the paper's map.
inline double map_aspect(const SquareMapOptions& options) {
  return options.face_target.empty() ? 1.0 : double(std::max(1, options.rect_width)) / double(std::max(1, options.rect_height));
}

}  // namespace tightex
