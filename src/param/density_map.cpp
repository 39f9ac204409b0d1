#include "param/density_map.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "core/statistics.hpp"
#include "param/density_flow.hpp"
#include "param/folds.hpp"
#include "param/slim.hpp"

namespace tightex {

namespace {

/// No flow on a fragment of fewer faces: the grid's noise moves those by more than it evens them out.
constexpr size_t kFlowMinFaces = 100;
/// The real faces must cover at least this share of the square after a refinement whose chords' ends
/// moved inwards, or it is made again with them on their sides: the layout promises an output 99%
/// used, which the hole caps already share.
constexpr double kMinRealShare = 0.99;
/// Symmetric Dirichlet steps towards the flowed faces' shapes where the flowed map itself folds or
/// collapses. Chosen by measurement: docs/decisions.md.
constexpr int kFlowShapeSteps = 30;
/// The flow rounds start from a density diffused over these many cells: a coarse start folds fewer
/// faces and leaves the finer rounds less to move. Chosen by measurement: docs/decisions.md.
constexpr double kFlowStarts[] = {4, 2, 1};
/// Symmetric Dirichlet steps towards the targets' shapes before the flow: they take the shear out of
/// the reweighted map, which the flow then keeps far better. Chosen by measurement: docs/decisions.md.
constexpr int kFlowLeadSteps = 10;
/// The flow rounds stop once the density error is within +-this (log2): each round costs a map's
/// worth of symmetric Dirichlet steps where faces fold. Chosen by measurement: docs/decisions.md.
constexpr double kFlowEnough = 0.4;
/// The refinement trades a little density for much less shear; it is kept unless it widens the
/// density error by more than this (log2).
constexpr double kRefineSlack = 0.1;

/// The density error's worst side, max(-P5, P95) of log2(area / target).
double worst_error(double p5, double p95) { return std::max(-p5, p95); }

/// refine_map in the rectangle's proportions (area 1: the targets are normalised to the unit square),
/// so the targets' shapes are met in texels. `shapes` (unit square, optional): refine_map's.
SlimStats refine_in_rectangle(const DensityConstraints& c, const std::vector<double>& target, int iterations,
                              const std::function<void(int)>& on_step, std::vector<Vec2>& uv,
                              const std::vector<FaceShape>* shapes = nullptr) {
  if (c.aspect == 1.0)
    return refine_map(c.mesh, c.fixed, target, iterations, uv, c.options.supernodal_from, on_step, shapes, c.vertex_order.get(),
                      &c.refinement, &c.bounds);
  const double sx = std::sqrt(c.aspect);
  const std::vector<Vec2> before = uv;
  for (Vec2& p : uv) p = Vec2(p.x() * sx, p.y() / sx);
  std::vector<FaceShape> scaled_shapes;
  if (shapes) {
    scaled_shapes = *shapes;
    for (FaceShape& s : scaled_shapes)
      for (Vec2& p : s) p = Vec2(p.x() * sx, p.y() / sx);
  }
  std::vector<CoordinateBound> scaled_bounds = c.bounds;
  for (CoordinateBound& b : scaled_bounds) b.bound *= b.axis == 0 ? sx : 1 / sx;
  const SlimStats r = refine_map(c.mesh, c.fixed, target, iterations, uv, c.options.supernodal_from, on_step,
                                 shapes ? &scaled_shapes : nullptr, c.vertex_order.get(), &c.refinement, &scaled_bounds);
  for (Vec2& p : uv) p = Vec2(p.x() / sx, p.y() * sx);
  // Held coordinates come back exactly (x * sx / sx may miss 1 by an ulp: a side's texel centres
  // would fall outside the chart), bounded ones within their line.
  for (size_t v = 0; v < uv.size(); ++v)
    for (int a = 0; a < 2; ++a)
      if (c.fixed[v] & (1 << a)) uv[v](a) = before[v](a);
  for (const CoordinateBound& b : c.bounds)
    if (b.sign * (uv[b.vertex](b.axis) - b.bound) > 0) uv[b.vertex](b.axis) = b.bound;
  return r;
}

/// The density error of uv against st.blended_target (scaled to the map's area) into st.spread_p5 and
/// st.spread_p95; returns each face's log2(area / target).
std::vector<double> measure_density_error(const Surface& m, const std::vector<Vec2>& uv, SquareMapStats& st) {
  const size_t nf = m.num_faces();
  std::vector<double> log_ratio(nf);
  std::vector<std::pair<double, double>> vw(nf);
  double total = 0, sum_t = 0;
  for (size_t f = 0; f < nf; ++f) {
    log_ratio[f] = signed_area(uv[m.triangles[f][0]], uv[m.triangles[f][1]], uv[m.triangles[f][2]]);  // the area, for now
    total += log_ratio[f], sum_t += st.blended_target[f];
  }
  for (size_t f = 0; f < nf; ++f) {
    log_ratio[f] = std::log2(std::max(log_ratio[f], 1e-300) / (st.blended_target[f] * total / sum_t));
    vw[f] = {log_ratio[f], st.blended_target[f]};
  }
  st.spread_p5 = weighted_quantile(vw, 0.05);
  st.spread_p95 = weighted_quantile(vw, 0.95);
  return log_ratio;
}

/// Tracers for the flow: a small copy of each face about its centroid, at most a quarter cell across,
/// which the flow carries as its own local map (its Jacobian there) carries the face. tracer_scale[f]:
/// the copy's scale.
std::vector<Vec2> face_tracers(const Surface& m, const std::vector<Vec2>& uv, double cell, std::vector<double>& tracer_scale) {
  const size_t nf = m.num_faces();
  std::vector<Vec2> tracers(3 * nf);
  tracer_scale.assign(nf, 0.0);
  for (size_t f = 0; f < nf; ++f) {
    const Tri& t = m.triangles[f];
    const Vec2 centroid = (uv[t[0]] + uv[t[1]] + uv[t[2]]) / 3.0;
    const double longest = std::max({(uv[t[1]] - uv[t[0]]).norm(), (uv[t[2]] - uv[t[1]]).norm(), (uv[t[0]] - uv[t[2]]).norm()});
    tracer_scale[f] = longest > 0.25 * cell ? 0.25 * cell / longest : 1.0;
    for (size_t k = 0; k < 3; ++k) tracers[3 * f + k] = centroid + tracer_scale[f] * (uv[t[k]] - centroid);
  }
  return tracers;
}

/// One flow round from a density diffused over `start_cells` cells. The flow carries vertices, not
/// triangles: a face spanning many cells of a field that bends across it can fold. Where any face of
/// the flowed map folds or collapses, kFlowShapeSteps symmetric Dirichlet steps aim from the map
/// before at the shapes the flow gives each face instead: the tracers' (the flow's own local map at
/// the face, which never folds, where the flowed vertices of a long face can). Kept only if it narrows
/// the density error.
void flow_round(const DensityConstraints& c, double start_cells, std::vector<Vec2>& uv, SquareMapStats& st) {
  const Surface& m = c.mesh;
  const size_t nf = m.num_faces();
  const std::vector<Vec2> previous = uv;
  const double previous_p5 = st.spread_p5, previous_p95 = st.spread_p95;
  std::vector<Vec2> flowed = uv;
  FlowOptions fo;
  fo.fold_free = false;
  fo.start_cells = start_cells;
  std::vector<double> tracer_scale;
  std::vector<Vec2> tracers = face_tracers(m, uv, 1.0 / flow_grid(nf, fo), tracer_scale);
  const FlowStats fs = flow_density(m, c.flow_fixed, st.blended_target, c.aspect, flowed, fo, &tracers);
  st.flow_steps += fs.steps;
  st.flow_stopped = fs.stopped;
  const size_t collapsed = count_collapsed(m, flowed, c.options);
  if (collapsed == 0) {
    uv = flowed;
  } else {
    std::vector<FaceShape> shapes(nf);
    for (size_t f = 0; f < nf; ++f)
      for (size_t k = 0; k < 3; ++k) shapes[f][k] = tracers[3 * f + k] / tracer_scale[f];
    const SlimStats shaped = refine_in_rectangle(c, st.blended_target, kFlowShapeSteps, {}, uv, &shapes);
    st.flow_shape_steps += shaped.iterations;
  }
  measure_density_error(m, uv, st);
  if (!(worst_error(st.spread_p5, st.spread_p95) < worst_error(previous_p5, previous_p95))) {
    uv = previous;
    st.spread_p5 = previous_p5, st.spread_p95 = previous_p95;
  }
}

/// Rounds of target correction: the symmetric Dirichlet energy balances area against angle; where the
/// area still misses its target, the target shape itself is corrected (grown where the face came out
/// small) and the energy lowered again, so the density converges at the cost of a little more shear.
/// `log_ratio`: the density error of uv per face (measure_density_error).
void correct_targets(const DensityConstraints& c, std::vector<double> log_ratio, std::vector<Vec2>& uv, SquareMapStats& st) {
  const size_t nf = c.mesh.num_faces();
  std::vector<double> corrected = st.blended_target;
  for (int round = 0; round < c.options.correction_rounds; ++round) {
    if (worst_error(st.spread_p5, st.spread_p95) <= c.options.tolerance_log2) break;
    for (size_t f = 0; f < nf; ++f) corrected[f] *= std::exp2(-std::clamp(log_ratio[f], -4.0, 4.0));
    const std::vector<Vec2> previous = uv;
    const double previous_p5 = st.spread_p5, previous_p95 = st.spread_p95;
    const SlimStats cs = refine_in_rectangle(c, corrected, 2, {}, uv);
    st.refine_iterations += cs.iterations;
    ++st.correction_rounds;
    log_ratio = measure_density_error(c.mesh, uv, st);
    if (worst_error(st.spread_p5, st.spread_p95) > worst_error(previous_p5, previous_p95) + kRefineSlack) {  // worse: undo, stop
      uv = previous;
      st.spread_p5 = previous_p5, st.spread_p95 = previous_p95;
      break;
    }
  }
}

/// Per boundary position, whether it is the end of a bump's chords: a side neighbour of a bumped
/// (pinned, not corner) position, neither pinned nor a corner itself.
template <class IsCorner>
std::vector<char> chord_ends(const SquareBoundary& b, IsCorner&& is_corner) {
  const size_t nb = b.pinned.size();
  std::vector<char> end(nb, 0);
  for (size_t i = 0; i < nb; ++i)
    if (b.pinned[i] && !is_corner(i))
      for (size_t j : {(i + 1) % nb, (i + nb - 1) % nb})
        if (!b.pinned[j]) end[j] = 1;
  return end;
}

}  // namespace

DensityConstraints density_constraints(const Disk& disk, const SquareBoundary& boundary, const SquareMapOptions& options,
                                       std::shared_ptr<const std::vector<int>> vertex_order) {
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  const auto& corner = boundary.corner;
  auto is_corner = [&](size_t i) { return std::find(corner.begin(), corner.end(), i) != corner.end(); };
  const std::vector<char> chord_end = chord_ends(boundary, is_corner);
  auto inwards = [&](size_t i) { return chord_end[i] || (boundary.pinned[i] && !is_corner(i)); };
  // A boundary vertex that `holds(i)` stays (3), every other slides along its side (2: a horizontal
  // side holds v, 1: a vertical one holds u); all stay when the boundary does not slide.
  auto side_constraints = [&](auto&& holds) {
    std::vector<char> fixed(disk.mesh.num_vertices(), 0);
    for (size_t i = 0; i < nb; ++i) fixed[bnd[i]] = holds(i) || !options.slide_boundary ? 3 : (boundary.side_of[i] % 2 == 0 ? 2 : 1);
    return fixed;
  };
  const std::vector<char> on_sides = side_constraints([&](size_t i) { return boundary.pinned[i] || chord_end[i]; });
  DensityConstraints c{disk.mesh, options,  map_aspect(options),         on_sides,
                       {},        on_sides, side_constraints(is_corner), std::move(vertex_order)};
  // The flow slides every side vertex with its field, which keeps them in order only while they all
  // lie on their sides: a map that may flow keeps its chords there.
  if (!options.chords_move_inwards || options.density_flow || !options.slide_boundary ||
      std::find(chord_end.begin(), chord_end.end(), 1) == chord_end.end())
    return c;
  // The bumps and the chords' ends keep their place along the side (the coordinate the side does not
  // hold) and move inwards only, across the side: a chord's end from the side, a bumped vertex from its
  // bump. The vertices next to the chords' ends stay instead.
  c.fixed = side_constraints(
      [&](size_t i) { return is_corner(i) || (!inwards(i) && (chord_end[(i + 1) % nb] || chord_end[(i + nb - 1) % nb])); });
  for (size_t i = 0; i < nb; ++i) {
    if (!inwards(i)) continue;
    const int side = boundary.side_of[i], across = side % 2 == 0 ? 1 : 0, sign = side == 0 || side == 3 ? -1 : 1;
    c.fixed[bnd[i]] = char(1 << (1 - across));
    c.bounds.push_back({bnd[i], across, boundary.uv[i](across), sign});
  }
  return c;
}

void measure_density_spread(const Surface& mesh, const std::vector<Vec2>& uv, SquareMapStats& stats) {
  measure_density_error(mesh, uv, stats);
}

void flow_towards_targets(const DensityConstraints& c, std::vector<Vec2>& uv, SquareMapStats& st) {
  if (!c.options.density_flow || c.mesh.num_faces() < kFlowMinFaces ||
      !(worst_error(st.spread_p5, st.spread_p95) > c.options.tolerance_log2))
    return;
  const double reweighted_p5 = st.spread_p5, reweighted_p95 = st.spread_p95;
  const std::vector<Vec2> reweighted = uv;
  st.flow_lead_steps = refine_in_rectangle(c, st.blended_target, kFlowLeadSteps, {}, uv).iterations;
  measure_density_error(c.mesh, uv, st);
  for (double start_cells : kFlowStarts) {
    flow_round(c, start_cells, uv, st);
    if (worst_error(st.spread_p5, st.spread_p95) <= kFlowEnough) break;
  }
  // No narrower than the reweighted map (the rounds' and the lead steps' work undone): back to it.
  if (!(worst_error(st.spread_p5, st.spread_p95) < worst_error(reweighted_p5, reweighted_p95))) {
    uv = reweighted;
    measure_density_error(c.mesh, uv, st);
    st.flow_stopped += ", reverted";
  }
}

namespace {

/// A refinement step from `kept` to uv that widened the density error past `allowed`: the longest of
/// 1/2, 1/4 and 1/8 of it that does not, where its energy is below `kept_energy` (every point of a
/// step is fold-free: the line search stops short of any collapse). True with uv there and `energy`
/// its energy; false with uv back at kept.
bool shorten_within_density(const DensityConstraints& c, const std::vector<Vec2>& kept, double allowed, double kept_energy, double& energy,
                            std::vector<Vec2>& uv, SquareMapStats& st) {
  const std::vector<Vec2> whole = uv;
  for (double t : {0.5, 0.25, 0.125}) {
    for (size_t v = 0; v < uv.size(); ++v) uv[v] = kept[v] + t * (whole[v] - kept[v]);
    measure_density_error(c.mesh, uv, st);
    if (worst_error(st.spread_p5, st.spread_p95) > allowed) continue;
    energy = refine_in_rectangle(c, st.blended_target, 0, {}, uv).energy_before;  // no step: the energy at uv
    if (energy < kept_energy) return true;
    break;
  }
  uv = kept;
  measure_density_error(c.mesh, uv, st);
  return false;
}

/// The refinement of a map whose promise is its density (refine_keeps_density): one step at a time,
/// each kept while the density error stays within kRefineSlack of the reweighted map's; the first step
/// that widens it further is shortened until it does not (shorten_within_density), or undone, and ends
/// the refinement ("density"). Newton's steps lower the energy fast enough that all of a map's steps
/// would widen it too far where the first few, or part of the first, do not.
SlimStats refine_keeping_density(const DensityConstraints& c, const std::function<void(int)>& on_step, std::vector<Vec2>& uv,
                                 SquareMapStats& st) {
  const double allowed = worst_error(st.spread_p5, st.spread_p95) + kRefineSlack;
  SlimStats total;
  std::vector<Vec2> kept = uv;
  for (int step = 0; step < c.options.refine_iterations && total.stopped.empty(); ++step) {
    const SlimStats one = refine_in_rectangle(c, st.blended_target, 1, {}, uv);
    if (step == 0) total.energy_before = total.energy = one.energy_before;
    if (one.iterations == 0) {
      total.stopped = one.stopped;
      break;
    }
    measure_density_error(c.mesh, uv, st);
    double energy = one.energy;
    if (worst_error(st.spread_p5, st.spread_p95) > allowed) {
      total.stopped = "density";
      if (!shorten_within_density(c, kept, allowed, total.energy, energy, uv, st)) break;
    }
    kept = uv;
    total.energy = energy;
    on_step(++total.iterations);
    if (total.stopped.empty() && one.stopped == "converged") total.stopped = one.stopped;
  }
  if (total.stopped.empty()) total.stopped = "iterations";
  return total;
}

/// The symmetric Dirichlet refinement (refine_towards_targets) with the constraints as given, then the
/// target correction.
void refine_and_correct(const DensityConstraints& c, std::vector<Vec2>& uv, SquareMapStats& st) {
  const auto on_step = [&](int step) {
    if (c.options.progress) c.options.progress(0.4 + 0.6 * std::min(1.0, step / 15.0));
  };
  const SlimStats ss = c.options.refine_keeps_density ? refine_keeping_density(c, on_step, uv, st)
                                                      : refine_in_rectangle(c, st.blended_target, c.options.refine_iterations, on_step, uv);
  st.refine_iterations = ss.iterations;
  st.refine_energy_before = ss.energy_before;
  st.refine_energy = ss.energy;
  st.refine_stopped = ss.stopped;
  correct_targets(c, measure_density_error(c.mesh, uv, st), uv, st);
}

/// Whether the notches that chords' ends moved inwards leave beside them take the real faces (not
/// scaffolding) below kMinRealShare of the square, where the caps alone would not.
bool notches_too_large(const Surface& m, const std::vector<Vec2>& uv) {
  double real = 0, all = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const double area = signed_area(uv[m.triangles[f][0]], uv[m.triangles[f][1]], uv[m.triangles[f][2]]);
    all += area;
    if (m.face_parent[f] != kNone) real += area;
  }
  const double notches = std::max(0.0, 1 - all);
  return real < kMinRealShare && real + notches >= kMinRealShare;
}

}  // namespace

void refine_towards_targets(const DensityConstraints& c, std::vector<Vec2>& uv, SquareMapStats& st) {
  if (c.options.refine_iterations <= 0) return;
  const std::vector<Vec2> start = c.bounds.empty() ? std::vector<Vec2>{} : uv;
  const SquareMapStats start_stats = c.bounds.empty() ? SquareMapStats{} : st;
  refine_and_correct(c, uv, st);
  if (c.bounds.empty() || !notches_too_large(c.mesh, uv)) return;
  // The chords' ends moved in so far that the notches beside them took too much of the square: the
  // refinement again, with the chords on their sides.
  DensityConstraints on_sides = c;
  on_sides.fixed = c.fixed_on_sides;
  on_sides.bounds.clear();
  on_sides.refinement = nullptr;
  uv = start;
  st = start_stats;
  refine_and_correct(on_sides, uv, st);
}

}  // namespace tightex
