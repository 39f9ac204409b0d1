#include "param/multilevel.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/task_group.h>

#include "core/resources.hpp"
#include "param/boundary.hpp"
#include "param/coarsen.hpp"
#include "param/density_map.hpp"
#include "param/density_reweighting.hpp"
#include "param/folds.hpp"
#include "param/harmonic.hpp"
#include "param/map_disk.hpp"
#include "param/slim.hpp"
#include "param/sparse_cholesky.hpp"

namespace tightex {

namespace {

/// Per vertex of the full mesh, whether it is one of the coarse copy's.
std::vector<char> coarse_vertices(const Surface& m, const CoarseDisk& coarse) {
  std::vector<char> held(m.num_vertices(), 0);
  for (uint32_t v : coarse.fine_vertex) held[v] = 1;
  return held;
}

/// The harmonic map between the coarse vertices (held where coarse_uv puts them): a target close to the
/// coarse map, with its own detail between the coarse vertices, but which may fold where the held
/// vertices enclose a concave patch.
std::vector<Vec2> harmonic_between(const Disk& disk, const CoarseDisk& coarse, const std::vector<Vec2>& coarse_uv,
                                   DirichletSolver& solver) {
  const Surface& m = disk.mesh;
  std::vector<Vec2> uv(m.num_vertices(), Vec2::Zero());
  for (size_t c = 0; c < coarse.fine_vertex.size(); ++c) uv[coarse.fine_vertex[c]] = coarse_uv[c];
  if (!solver.solve(m, edge_weights(m, EdgeWeights::kClamped), coarse_vertices(m, coarse), uv)) return {};
  return uv;
}

/// Per edge (at its lower halfedge, as edge_weights gives them) the cotangent weight of the target map's
/// own triangles, at least `floor` times their mean magnitude (which `mean` gets): a planar triangulation
/// is harmonic for its own cotangent weights, so the Tutte map with these reproduces the target wherever
/// its triangles are unfolded and not obtuse. A folded target triangle adds nothing.
std::vector<double> target_cotangent_weights(const Surface& m, const std::vector<Vec2>& target, double floor, double& mean) {
  const size_t nh = m.opposite.size();
  std::vector<double> half_cot(nh, 0.0);
  for (uint32_t h = 0; h < nh; ++h) {
    const Vec2 &a = target[m.from(h)], &b = target[m.to(h)], &c = target[m.triangles[h / 3][(h % 3 + 2) % 3]];
    const Vec2 u = a - c, v = b - c;
    const double cross = u.x() * v.y() - u.y() * v.x();
    half_cot[h] = cross > 0 ? 0.5 * u.dot(v) / cross : 0.0;
  }
  std::vector<double> w(nh, 0.0);
  double mean_abs = 0;
  size_t count = 0;
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t o = m.opposite[h];
    if (o != kNone && o < h) continue;
    w[h] = half_cot[h] + (o == kNone ? 0.0 : half_cot[o]);
    if (!std::isfinite(w[h])) w[h] = 0;
    mean_abs += std::abs(w[h]), ++count;
  }
  mean_abs = count && mean_abs > 0 ? mean_abs / double(count) : 1.0;
  for (uint32_t h = 0; h < nh; ++h) w[h] = std::max(w[h], floor * mean_abs);
  mean = mean_abs;
  return w;
}

/// The full mesh's Laplacians: the one with the coarse vertices held (the harmonic fill), built and
/// analysed ahead (prepare_fills), and the one with the boundary held (the Tutte fill and the
/// reweighting), built and analysed at its first solve, once the harmonic fill's is freed: the
/// factor of the one beside the other's pattern and analysis was the map's peak.
struct FineSystems {
  std::unique_ptr<DirichletSolver> between, tutte;
};

/// How the Tutte fill's weights are floored (times their mean magnitude), tried in turn while its map
/// folds: everywhere, and where the try before folded, within kFloorRings vertex rings of its folded
/// triangles. The target's cotangent weights around slivers and obtuse triangles spread over six orders
/// of magnitude, and at 1.7M vertices such a fill can crush a triangle to zero area in rounding (the
/// 3.4M-face scan read from float32 GLB: 3 triangles at 1e-22 of the square with the floor at 1e-3,
/// still folded at 1e-2). A higher floor crowds less, but everywhere it moves the map off the target:
/// 1e-1 everywhere took the 3.4M scan's steps 20 s instead of 7 s and 0.39 dB (the OBJ scan), hence the
/// local floor first.
struct FillFloor {
  double everywhere, near_folds;
};
constexpr FillFloor kFillFloors[] = {{1e-3, 1e-3}, {1e-3, 1e-1}, {1e-2, 1e-1}, {1e-1, 1e-1}};
constexpr int kFloorRings = 8;

/// Per vertex, 1 within `rings` vertex rings of a triangle that folds in `uv`, added to `near`.
void mark_near_folds(const Surface& m, const std::vector<Vec2>& uv, int rings, std::vector<char>& near) {
  std::vector<char> now(m.num_vertices(), 0);
  for (const Tri& t : m.triangles)
    if (!(signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0)) now[t[0]] = now[t[1]] = now[t[2]] = 1;
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> next = now;
    for (const Tri& t : m.triangles)
      if (now[t[0]] || now[t[1]] || now[t[2]]) next[t[0]] = next[t[1]] = next[t[2]] = 1;
    now.swap(next);
  }
  for (size_t v = 0; v < near.size(); ++v) near[v] = near[v] || now[v];
}

