#include "param/sparse_cholesky.hpp"
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "param/param.hpp"

namespace tightex {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

enum class Weights { kCotangent, kClamped, kUniform };

/// Per interior edge (as a halfedge pair, stored on the smaller halfedge) the Laplacian weight.
std::vector<double> edge_weights(const Surface& m, Weights kind, size_t* negative) {
  const size_t nh = m.opposite.size();
  std::vector<double> half_cot(nh, 0.0);  // 1/2 cot of the angle opposite halfedge h in its triangle
  for (uint32_t h = 0; h < nh; ++h) {
    const Vec3 &a = m.positions[m.from(h)], &b = m.positions[m.to(h)],
               &c = m.positions[m.triangles[h / 3][(h % 3 + 2) % 3]];
    const Vec3 u = a - c, v = b - c;
    const double cross = u.cross(v).norm();
    const double dot = u.dot(v);
    half_cot[h] = cross > 0 ? 0.5 * dot / cross : 0.0;
  }
  std::vector<double> w(nh, 0.0);
  double mean_abs = 0;
  size_t count = 0, neg = 0;
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t o = m.opposite[h];
    if (o != kNone && o < h) continue;
    w[h] = half_cot[h] + (o == kNone ? 0.0 : half_cot[o]);
    if (!std::isfinite(w[h])) w[h] = 0;
    mean_abs += std::abs(w[h]);
    ++count;
    neg += w[h] < 0;
  }
  if (negative) *negative = neg;
  mean_abs = count ? mean_abs / double(count) : 1.0;
  if (!(mean_abs > 0)) mean_abs = 1.0;
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t o = m.opposite[h];
    if (o != kNone && o < h) continue;
    if (kind == Weights::kUniform) w[h] = 1.0;
    else if (kind == Weights::kClamped) w[h] = std::max(w[h], 1e-3 * mean_abs);
  }
  return w;
}

/// Solves the Dirichlet problem with the boundary fixed at `uv` of boundary vertices. The fallbacks
/// change the weights, never the sparsity pattern: the symbolic analysis is done once.
bool solve_interior(const Surface& m, const std::vector<double>& w, const std::vector<char>& on_boundary,
                    std::vector<Vec2>& uv, SparseCholesky& solver, bool& analyzed) {
  const size_t nv = m.num_vertices();
  std::vector<int> unknown(nv, -1);
  int n = 0;
  for (size_t v = 0; v < nv; ++v)
    if (!on_boundary[v]) unknown[v] = n++;
  if (n == 0) return true;
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(size_t(n) * 7);
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(n, 2);
  std::vector<double> diag(size_t(n), 0.0);
  for (uint32_t h = 0; h < m.opposite.size(); ++h) {
    const uint32_t o = m.opposite[h];
    if (o == kNone || o < h) continue;  // boundary edges join two fixed vertices
    const uint32_t a = m.from(h), b = m.to(h);
    const double wt = w[h];
    const int ia = unknown[a], ib = unknown[b];
    if (ia >= 0) diag[size_t(ia)] += wt;
    if (ib >= 0) diag[size_t(ib)] += wt;
    if (ia >= 0 && ib >= 0) {
      trips.emplace_back(std::max(ia, ib), std::min(ia, ib), -wt);  // lower triangle only
    } else if (ia >= 0) {
      rhs.row(ia) += wt * uv[b].transpose();
    } else if (ib >= 0) {
      rhs.row(ib) += wt * uv[a].transpose();
    }
  }
  for (int i = 0; i < n; ++i) trips.emplace_back(i, i, diag[size_t(i)]);
  SpMat A(n, n);
  A.setFromTriplets(trips.begin(), trips.end());
  if (!analyzed) {
    solver.analyzePattern(A);
    analyzed = true;
  }
  if (!solver.factorize(A)) return false;
  Eigen::MatrixX2d x;
  if (!solver.solve(A, rhs, x)) return false;
  for (size_t v = 0; v < nv; ++v)
    if (unknown[v] >= 0) uv[v] = x.row(unknown[v]).transpose();
  return true;
}

