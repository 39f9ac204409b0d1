#include "param/harmonic.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>

#include <tbb/parallel_invoke.h>

#include "core/eigen_vector.hpp"
#include "param/folds.hpp"
#include "param/multigrid.hpp"
#include "param/sparse_cholesky.hpp"

namespace tightex {

std::string_view to_string(EdgeWeights kind) {
  switch (kind) {
    case EdgeWeights::kCotangent:
      return "cotangent";
    case EdgeWeights::kClamped:
      return "clamped-cotangent";
    case EdgeWeights::kUniform:
      return "uniform";
  }
  return "";
}

std::vector<double> edge_weights(const Surface& m, EdgeWeights kind, size_t* negative) {
  const size_t nh = m.opposite.size();
  std::vector<double> half_cot(nh, 0.0);  // 1/2 cot of the angle opposite halfedge h in its triangle
  for (uint32_t h = 0; h < nh; ++h) {
    const Vec3 &a = m.positions[m.from(h)], &b = m.positions[m.to(h)], &c = m.positions[m.triangles[h / 3][(h % 3 + 2) % 3]];
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
    if (kind == EdgeWeights::kUniform)
      w[h] = 1.0;
    else if (kind == EdgeWeights::kClamped)
      w[h] = std::max(w[h], 1e-3 * mean_abs);
  }
  return w;
}

std::vector<char> boundary_mask(size_t num_vertices, const std::vector<uint32_t>& boundary) {
  std::vector<char> on_boundary(num_vertices, 0);
  for (uint32_t v : boundary) on_boundary[v] = 1;
  return on_boundary;
}

/// The Laplacian over the vertices off the boundary (lower triangle), its pattern built once: where
/// each edge's and each unknown's entry lands in the value array, so a solve only overwrites values
/// (a new matrix per solve allocated and page-faulted 100 MB at 1.7M unknowns, eight times a map).
struct DirichletSolver::Laplacian {
  std::vector<int> unknown;  // per vertex, -1 on the boundary
  int n = 0;
  SparseCholesky::Matrix a;
  std::vector<int> edge_slot;  // per halfedge: its edge's entry (on the edge's first halfedge; -1 elsewhere)
  std::vector<int> diagonal_slot;

  Laplacian(const Surface& m, const std::vector<char>& on_boundary) : unknown(m.num_vertices(), -1), edge_slot(m.opposite.size(), -1) {
    for (size_t v = 0; v < unknown.size(); ++v)
      if (!on_boundary[v]) unknown[v] = n++;
    std::vector<Eigen::Triplet<double>> trips;
    trips.reserve(size_t(n) * 4);
    for_each_entry(m, [&](uint32_t, int row, int col) { trips.emplace_back(row, col, 0.0); });
    for (int i = 0; i < n; ++i) trips.emplace_back(i, i, 0.0);
    a.resize(n, n);
    a.setFromTriplets(trips.begin(), trips.end());
    a.makeCompressed();
    for_each_entry(m, [&](uint32_t h, int row, int col) { edge_slot[h] = slot(row, col); });
    diagonal_slot.resize(size_t(n));
    for (int i = 0; i < n; ++i) diagonal_slot[size_t(i)] = slot(i, i);
  }

  /// Whether this system holds exactly the vertices on_boundary marks.
  bool holds(const std::vector<char>& on_boundary) const {
    if (on_boundary.size() != unknown.size()) return false;
    for (size_t v = 0; v < unknown.size(); ++v)
      if ((on_boundary[v] != 0) != (unknown[v] < 0)) return false;
    return true;
  }

  /// Calls f(halfedge, row, col) for every edge joining two unknowns, once (on its first halfedge).
  template <class F>
  void for_each_entry(const Surface& m, F&& f) const {
    for (uint32_t h = 0; h < m.opposite.size(); ++h) {
      const uint32_t o = m.opposite[h];
      if (o == kNone || o < h) continue;  // boundary edges join two fixed vertices
      const int ia = unknown[m.from(h)], ib = unknown[m.to(h)];
      if (ia >= 0 && ib >= 0) f(h, std::max(ia, ib), std::min(ia, ib));
    }
  }

  int slot(int row, int col) const {
    const int* begin = a.innerIndexPtr() + a.outerIndexPtr()[col];
    const int* end = a.innerIndexPtr() + a.outerIndexPtr()[col + 1];
    return int(std::lower_bound(begin, end, row) - a.innerIndexPtr());
  }