/// Step 2 of multilevel_map: the Tutte map (only the boundary held) with the weights of the harmonic
/// target between the coarse vertices (target_cotangent_weights, floored by the first of kFillFloors
/// whose map folds nothing), which `weights` gets. The harmonic target's solver is freed once it is
/// solved. Empty if a solve fails or the map folds numerically with every floor.
std::vector<Vec2> fill_between(const Disk& disk, const CoarseDisk& coarse, const std::vector<Vec2>& coarse_uv, FineSystems& systems,
                               std::vector<double>& weights) {
  const Surface& m = disk.mesh;
  const std::vector<Vec2> target = harmonic_between(disk, coarse, coarse_uv, *systems.between);
  systems.between.reset();
  release_free_memory();  // for the Tutte fill's system, made next
  if (target.empty()) return {};
  const std::vector<char> held = boundary_mask(m.num_vertices(), disk.boundary);
  std::vector<char> near(m.num_vertices(), 0);  // near a fold of an earlier try
  for (const FillFloor& floor : kFillFloors) {
    double mean = 0;
    weights = target_cotangent_weights(m, target, floor.everywhere, mean);
    for (uint32_t h = 0; h < weights.size(); ++h)
      if (near[m.from(h)] || near[m.to(h)]) weights[h] = std::max(weights[h], floor.near_folds * mean);
    std::vector<Vec2> uv = target;
    if (!systems.tutte->solve(m, weights, held, uv)) return {};
    if (count_folds(m, uv) == 0) return uv;
    mark_near_folds(m, uv, kFloorRings, near);
  }
  return {};
}

/// The relative residual the full mesh's Laplacians are solved to where they are solved iteratively
/// (options.iterative_laplacians): at 1e-10 the Tutte fill of esp32cam subdivided twice folded a
/// triangle, at 1e-12 none.
constexpr double kFillTolerance = 1e-12;

/// The aggregates' coarsest level has about this many vertices (the collapses may stop short of it).
constexpr size_t kCoarsestAggregate = 3000;

/// The sizes the collapses record the full mesh's aggregates at (multigrid.hpp): a quarter of the
/// vertices each, down to kCoarsestAggregate; at least two levels (a small disk's, in the tests).
std::vector<size_t> aggregate_sizes(const Disk& disk) {
  std::vector<size_t> sizes;
  for (size_t size = disk.mesh.num_vertices() / 4; size > 0 && (size >= kCoarsestAggregate || sizes.size() < 2); size /= 4)
    sizes.push_back(size);
  return sizes;
}

/// Coarse copies tried, each twice the vertices of the one before, while it stays within
/// multilevel_from and at most a quarter of the disk.
constexpr int kCoarseTries = 3;