/// Area-weighted quantile q of values (weights > 0).
double weighted_quantile(std::vector<std::pair<double, double>>& value_weight, double q) {
  std::sort(value_weight.begin(), value_weight.end());
  double total = 0;
  for (const auto& [v, w] : value_weight) total += w;
  double acc = 0;
  for (const auto& [v, w] : value_weight) {
    acc += w;
    if (acc >= q * total) return v;
  }
  return value_weight.empty() ? 0.0 : value_weight.back().first;
}

/// The boundary loop as placed on the square: which side each boundary vertex starts, the face of each
/// boundary edge (bnd[i], bnd[i+1]), and the vertices that may not move (corners, bumps).
struct SquareBoundary {
  const std::vector<uint32_t>* bnd = nullptr;
  std::array<size_t, 4> corner{};
  std::vector<int> side_of;
  std::vector<uint32_t> edge_face;
  std::vector<char> pinned;
};

/// Slides the boundary vertices along their sides: each boundary edge's length is multiplied by the
/// square root of target/area of its face, then each side is rescaled to its full length. The order
/// along a side never changes, so the boundary stays convex and the next Tutte solve cannot fold.
/// Sides holding a pinned (bumped) vertex stay as they are.
void slide_boundary(const SquareBoundary& b, const std::vector<double>& log_ratio, std::vector<Vec2>& uv) {
  static const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const auto& bnd = *b.bnd;
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
      uv[bnd[(a + j) % nb]] = (1 - t) * kCorner[k] + t * kCorner[(k + 1) % 4];
    }
  }
}

/// The density iterations of map_to_square (see param.hpp). `uv` holds a fold-free map with the
/// boundary already placed; `w` positive weights (one per edge, on its smaller halfedge).
void equalize_density(const Surface& m, const SquareMapOptions& options, const std::vector<char>& on_boundary,
                      const SquareBoundary* sides, std::vector<double> w, SparseCholesky& solver, bool& analyzed, std::vector<Vec2>& uv,
                      SquareMapStats& st) {
  const size_t nf = m.num_faces();
  const double balance = std::clamp(options.balance, 0.0, 1.0);
  std::vector<double> log_target(nf), area(nf);
  auto areas = [&](const std::vector<Vec2>& p) {
    double total = 0;
    for (size_t f = 0; f < nf; ++f) total += area[f] = signed_area(p[m.triangles[f][0]], p[m.triangles[f][1]], p[m.triangles[f][2]]);
    return total;
  };
  areas(uv);
  // Blend in log space with the harmonic map's own areas; then normalise so the targets fill the map.
  for (size_t f = 0; f < nf; ++f) {
    const double t = options.face_target[f] > 0 ? options.face_target[f] : 1e-300;
    log_target[f] = balance * std::log(t) + (1 - balance) * std::log(std::max(area[f], 1e-300));
  }
  std::vector<double> log_ratio(nf), scaled_target(nf);
  std::vector<std::pair<double, double>> vw(nf);
  // log(area/target) per face after normalisation, and its P5/P95 in log2.
  auto measure_ratio = [&](double total, double* p5, double* p95) {
    double lt_max = -1e300;
    for (size_t f = 0; f < nf; ++f) lt_max = std::max(lt_max, log_target[f]);
    double sum_t = 0;
    for (size_t f = 0; f < nf; ++f) sum_t += std::exp(log_target[f] - lt_max);
    const double log_scale = std::log(total / sum_t) - lt_max;  // target_f = exp(log_target + log_scale)
    for (size_t f = 0; f < nf; ++f) {
      log_ratio[f] = std::log(std::max(area[f], 1e-300)) - (log_target[f] + log_scale);
      scaled_target[f] = std::exp(log_target[f] + log_scale);
      vw[f] = {log_ratio[f] / std::numbers::ln2, scaled_target[f]};
    }
    *p5 = weighted_quantile(vw, 0.05);
    *p95 = weighted_quantile(vw, 0.95);
  };
  double total = areas(uv), p5 = 0, p95 = 0;
  measure_ratio(total, &p5, &p95);
  st.blended_target = scaled_target;
  st.spread_before_p5 = st.spread_p5 = p5;
  st.spread_before_p95 = st.spread_p95 = p95;
  st.stopped = "iterations";
  double best = std::max(-p5, p95);
  std::vector<Vec2> trial, best_uv = uv;
  double best_p5 = p5, best_p95 = p95;
  int stalls = 0;
  for (int it = 0; it < options.max_iterations; ++it) {
    if (best <= options.tolerance_log2) {
      st.stopped = "converged";
      break;
    }
    // Each edge's weight times sqrt(area/target) of its faces (geometric mean).
    for (uint32_t h = 0; h < m.opposite.size(); ++h) {
      const uint32_t o = m.opposite[h];
      if (o == kNone || o < h) continue;
      const double lr = 0.5 * (log_ratio[h / 3] + log_ratio[o / 3]);
      w[h] *= std::exp(0.5 * std::clamp(lr, -20.0, 20.0));
    }
    trial = uv;
    if (sides) slide_boundary(*sides, log_ratio, trial);
    if (!solve_interior(m, w, on_boundary, trial, solver, analyzed)) {
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
    total = areas(uv);
    measure_ratio(total, &p5, &p95);
    st.spread_p5 = p5;
    st.spread_p95 = p95;
    const double now = std::max(-p5, p95);
    stalls = now > 0.98 * best ? stalls + 1 : 0;
    if (now < best) best = now, best_uv = uv, best_p5 = p5, best_p95 = p95;
    if (stalls >= 3) {
      st.stopped = "stalled";
      break;
    }
  }
  uv.swap(best_uv);  // the iterate closest to the target (the last may have overshot)
  st.spread_p5 = best_p5;
  st.spread_p95 = best_p95;
}

}  // namespace