  /// The matrix's values and the right-hand side for weights w, the boundary held at uv.
  void assemble(const Surface& m, const std::vector<double>& w, const std::vector<Vec2>& uv, Eigen::MatrixX2d& rhs) {
    double* values = a.valuePtr();
    std::fill(values, values + a.nonZeros(), 0.0);
    rhs = Eigen::MatrixX2d::Zero(n, 2);
    for (uint32_t h = 0; h < m.opposite.size(); ++h) {
      const uint32_t o = m.opposite[h];
      if (o == kNone || o < h) continue;
      const uint32_t va = m.from(h), vb = m.to(h);
      const double wt = w[h];
      const int ia = unknown[va], ib = unknown[vb];
      if (ia >= 0) values[diagonal_slot[size_t(ia)]] += wt;
      if (ib >= 0) values[diagonal_slot[size_t(ib)]] += wt;
      if (ia >= 0 && ib >= 0) {
        values[edge_slot[h]] += -wt;
      } else if (ia >= 0) {
        rhs.row(ia) += wt * as_eigen(uv[vb]).transpose();
      } else if (ib >= 0) {
        rhs.row(ib) += wt * as_eigen(uv[va]).transpose();
      }
    }
  }
};

DirichletSolver::DirichletSolver(long supernodal_from, std::shared_ptr<const std::vector<int>> vertex_order)
    : cholesky_(std::make_unique<SparseCholesky>(supernodal_from)), vertex_order_(std::move(vertex_order)) {}

DirichletSolver::~DirichletSolver() = default;

void DirichletSolver::solve_iteratively(std::shared_ptr<const VertexAggregates> aggregates, double tolerance) {
  aggregates_ = std::move(aggregates);
  tolerance_ = tolerance;
  laplacian_.reset();
}

void DirichletSolver::prepare(const Surface& m, const std::vector<char>& on_boundary) {
  const size_t nv = m.num_vertices();
  laplacian_ = std::make_unique<Laplacian>(m, on_boundary);
  multilevel_.reset();
  cholesky_analysed_ = false;
  if (laplacian_->n == 0) return;
  if (aggregates_) {
    std::vector<uint32_t> vertex(size_t(laplacian_->n));
    for (size_t v = 0; v < nv; ++v)
      if (laplacian_->unknown[v] >= 0) vertex[size_t(laplacian_->unknown[v])] = uint32_t(v);
    multilevel_ = std::make_unique<MultilevelSolver>(laplacian_->a, vertex, std::vector<uint8_t>(vertex.size(), 0), *aggregates_);
    return;
  }
  analyse();
}

/// CHOLMOD's analysis of the Laplacian's pattern, in the disk's vertex order where there is one.
void DirichletSolver::analyse() {
  const size_t nv = laplacian_->unknown.size();
  cholesky_analysed_ = true;
  const std::vector<int> order =
      vertex_order_ && vertex_order_->size() == nv ? order_of_unknowns(*vertex_order_, laplacian_->unknown, 1) : std::vector<int>{};
  cholesky_->analyzePattern(laplacian_->a, order.empty() ? nullptr : &order);
}

bool DirichletSolver::solve(const Surface& m, const std::vector<double>& w, const std::vector<char>& on_boundary, std::vector<Vec2>& uv) {
  const size_t nv = m.num_vertices();
  if (!laplacian_ || !laplacian_->holds(on_boundary)) prepare(m, on_boundary);
  Laplacian& lap = *laplacian_;
  if (lap.n == 0) return true;
  Eigen::MatrixX2d rhs;
  lap.assemble(m, w, uv, rhs);
  Eigen::MatrixX2d x(lap.n, 2);
  for (size_t v = 0; v < nv; ++v)
    if (lap.unknown[v] >= 0) x.row(lap.unknown[v]) = as_eigen(uv[v]).transpose();
  if (!multilevel_ || !solve_by_iterations(rhs, x)) {
    if (!cholesky_analysed_) analyse();
    if (!cholesky_->factorize(lap.a)) return false;
    if (!cholesky_->solve(lap.a, rhs, x)) return false;
  }
  for (size_t v = 0; v < nv; ++v)
    if (lap.unknown[v] >= 0) uv[v] = x.row(lap.unknown[v]).transpose();
  return true;
}

namespace {
/// An iterative solve that has not converged by then is given up for the factorisation.
constexpr int kMaxIterations = 200;
}  // namespace

bool DirichletSolver::solve_by_iterations(const Eigen::MatrixX2d& rhs, Eigen::MatrixX2d& x) {
  if (!multilevel_->update(laplacian_->a)) return false;
  IterativeSolve outcome[2];
  Eigen::VectorXd b[2] = {rhs.col(0), rhs.col(1)}, column[2] = {x.col(0), x.col(1)};
  auto solve_column = [&](int k) { outcome[k] = multilevel_->solve(b[k], column[k], tolerance_, kMaxIterations); };
  tbb::parallel_invoke([&] { solve_column(0); }, [&] { solve_column(1); });
  if (!outcome[0].converged || !outcome[1].converged) return false;
  x.col(0) = column[0];
  x.col(1) = column[1];
  return true;
}

bool harmonic_map(const Surface& mesh, const std::vector<uint32_t>& boundary, const std::vector<Vec2>& boundary_uv,
                  const std::vector<double>& weights, DirichletSolver& solver, std::vector<Vec2>& uv) {
  uv.assign(mesh.num_vertices(), Vec2::Zero());
  for (size_t i = 0; i < boundary.size(); ++i) uv[boundary[i]] = boundary_uv[i];
  return solver.solve(mesh, weights, boundary_mask(mesh.num_vertices(), boundary), uv);
}

HarmonicAttempts fold_free_harmonic_map(const Surface& mesh, const std::vector<uint32_t>& boundary, const std::vector<Vec2>& boundary_uv,
                                        DirichletSolver& solver) {
  HarmonicAttempts r;
  for (EdgeWeights kind : {EdgeWeights::kCotangent, EdgeWeights::kClamped, EdgeWeights::kUniform}) {
    size_t negative = 0;
    const auto w = edge_weights(mesh, kind, &negative);
    if (kind != EdgeWeights::kCotangent) r.positive_weights = w;
    if (kind == EdgeWeights::kCotangent) r.negative_weights = negative;
    if (!harmonic_map(mesh, boundary, boundary_uv, w, solver, r.uv)) continue;
    r.flipped = count_folds(mesh, r.uv);
    r.folds_per_attempt.push_back(r.flipped);
    if (kind == EdgeWeights::kClamped && r.flipped)
      for (const Tri& f : mesh.triangles)
        if (!(signed_area(r.uv[f[0]], r.uv[f[1]], r.uv[f[2]]) > 0)) {
          r.crowded_vertex = f[0];
          break;
        }
    r.weights = kind;
    if (r.flipped == 0) break;
  }
  return r;
}

}  // namespace tightex