/// The sizes of the coarse copies to try, largest first (coarsen_disk_in_steps' order).
std::vector<size_t> coarse_sizes(const Disk& disk, const SquareMapOptions& options) {
  std::vector<size_t> sizes{options.coarse_vertices};
  while (sizes.size() < size_t(kCoarseTries) && 2 * sizes.back() <= options.multilevel_from && 8 * sizes.back() <= disk.mesh.num_vertices())
    sizes.push_back(2 * sizes.back());
  std::reverse(sizes.begin(), sizes.end());
  return sizes;
}

/// Step 1 of multilevel_map: the first of the coarse copies (coarsen_disk_in_steps', tried smallest
/// first) whose map folds nothing, and that map (the boundary as `placed`), with stats in `st`. A copy
/// whose map folds (decimation can leave a narrow neck, which even the uniform harmonic map crowds below
/// floating-point precision: esp32cam subdivided three times, at 30k of 1.7M vertices) is replaced by
/// a finer one. nullopt where no copy maps fold-free or the disk cannot be coarsened enough.
std::optional<std::pair<CoarseDisk, std::vector<Vec2>>> coarse_map(std::vector<CoarseDisk>& copies, const SquareMapOptions& options,
                                                                   SquareMapStats& st, SquareBoundary& placed) {
  for (auto coarse = copies.rbegin(); coarse != copies.rend(); ++coarse) {
    if (coarse->fine_vertex.size() > options.multilevel_from) return std::nullopt;  // it could not be coarsened enough
    st = SquareMapStats{};
    std::vector<Vec2> uv = map_disk(coarse->disk, coarse_options(options, *coarse), st, &placed);
    if (st.flipped == 0) return std::pair{std::move(*coarse), std::move(uv)};
  }
  return std::nullopt;
}

/// The full mesh's Laplacians: `held` (the vertices of the coarse copy coarse_map tries first) held for
/// the harmonic fill, prepared; the Tutte fill's made, to be prepared at its first solve (FineSystems).
/// Where coarse_map settles on another copy, the harmonic fill makes its own.
FineSystems prepare_fills(const Disk& disk, const std::vector<char>& held, const SquareMapOptions& options,
                          const std::shared_ptr<const std::vector<int>>& order, const std::shared_ptr<const VertexAggregates>& aggregates) {
  const Surface& m = disk.mesh;
  FineSystems systems{std::make_unique<DirichletSolver>(options.supernodal_from, order),
                      std::make_unique<DirichletSolver>(options.supernodal_from, order)};
  if (aggregates && options.iterative_laplacians) {
    systems.between->solve_iteratively(aggregates, kFillTolerance);
    systems.tutte->solve_iteratively(aggregates, kFillTolerance);
  }
  systems.between->prepare(m, held);
  return systems;
}

/// Steps 2 and 3 but the symmetric Dirichlet steps: the coarse map carried to the full mesh, then the
/// reweighting there. Empty where the fill fails.
std::vector<Vec2> fill_and_reweight(const Disk& disk, const CoarseDisk& coarse, const std::vector<Vec2>& coarse_uv,
                                    const SquareMapOptions& fine_options, FineSystems& systems, SquareMapStats& fine) {
  std::vector<double> weights;
  std::vector<Vec2> uv = fill_between(disk, coarse, coarse_uv, systems, weights);
  if (uv.empty()) return uv;
  // The density on the full mesh (the coarse map's holds only on average over each coarse triangle).
  reweight_towards_density(disk.mesh, disk.boundary, fine_options, nullptr, std::move(weights), *systems.tutte, uv, fine);
  return uv;
}

}  // namespace

SquareMapOptions coarse_options(const SquareMapOptions& options, const CoarseDisk& coarse) {
  SquareMapOptions o = options;
  o.face_target = coarse.face_target;
  o.density_despite_crowding = true;
  o.chords_move_inwards = false;
  return o;
}

