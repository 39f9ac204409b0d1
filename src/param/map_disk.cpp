#include "param/map_disk.hpp"

#include <optional>

#include <tbb/task_group.h>

#include "core/error.hpp"
#include "param/density_map.hpp"
#include "param/density_reweighting.hpp"
#include "param/folds.hpp"
#include "param/harmonic.hpp"
#include "param/sparse_cholesky.hpp"

namespace tightex {

std::vector<Vec2> map_disk(const Disk& disk, const SquareMapOptions& options, SquareMapStats& st, SquareBoundary* placed) {
  st = SquareMapStats{};
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  if (bnd.size() < 3) fail_internal("map_to_square: boundary has {} vertices", bnd.size());
  const bool density = !options.face_target.empty();
  if (density && options.face_target.size() != m.num_faces())
    fail_internal("map_to_square: {} face targets for {} faces", options.face_target.size(), m.num_faces());

  // Alg. 1: the boundary onto the square's sides.
  const SquareBoundary boundary = map_boundary_to_square(disk, options);
  if (placed) *placed = boundary;
  for (int k = 0; k < 4; ++k) st.corners[k] = bnd[boundary.corner[k]];
  st.bumped_vertices = boundary.bumped_vertices;

  // Alg. 2: the harmonic map with the fold-free fallbacks.
  // One fill-reducing order for all of this map's systems (harmonic, reweighting, symmetric Dirichlet).
  const std::shared_ptr<const std::vector<int>> order = vertex_order_from(m, options.vertex_order_from);
  // The symmetric Dirichlet steps' system is built and analysed beside the harmonic map and the
  // reweighting, which do not need it: a core to spare while a disk's map is one solve after another.
  std::optional<DensityConstraints> constraints;
  tbb::task_group steps_ahead;
  if (density) constraints.emplace(density_constraints(disk, boundary, options, order));
  if (density && (options.refine_iterations > 0 || options.density_flow))
    steps_ahead.run([&] {
      constraints->refinement = prepare_refinement(m, constraints->fixed, options.face_target, options.supernodal_from, order.get());
    });
  DirichletSolver solver(options.supernodal_from, order);
  HarmonicAttempts harmonic = fold_free_harmonic_map(m, bnd, boundary.uv, solver);
  // No weighting solved (a factorisation failed, or its solution did not solve the system): the
  // interior still sits where the boundary left it. A failure, never a map.
  if (!harmonic.weights) fail_internal("the sparse solve of the harmonic map failed for every weighting ({} vertices)", m.num_vertices());
  std::vector<Vec2> uv = std::move(harmonic.uv);
  st.weights = to_string(*harmonic.weights);
  st.flipped = harmonic.flipped;
  st.negative_weights = harmonic.negative_weights;
  st.folds_per_attempt = harmonic.folds_per_attempt;
  st.crowded_vertex = harmonic.crowded_vertex;

  // The paper's map can crowd a region so far that its triangles keep a positive area only below what
  // the output's texture coordinates hold: they count as folds, and their region as crowded (the
  // caller slits to it). The density maps never get near: they spread this map out.
  if (!density && st.flipped == 0) {
    st.flipped = count_collapsed(m, uv, options, &st.crowded_vertex);
    if (st.flipped) st.folds_per_attempt.push_back(st.flipped);
  }

  // Beyond the paper: the texel density towards the face targets.
  if (density && st.flipped == 0 && (st.crowded_vertex == kNone || options.density_despite_crowding)) {
    std::vector<double> positive = harmonic.positive_weights;
    if (positive.empty()) positive = edge_weights(m, EdgeWeights::kClamped);
    reweight_towards_density(m, bnd, options, options.slide_boundary ? &boundary : nullptr, std::move(positive), solver, uv, st);
    steps_ahead.wait();
    flow_towards_targets(*constraints, uv, st);
    refine_towards_targets(*constraints, uv, st);
    st.blended_target.clear();
  }
  steps_ahead.wait();
  return uv;
}

}  // namespace tightex
