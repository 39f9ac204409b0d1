#include "param/density_reweighting.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/statistics.hpp"
#include "param/folds.hpp"

namespace tightex {

namespace {

/// Slides the boundary vertices along their sides: each boundary edge's length is multiplied by the
/// square root of target/area of its face, then each side is rescaled to its full length. The order
/// along a side never changes, so the boundary stays convex and the next Tutte solve cannot fold.
/// Sides holding a pinned (bumped) vertex stay as they are.
void slide_boundary(const std::vector<uint32_t>& bnd, const SquareBoundary& b, const std::vector<double>& log_ratio,
                    std::vector<Vec2>& uv) {
  const size_t nb = bnd.size();
  if (nb < 5) return;
  for (int k = 0; k < 4; ++k) {
    const size_t a = b.corner[k], len = (b.corner[(k + 1) % 4] + nb - a) % nb;
    if (len < 2) continue;
    bool movable = true;
    for (size_t j = 1; j < len; ++j) movable = movable && !b.pinned[(a + j) % nb];
    if (!movable) continue;
    std::vector<double> l(len);
    double total = 0;
    for (size_t j = 0; j < len; ++j) {
      const size_t i = (a + j) % nb;
      const double cur = (uv[bnd[(i + 1) % nb]] - uv[bnd[i]]).norm();
      const uint32_t f = b.edge_face[i];
      const double lr = f == kNone ? 0.0 : std::clamp(log_ratio[f], -4.0, 4.0);
      l[j] = std::max(cur, 1e-12) * std::exp(-0.5 * lr);
      total += l[j];
    }
    double acc = 0;
    for (size_t j = 1; j < len; ++j) {
      acc += l[j - 1];
      const double t = acc / total;
      uv[bnd[(a + j) % nb]] = (1 - t) * kSquareCorners[k] + t * kSquareCorners[(k + 1) % 4];
    }
  }
}

/// Each face's signed UV area into `area`; returns their sum.
double face_areas(const Surface& m, const std::vector<Vec2>& uv, std::vector<double>& area) {
  double total = 0;
  for (size_t f = 0; f < m.num_faces(); ++f)
    total += area[f] = signed_area(uv[m.triangles[f][0]], uv[m.triangles[f][1]], uv[m.triangles[f][2]]);
  return total;
}

/// The density error of a map against fixed log targets (any common scale).
struct DensityError {
  std::vector<double> log_ratio;                        // per face log(area / target), the targets scaled to the map's area
  std::vector<double> scaled_target;                    // per face the target so scaled
  double p5 = 0, p95 = 0;                               // P5 and P95 of log2(area / target), weighted by target
  std::vector<std::pair<double, double>> value_weight;  // scratch for the quantiles

  explicit DensityError(size_t faces) : log_ratio(faces), scaled_target(faces), value_weight(faces) {}

  /// Measures faces of `area` (summing to `total`) against exp(log_target).
  void measure(const std::vector<double>& log_target, const std::vector<double>& area, double total) {
    const size_t nf = area.size();
    double lt_max = -1e300;
    for (size_t f = 0; f < nf; ++f) lt_max = std::max(lt_max, log_target[f]);
    double sum_t = 0;
    for (size_t f = 0; f < nf; ++f) sum_t += std::exp(log_target[f] - lt_max);
    const double log_scale = std::log(total / sum_t) - lt_max;  // target_f = exp(log_target + log_scale)
    for (size_t f = 0; f < nf; ++f) {
      log_ratio[f] = std::log(std::max(area[f], 1e-300)) - (log_target[f] + log_scale);
      scaled_target[f] = std::exp(log_target[f] + log_scale);
      value_weight[f] = {log_ratio[f] / std::numbers::ln2, scaled_target[f]};
    }
    p5 = weighted_quantile(value_weight, 0.05);
    p95 = weighted_quantile(value_weight, 0.95);
  }
  double worst() const { return std::max(-p5, p95); }
};

/// Each edge's weight times sqrt(area/target) of its faces (geometric mean).
void reweight_edges(const Surface& m, const std::vector<double>& log_ratio, std::vector<double>& w) {
  for (uint32_t h = 0; h < m.opposite.size(); ++h) {
    const uint32_t o = m.opposite[h];
    if (o == kNone || o < h) continue;
    const double lr = 0.5 * (log_ratio[h / 3] + log_ratio[o / 3]);
    w[h] *= std::exp(0.5 * std::clamp(lr, -20.0, 20.0));
  }
}

}  // namespace

void reweight_towards_density(const Surface& m, const std::vector<uint32_t>& boundary, const SquareMapOptions& options,
                              const SquareBoundary* sliding, std::vector<double> w, DirichletSolver& solver, std::vector<Vec2>& uv,
                              SquareMapStats& st) {
  const size_t nf = m.num_faces();
  const double balance = std::clamp(options.balance, 0.0, 1.0);
  const std::vector<char> on_boundary = boundary_mask(m.num_vertices(), boundary);
  std::vector<double> log_target(nf), area(nf);
  face_areas(m, uv, area);
  // Blend in log space with the harmonic map's own areas; then normalise so the targets fill the map.
  for (size_t f = 0; f < nf; ++f) {
    const double t = options.face_target[f] > 0 ? options.face_target[f] : 1e-300;
    log_target[f] = balance * std::log(t) + (1 - balance) * std::log(std::max(area[f], 1e-300));
  }
  DensityError error(nf);
  error.measure(log_target, area, face_areas(m, uv, area));
  st.blended_target = error.scaled_target;
  st.spread_before_p5 = st.spread_p5 = error.p5;
  st.spread_before_p95 = st.spread_p95 = error.p95;
  st.stopped = "iterations";
  double best = error.worst();
  std::vector<Vec2> trial, best_uv = uv;
  double best_p5 = error.p5, best_p95 = error.p95;
  int stalls = 0;
  for (int it = 0; it < options.max_iterations; ++it) {
    if (best <= options.tolerance_log2) {
      st.stopped = "converged";
      break;
    }
    reweight_edges(m, error.log_ratio, w);
    trial = uv;
    if (sliding) slide_boundary(boundary, *sliding, error.log_ratio, trial);
    if (!solver.solve(m, w, on_boundary, trial)) {
      st.stopped = "solver";
      break;
    }
    if (count_folds(m, trial) > 0) {
      st.stopped = "fold";
      break;
    }
    uv.swap(trial);
    ++st.iterations;
    if (options.progress) options.progress(0.4 * std::min(1.0, st.iterations / 20.0));
    error.measure(log_target, area, face_areas(m, uv, area));
    st.spread_p5 = error.p5;
    st.spread_p95 = error.p95;
    const double now = error.worst();
    stalls = now > 0.98 * best ? stalls + 1 : 0;
    if (now < best) best = now, best_uv = uv, best_p5 = error.p5, best_p95 = error.p95;
    if (stalls >= 3) {
      st.stopped = "stalled";
      break;
    }
  }
  uv.swap(best_uv);  // the iterate closest to the target (the last may have overshot)
  st.spread_p5 = best_p5;
  st.spread_p95 = best_p95;
}

}  // namespace tightex