std::optional<std::vector<Vec2>> multilevel_map(const Disk& disk, const SquareMapOptions& options, SquareMapStats& stats) {
  const Surface& m = disk.mesh;
  if (options.face_target.empty() || options.balance != 1.0 || m.num_vertices() <= options.multilevel_from) return std::nullopt;
  SquareMapStats st;
  SquareBoundary placed;
  // Two chains side by side, each on one thread: the coarse copies, then the coarse map; the
  // fill-reducing order of every system on the full mesh (METIS), then the harmonic fill's Laplacian
  // built and analysed for the copy coarse_map tries first (its vertices taken before the map may move
  // it). The chains take about as long as each other, where waiting for both the copies and the order
  // before either went on left a core idle while the coarse map ran.
  // The iterative solves' aggregates (multigrid.hpp) are recorded by the coarsening's collapses.
  const bool iterative = m.num_vertices() >= options.iterative_from;
  std::shared_ptr<const std::vector<int>> order;
  tbb::task_group ordering;
  ordering.run([&] { order = vertex_order_from(m, options.vertex_order_from); });
  std::shared_ptr<VertexAggregates> aggregates = iterative ? std::make_shared<VertexAggregates>() : nullptr;
  std::vector<CoarseDisk> copies =
      coarsen_disk_in_steps(disk, options.face_target, coarse_sizes(disk, options), aggregate_sizes(disk), aggregates.get());
  if (copies.empty() || copies.back().fine_vertex.size() > options.multilevel_from) {
    ordering.wait();
    return std::nullopt;
  }
  const std::vector<char> first_held = coarse_vertices(m, copies.back());
  FineSystems systems;
  tbb::task_group fills;
  fills.run([&] {
    ordering.wait();
    // What METIS freed stays in its thread's malloc arena, out of reach of the fine stage's
    // factorisations, which would take fresh memory beside it and raise the peak.
    release_free_memory();
    systems = prepare_fills(disk, first_held, options, order, aggregates);
  });
  std::optional<std::pair<CoarseDisk, std::vector<Vec2>>> coarse_and_map = coarse_map(copies, options, st, placed);
  fills.wait();
  copies.clear();
  if (!coarse_and_map) return std::nullopt;
  const CoarseDisk& coarse = coarse_and_map->first;
  const std::vector<Vec2>& coarse_uv = coarse_and_map->second;
  st.crowded_vertex = kNone;
  for (uint32_t& corner : st.corners) corner = coarse.fine_vertex[corner];
  st.coarse_vertices = coarse.fine_vertex.size();
  SquareMapOptions fine_options = options;
  fine_options.max_iterations = options.fine_reweighting;
  fine_options.refine_iterations = options.fine_steps;
  fine_options.correction_rounds = 0;
  fine_options.progress = nullptr;
  // The symmetric Dirichlet steps' constraints are the coarse boundary's (its vertices are the fine
  // boundary's, in the same order). Their system is made beside the fill and the reweighting where
  // it is factorised (its analysis takes seconds); an iterative one after them, once the Laplacian's
  // factor is freed: the two at once were the peak of the run (3.4M faces).
  const DensityConstraints constraints = density_constraints(disk, placed, fine_options, order);
  const auto prepare_steps = [&] {
    constraints.refinement =
        prepare_refinement(m, constraints.fixed, options.face_target, options.supernodal_from, order.get(), aggregates.get());
  };
  SquareMapStats fine;
  tbb::task_group steps_ahead;
  if (!aggregates) steps_ahead.run(prepare_steps);
  std::vector<Vec2> uv = fill_and_reweight(disk, coarse, coarse_uv, fine_options, systems, fine);
  steps_ahead.wait();
  if (uv.empty()) return std::nullopt;
  // The Laplacian's factor is freed before the symmetric Dirichlet steps factorise a system of twice
  // the unknowns, and handed back to the system: the steps' system, built already, would not reuse it.
  systems.tutte.reset();
  release_free_memory();
  if (aggregates) prepare_steps();
  refine_towards_targets(constraints, uv, fine);
  st.fine_reweighting = fine.iterations;
  st.fine_steps = fine.refine_iterations;
  st.spread_p5 = fine.spread_p5, st.spread_p95 = fine.spread_p95;
  stats = st;
  return uv;
}

}  // namespace tightex