size_t count_folds(const Surface& mesh, const std::vector<Vec2>& uv) {
  size_t folds = 0;
  for (const Tri& f : mesh.triangles) folds += !(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0);
  return folds;
}

size_t count_collapsed(const Surface& mesh, const std::vector<Vec2>& uv, const SquareMapOptions& options, uint32_t* worst_vertex) {
  const double sx = double(std::max(1, options.rect_width - 1)), sy = double(std::max(1, options.rect_height - 1));
  const double extent = std::max({options.texel_extent, double(options.rect_width), double(options.rect_height)});
  const double rounding = std::ldexp(extent, -52);  // texels
  size_t collapsed = 0;
  double worst = 1;
  for (const Tri& f : mesh.triangles) {
    const Vec2 a(uv[f[0]].x() * sx, uv[f[0]].y() * sy), b(uv[f[1]].x() * sx, uv[f[1]].y() * sy), c(uv[f[2]].x() * sx, uv[f[2]].y() * sy);
    const double margin = signed_area(a, b, c) / (rounding * ((b - a).norm() + (c - b).norm() + (a - c).norm()));
    if (!(margin >= 1)) {
      collapsed++;
      if (!(margin >= worst)) {
        worst = margin;
        if (worst_vertex) *worst_vertex = f[0];
      }
    }
  }
  return collapsed;
}

std::vector<Vec2> map_to_square(const Disk& disk, const SquareMapOptions& options, SquareMapStats* stats) {
  SquareMapStats st;
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  std::vector<Vec2> uv(m.num_vertices(), Vec2::Zero());
  if (nb < 3) fail_internal("map_to_square: boundary has {} vertices", nb);

  // Arc length along the boundary; with a density target, each edge's length is scaled by the square
  // root of its face's target density (target area / 3D area), so lengths along a side are in the
  // units the target asks for.
  const bool density = !options.face_target.empty();
  if (density && options.face_target.size() != m.num_faces())
    fail_internal("map_to_square: {} face targets for {} faces", options.face_target.size(), m.num_faces());
  std::vector<double> edge_scale(nb, 1.0);
  std::vector<uint32_t> edge_face(nb, kNone);  // the face of boundary edge (bnd[i], bnd[i+1])
  if (density) {
    std::vector<uint32_t> boundary_face_from(m.num_vertices(), kNone), boundary_face_to(m.num_vertices(), kNone);
    for (uint32_t h = 0; h < m.opposite.size(); ++h)
      if (m.opposite[h] == kNone) boundary_face_from[m.from(h)] = h / 3, boundary_face_to[m.to(h)] = h / 3;
    for (size_t i = 0; i < nb; ++i) {
      uint32_t f = boundary_face_from[bnd[i]];
      if (f == kNone || !(m.triangles[f][0] == bnd[(i + 1) % nb] || m.triangles[f][1] == bnd[(i + 1) % nb] || m.triangles[f][2] == bnd[(i + 1) % nb]))
        f = boundary_face_to[bnd[i]];
      if (f == kNone) continue;
      edge_face[i] = f;
      const double a3 = triangle_area(m.positions[m.triangles[f][0]], m.positions[m.triangles[f][1]], m.positions[m.triangles[f][2]]);
      const double d = a3 > 0 ? options.face_target[f] / a3 : 0.0;
      if (d > 0 && std::isfinite(d)) edge_scale[i] = std::pow(d, 0.5 * std::clamp(options.balance, 0.0, 1.0));
    }
  }
  std::vector<double> arc(nb + 1, 0.0);
  for (size_t i = 0; i < nb; ++i) arc[i + 1] = arc[i] + edge_scale[i] * (m.positions[bnd[(i + 1) % nb]] - m.positions[bnd[i]]).norm();
  const double total = arc[nb];
  // The rectangle's width/height (texel spacing is the same both ways): 1 for the paper's map.
  const double aspect = density ? double(std::max(1, options.rect_width)) / double(std::max(1, options.rect_height)) : 1.0;
  const std::array<size_t, 4> corner = choose_corners(disk, arc, options.corners, aspect);
  for (int k = 0; k < 4; ++k) st.corners[k] = bnd[corner[k]];

  // Alg. 1: each side by arc length between its corners.
  static const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::vector<char> on_boundary(m.num_vertices(), 0);
  std::vector<int> side_of(nb, 0);
  std::vector<double> side_t(nb, 0.0);
  std::vector<char> pinned(nb, 0);  // corners and bumped vertices: fixed in both coordinates
  for (int k = 0; k < 4; ++k) pinned[corner[k]] = 1;
  if (nb == 3) std::fill(pinned.begin(), pinned.end(), 1);
  for (int k = 0; k < 4; ++k) {
    const size_t a = corner[k], b = corner[(k + 1) % 4];
    const size_t len = (b + nb - a) % nb;
    if (len == 0) continue;
    auto arc_from_a = [&](size_t i) {
      const double d = arc[i] - arc[a];
      return d < 0 ? d + total : d;
    };
    const double side_len = (b == a) ? total : (arc_from_a(b) > 0 ? arc_from_a(b) : total);
    for (size_t j = 0; j < len; ++j) {
      const size_t i = (a + j) % nb;
      const double t = side_len > 0 ? arc_from_a(i) / side_len : double(j) / double(len);
      uv[bnd[i]] = (1 - t) * kCorner[k] + t * kCorner[(k + 1) % 4];
      side_of[i] = k;
      side_t[i] = t;
    }
  }
  if (nb == 3) uv[bnd[2]] = kCorner[2];
  for (uint32_t v : bnd) on_boundary[v] = 1;

  // Bumps over chords whose two ends lie on the same side.
  if (nb > 4) {
    std::vector<int> bindex(m.num_vertices(), -1);
    for (size_t i = 0; i < nb; ++i) bindex[bnd[i]] = int(i);
    std::vector<std::vector<std::pair<size_t, size_t>>> intervals(4);  // per side, offsets from its corner
    auto offset = [&](int k, size_t i) { return (i + nb - corner[k]) % nb; };
    auto side_len_idx = [&](int k) { return (corner[(k + 1) % 4] + nb - corner[k]) % nb; };
    for (uint32_t h = 0; h < m.opposite.size(); ++h) {
      const uint32_t o = m.opposite[h];
      if (o == kNone || o < h) continue;
      const int ia = bindex[m.from(h)], ib = bindex[m.to(h)];
      if (ia < 0 || ib < 0) continue;
      for (int k = 0; k < 4; ++k) {
        const size_t L = side_len_idx(k), pa = offset(k, size_t(ia)), pb = offset(k, size_t(ib));
        if (pa <= L && pb <= L && std::max(pa, pb) - std::min(pa, pb) >= 2)
          intervals[k].push_back({std::min(pa, pb), std::max(pa, pb)});
      }
    }
    for (int k = 0; k < 4; ++k) {
      auto& iv = intervals[k];
      if (iv.empty()) continue;
      std::sort(iv.begin(), iv.end());
      const bool horizontal = (k % 2 == 0);
      const double h = options.bump_texels / double(std::max(1, (horizontal ? options.rect_height : options.rect_width) - 1));
      const Vec2 outward = k == 0 ? Vec2(0, -1) : k == 1 ? Vec2(1, 0) : k == 2 ? Vec2(0, 1) : Vec2(-1, 0);
      const Vec2 along = kCorner[(k + 1) % 4] - kCorner[k];
      size_t lo = iv[0].first, hi = iv[0].second;
      auto bump = [&](size_t lo_, size_t hi_) {
        const size_t ia = (corner[k] + lo_) % nb, ib = (corner[k] + hi_) % nb;
        const double ta = lo_ == 0 ? 0.0 : side_t[ia], tb = hi_ == side_len_idx(k) ? 1.0 : side_t[ib];
        for (size_t p = lo_ + 1; p < hi_; ++p) {
          const size_t i = (corner[k] + p) % nb;
          const double s = (side_t[i] - ta) / std::max(tb - ta, 1e-300);
          uv[bnd[i]] = kCorner[k] + side_t[i] * along + h * std::sin(std::numbers::pi * std::clamp(s, 0.0, 1.0)) * outward;
          pinned[i] = 1;
          st.bumped_vertices++;
        }
      };
      for (size_t j = 1; j < iv.size(); ++j) {
        if (iv[j].first < hi) {
          hi = std::max(hi, iv[j].second);
        } else {
          bump(lo, hi);
          lo = iv[j].first, hi = iv[j].second;
        }
      }
      bump(lo, hi);
    }
  }

  // Alg. 2 with the fold-free fallbacks.
  const std::vector<Vec2> boundary_uv = uv;
  SparseCholesky solver(options.supernodal_from);
  bool analyzed = false;
  std::vector<double> positive_w;  // the positive weights of the first fold-free positive weighting
  for (Weights kind : {Weights::kCotangent, Weights::kClamped, Weights::kUniform}) {
    size_t negative = 0;
    const auto w = edge_weights(m, kind, &negative);
    if (kind != Weights::kCotangent) positive_w = w;
    if (kind == Weights::kCotangent) st.negative_weights = negative;
    uv = boundary_uv;
    if (!solve_interior(m, w, on_boundary, uv, solver, analyzed)) continue;
    st.flipped = count_folds(m, uv);
    st.folds_per_attempt.push_back(st.flipped);
    if (kind == Weights::kClamped && st.flipped)
      for (const Tri& f : m.triangles)
        if (!(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0)) {
          st.crowded_vertex = f[0];
          break;
        }
    st.weights = kind == Weights::kCotangent ? "cotangent" : kind == Weights::kClamped ? "clamped-cotangent" : "uniform";
    if (st.flipped == 0) break;
  }
  // No weighting solved (a factorisation failed, or its solution did not solve the system): the
  // interior still sits where the boundary left it. A failure, never a map.
  if (st.weights.empty()) fail_internal("the sparse solve of the harmonic map failed for every weighting ({} vertices)", m.num_vertices());
  // The paper's map (no density targets) can crowd a region so far that its triangles keep a positive
  // area only below what the output's texture coordinates hold: placed in the rectangle and written in
  // double precision, they come out folded (meshroom_esp32cam with six 1% patches of its surface
  // missing: 3 triangles of 1e-14 texels). A triangle whose area in texels is within the reach of that
  // rounding (2^-52 of the texel extent, per unit of its perimeter) counts as a fold, and its region as
  // crowded (the caller slits to it). The density maps never get near: they spread this map out.
  if (!density && st.flipped == 0) {
    st.flipped = count_collapsed(m, uv, options, &st.crowded_vertex);
    if (st.flipped) st.folds_per_attempt.push_back(st.flipped);
  }
  if (density && st.flipped == 0 && st.crowded_vertex == kNone) {
    if (positive_w.empty()) positive_w = edge_weights(m, Weights::kClamped, nullptr);
    SquareBoundary sb{&bnd, corner, side_of, edge_face, pinned};
    equalize_density(m, options, on_boundary, options.slide_boundary ? &sb : nullptr, positive_w, solver, analyzed, uv, st);
    // Fixed coordinates (bit 0: u, bit 1: v): both for corners and bumps; a side's vertex slides along it.
    // A bump's vertices are pinned off the side; its two neighbours on the side are held too. A free
    // vertex beside a bump could slide past it without any triangle collapsing (the bump is off the
    // line) and turn the boundary back on itself; two neighbours on the side cannot pass each other
    // without their boundary triangle collapsing, which the line search prevents (found with 2% hole
    // caps on the catalogue's holey slab; meshroom_esp32cam at --size 1024 had 4 such pairs).
    std::vector<char> held = pinned;
    for (size_t i = 0; i < nb; ++i)
      if (pinned[i] && std::find(corner.begin(), corner.end(), i) == corner.end()) held[(i + 1) % nb] = held[(i + nb - 1) % nb] = 1;
    // A boundary vertex that `holds(i)` stays (3), every other slides along its side (2: a horizontal
    // side holds v, 1: a vertical one holds u); all stay when the boundary does not slide.
    auto side_constraints = [&](auto&& holds) {
      std::vector<char> fixed(m.num_vertices(), 0);
      for (size_t i = 0; i < nb; ++i) fixed[bnd[i]] = holds(i) || !options.slide_boundary ? 3 : (side_of[i] % 2 == 0 ? 2 : 1);
      return fixed;
    };
    const std::vector<char> fixed = side_constraints([&](size_t i) { return held[i] != 0; });
    // Refined in the rectangle's proportions (area 1: the targets are normalised to the unit square),
    // so the targets' shapes are met in texels. `shapes` (unit square, optional): refine_map's.
    auto refine_in_rect = [&](const std::vector<double>& target, int iterations, const std::function<void(int)>& on_step,
                              const std::vector<FaceShape>* shapes = nullptr) {
      if (aspect == 1.0) return refine_map(m, fixed, target, iterations, uv, options.supernodal_from, on_step, shapes);
      const double sx = std::sqrt(aspect);
      const std::vector<Vec2> before = uv;
      for (Vec2& p : uv) p = Vec2(p.x() * sx, p.y() / sx);
      std::vector<FaceShape> scaled_shapes;
      if (shapes) {
        scaled_shapes = *shapes;
        for (FaceShape& s : scaled_shapes)
          for (Vec2& p : s) p = Vec2(p.x() * sx, p.y() / sx);
      }
      const SlimStats r = refine_map(m, fixed, target, iterations, uv, options.supernodal_from, on_step, shapes ? &scaled_shapes : nullptr);
      for (Vec2& p : uv) p = Vec2(p.x() / sx, p.y() * sx);
      // Held coordinates come back exactly (x * sx / sx may miss 1 by an ulp: a side's texel centres
      // would fall outside the chart).
      for (size_t v = 0; v < uv.size(); ++v)
        for (int a = 0; a < 2; ++a)
          if (fixed[v] & (1 << a)) uv[v](a) = before[v](a);
      return r;
    };
    const size_t nf = m.num_faces();
    std::vector<double> log_ratio(nf);
    auto spread = [&] {
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
    };
    // Where the reweighting stalled short of the targets, the density-equalising flow (density_flow.cpp)
    // moves the whole map on towards them. The flow carries vertices, not triangles: a face spanning
    // many cells of a field that bends across it can fold (the dancing girl with six patches missing:
    // 236 of 18k faces, triangles the reweighting had stretched to 10 cells). Where any folds or
    // collapses below what the output's coordinates hold, kFlowShapeSteps symmetric Dirichlet steps aim
    // from the map before at the shapes the flow gives each face (their line search never folds). A
    // face's shape is a small copy of it (a quarter cell across) carried by the flow as tracers and
    // scaled back: the flow's own local map at the face, which never folds, where the flowed vertices
    // of a long face can. Session 12 aimed at the flowed vertices' triangles: a folded one kept its 3D
    // shape, and its neighbours' shapes did not fit together, so the steps stopped short (seed 11 girl
    // with patches -1.04 / 0.82 and 67 steps; with the tracers' shapes -0.76 / 0.55 in 13 steps; seed
    // 7 -0.89 / 0.61 -> -0.65 / 0.47). The flow runs in rounds that start from a density diffused over
    // 4, then 2, then 1 cells (kFlowStarts): the coarse one folds fewer faces (girl: 128 against 236)
    // and leaves the finer ones less to move. Each round is kept only if it narrows the density error.
    // Measured in session 12 (P5 / P95 of log2(area / target), the girl and meshroom_esp32cam_pages
    // with six patches missing, tools/perturb_obj.py seed 7, the area map's 1:2 probe, the flowed
    // vertices' shapes): reweighting -1.93 / 0.94 and -2.06 / 0.77; one round from 1 cell -0.77 / 0.52
    // and -1.26 / 0.45; from 4, 2, 1 cells -0.74 / 0.50 and -0.62 / 0.37. A fourth round, from 1 or 0.5
    // cell, or rounds from 8, 4, 2, 1 cells, with the tracers' shapes: within 0.01 on the seed-11 girl.
    // Not on a fragment of under kFlowMinFaces faces: the grid's noise moves those by more than it
    // evens them out.
    constexpr size_t kFlowMinFaces = 100;
    constexpr int kFlowShapeSteps = 30;
    constexpr double kFlowStarts[] = {4, 2, 1};
    // Before the flow, kFlowLeadSteps symmetric Dirichlet steps towards the targets' shapes take the
    // shear out of the reweighted map (they widen its density error; the girl: -0.97 / 0.22 -> -1.56 /
    // 1.06); the flow then evens the density out and keeps the shapes far better than from the sheared
    // map. They cost the flow more steps (the girl 4.5 -> 6-8 s, a 93k-triangle scan 38 -> 70 s).
    // Measured (session 14, surface PSNR at the default budget, area map, no steps / 4 / 10):
    // danish_dancinggirl 45.11 / 45.42 / 45.96, meshroom_esp32cam 41.77 / 42.11 / 42.20, its pages
    // version 41.83 / 42.09 / 42.05; perturbed scans in BENCHMARKS.md, "Steps before the flow".
    constexpr int kFlowLeadSteps = 10;
    // The rounds stop once the density error is within +-kFlowEnough (log2), 0.4 of the area map's
    // promise: each round costs a map's worth of symmetric Dirichlet steps where faces fold
    // (meshroom_esp32cam: 0.3 s a step, 7-10 steps a round) and the finer rounds gain little there
    // (-0.31, -0.29, -0.27). It was 0.5 before the lead steps; with them the girl's first round ends
    // at -0.48 (from the reweighted map: -0.36), and its second at -0.32.
    constexpr double kFlowEnough = 0.4;
    if (options.density_flow && nf >= kFlowMinFaces && std::max(-st.spread_p5, st.spread_p95) > options.tolerance_log2) {
      const double reweighted_p5 = st.spread_p5, reweighted_p95 = st.spread_p95;
      // In the flow every side vertex slides with the field, the bumps' too (a continuous flow along a
      // line keeps its points in order, so none passes a bump); only the corners stay.
      const std::vector<char> flow_fixed = side_constraints([&](size_t i) { return std::find(corner.begin(), corner.end(), i) != corner.end(); });
      const std::vector<Vec2> reweighted = uv;
      st.flow_lead_steps = refine_in_rect(st.blended_target, kFlowLeadSteps, {}).iterations;
      spread();
      for (double start_cells : kFlowStarts) {
        const std::vector<Vec2> previous = uv;
        const double previous_p5 = st.spread_p5, previous_p95 = st.spread_p95;
        std::vector<Vec2> flowed = uv;
        FlowOptions fo;
        fo.fold_free = false;
        fo.start_cells = start_cells;
        // Tracers: a small copy of each face about its centroid, at most a quarter cell across: the flow
        // carries it as its own local map (its Jacobian there) carries the face. See kFlowShapeSteps.
        const double cell = 1.0 / flow_grid(nf, fo);
        std::vector<Vec2> tracers(3 * nf);
        std::vector<double> tracer_scale(nf);
        for (size_t f = 0; f < nf; ++f) {
          const Tri& t = m.triangles[f];
          const Vec2 centroid = (uv[t[0]] + uv[t[1]] + uv[t[2]]) / 3.0;
          const double longest = std::max({(uv[t[1]] - uv[t[0]]).norm(), (uv[t[2]] - uv[t[1]]).norm(), (uv[t[0]] - uv[t[2]]).norm()});
          tracer_scale[f] = longest > 0.25 * cell ? 0.25 * cell / longest : 1.0;
          for (size_t k = 0; k < 3; ++k) tracers[3 * f + k] = centroid + tracer_scale[f] * (uv[t[k]] - centroid);
        }
        const FlowStats fs = flow_density(m, flow_fixed, st.blended_target, aspect, flowed, fo, &tracers);
        st.flow_steps += fs.steps;
        st.flow_stopped = fs.stopped;
        const size_t collapsed = count_collapsed(m, flowed, options);
        if (collapsed == 0) {
          uv = flowed;
        } else {
          std::vector<FaceShape> shapes(nf);
          for (size_t f = 0; f < nf; ++f)
            for (size_t k = 0; k < 3; ++k) shapes[f][k] = tracers[3 * f + k] / tracer_scale[f];
          const SlimStats shaped = refine_in_rect(st.blended_target, kFlowShapeSteps, {}, &shapes);
          st.flow_shape_steps += shaped.iterations;
        }
        spread();
        if (!(std::max(-st.spread_p5, st.spread_p95) < std::max(-previous_p5, previous_p95))) {
          uv = previous;
          st.spread_p5 = previous_p5, st.spread_p95 = previous_p95;
        }
        if (std::max(-st.spread_p5, st.spread_p95) <= kFlowEnough) break;
      }
      // No narrower than the reweighted map (the rounds' and the lead steps' work undone): back to it.
      if (!(std::max(-st.spread_p5, st.spread_p95) < std::max(-reweighted_p5, reweighted_p95))) {
        uv = reweighted;
        spread();
        st.flow_stopped += ", reverted";
      }
    }
    if (options.refine_iterations > 0) {
      const std::vector<Vec2> reweighted = uv;
      const double reweighted_p5 = st.spread_p5, reweighted_p95 = st.spread_p95;
      const SlimStats ss = refine_in_rect(st.blended_target, options.refine_iterations, [&](int step) {
        if (options.progress) options.progress(0.4 + 0.6 * std::min(1.0, step / 15.0));
      });
      st.refine_iterations = ss.iterations;
      st.refine_energy_before = ss.energy_before;
      st.refine_energy = ss.energy;
      st.refine_stopped = ss.stopped;
      spread();
      // Refinement trades a little density for much less shear (PSNR: meshroom +0.4 dB); it is kept
      // unless it widens the density error by more than kRefineSlack.
      constexpr double kRefineSlack = 0.1;
      const double before = std::max(-reweighted_p5, reweighted_p95);
      if (options.refine_keeps_density && std::max(-st.spread_p5, st.spread_p95) > before + kRefineSlack) {
        uv = reweighted;
        st.refine_stopped = "reverted";
        spread();
      }
      // The symmetric Dirichlet energy balances area against angle; where the area still misses its
      // target, the target shape itself is corrected (grown where the face came out small) and the
      // energy lowered again, so the density converges at the cost of a little more shear.
      std::vector<double> corrected = st.blended_target;
      for (int round = 0; round < options.correction_rounds; ++round) {
        if (std::max(-st.spread_p5, st.spread_p95) <= options.tolerance_log2) break;
        for (size_t f = 0; f < nf; ++f) corrected[f] *= std::exp2(-std::clamp(log_ratio[f], -4.0, 4.0));
        const std::vector<Vec2> previous = uv;
        const double previous_p5 = st.spread_p5, previous_p95 = st.spread_p95;
        const SlimStats cs = refine_in_rect(corrected, 2, {});
        st.refine_iterations += cs.iterations;
        ++st.correction_rounds;
        spread();
        if (std::max(-st.spread_p5, st.spread_p95) > std::max(-previous_p5, previous_p95) + kRefineSlack) {  // worse: undo, stop
          uv = previous;
          st.spread_p5 = previous_p5, st.spread_p95 = previous_p95;
          break;
        }
      }
    }
    st.blended_target.clear();
  }
  if (stats) *stats = st;
  return uv;
}

}  // namespace tightex
