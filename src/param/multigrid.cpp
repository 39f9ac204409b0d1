#include "param/multigrid.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/parallel_invoke.h>

namespace tightex {

namespace {

using Matrix = MultilevelSolver::Matrix;

/// A level whose aggregates would leave more than this share of its unknowns is not worth its sweeps.
constexpr double kMinCoarsening = 0.9;

/// The unknowns in blocks of one vertex's consecutive unknowns (one or two): each block's first
/// unknown, then the number of unknowns.
std::vector<int> vertex_blocks(const std::vector<uint32_t>& vertex) {
  std::vector<int> start;
  for (size_t i = 0; i < vertex.size(); ++i)
    if (i == 0 || vertex[i] != vertex[i - 1]) start.push_back(int(i));
  start.push_back(int(vertex.size()));
  return start;
}

/// Solves a block of one or two unknowns (first..last) of a sweep: d its diagonal, off its coupling,
/// s the right-hand side less the rest of its rows. A nearly singular 2x2 block (a projected Hessian's
/// can be: positive semi-definite only) is solved one unknown after the other instead, in the sweep's
/// order (so the backward sweep stays the forward one's transpose); an unknown whose diagonal is not
/// positive is left at 0.
void solve_block(int first, int last, const double (&s)[2], const double (&d)[2], double off, bool forward, Eigen::VectorXd& x) {
  const auto solve_one = [](double rhs, double diagonal) { return diagonal > 0 ? rhs / diagonal : 0.0; };
  if (first == last) {
    x[first] = solve_one(s[0], d[0]);
    return;
  }
  const double det = d[0] * d[1] - off * off;
  if (det > 1e-9 * d[0] * d[1]) {
    x[first] = (d[1] * s[0] - off * s[1]) / det;
    x[last] = (d[0] * s[1] - off * s[0]) / det;
  } else if (forward) {
    x[first] = solve_one(s[0], d[0]);
    x[last] = solve_one(s[1] - off * x[first], d[1]);
  } else {
    x[last] = solve_one(s[1], d[1]);
    x[first] = solve_one(s[0] - off * x[last], d[0]);
  }
}

/// A level of at least this many unknowns is swept, and multiplied by, on two threads (where its
/// unknowns come in halves: MultilevelSolver's `halves`): below it a thread's start costs more than
/// half the sweep saves.
constexpr int kTwoThreadsFrom = 50000;

}  // namespace

/// How a level's sweeps and products run: its unknowns' blocks (one vertex's, vertex_blocks) and,
/// where it runs on two threads, the first unknown of its second half (at a block's start) and the
/// entries between the halves.
struct MultilevelSolver::Sweeps {
  struct Crossing {
    int entry, row, column;
  };
  std::vector<int> start;           // vertex_blocks
  int middle = -1;                  // the second half's first unknown; -1: one thread
  int middle_block = 0;             // the second half's first block
  std::vector<Crossing> crossings;  // the lower triangle's entries from the first half's columns to the second half's rows

  /// `vertex` per unknown; `halves`: whether the level may run on two threads (its unknowns numbered
  /// so that each half of them is one region of the mesh).
  Sweeps(const Matrix& pattern, const std::vector<uint32_t>& vertex, bool halves) : start(vertex_blocks(vertex)) {
    if (!halves || pattern.cols() < kTwoThreadsFrom) return;
    middle_block = int(std::lower_bound(start.begin(), start.end(), int(pattern.cols() / 2)) - start.begin());
    middle = start[size_t(middle_block)];
    const int* outer = pattern.outerIndexPtr();
    const int* inner = pattern.innerIndexPtr();
    for (int c = 0; c < middle; ++c)
      for (int p = outer[c]; p < outer[c + 1]; ++p)
        if (inner[p] >= middle) crossings.push_back({p, inner[p], c});
  }

  bool two_threads() const { return middle >= 0; }
  /// The blocks of half h (0: all blocks on one thread): [first, end).
  int first_block(int h) const { return h == 0 ? 0 : middle_block; }
  int end_block(int h) const { return h == 0 && two_threads() ? middle_block : int(start.size()) - 1; }
  /// The rows of half h end before this.
  int end_row(int h) const { return h == 0 && two_threads() ? middle : start.back(); }
};

namespace {

using Sweeps = MultilevelSolver::Sweeps;

/// One half's part of a block Gauss-Seidel sweep (block_sweep): acc already holds, per row of the
/// half, what the other half contributes to it.
void sweep_half(const Matrix& a, const Sweeps& sw, int half, const Eigen::VectorXd& b, Eigen::VectorXd& x, Eigen::VectorXd& acc,
                bool forward) {
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  const int end_row = sw.end_row(half), first_block = sw.first_block(half), end_block = sw.end_block(half);
  // Column k's rows are sorted: those of the half after the block end at end_row.
  auto below_block = [&](int first, int last, auto&& f) {
    for (int k = first; k <= last; ++k)
      for (int p = outer[k]; p < outer[k + 1] && inner[p] < end_row; ++p)
        if (inner[p] > last) f(k, inner[p], value[p]);
  };
  const auto block = [&](int blk, auto&& f) { f(sw.start[size_t(blk)], sw.start[size_t(blk) + 1] - 1); };
  if (!forward)
    for (int blk = first_block; blk < end_block; ++blk)
      block(blk, [&](int first, int last) { below_block(first, last, [&](int k, int r, double v) { acc[r] += v * x[k]; }); });
  for (int t = first_block; t < end_block; ++t) {
    block(forward ? t : first_block + end_block - 1 - t, [&](int first, int last) {
      double s[2] = {0, 0}, d[2] = {1, 1}, off = 0;
      for (int k = first; k <= last; ++k) {
        s[k - first] = b[k] - acc[k];
        for (int p = outer[k]; p < outer[k + 1]; ++p)
          if (inner[p] == k)
            d[k - first] = value[p];
          else if (inner[p] <= last)
            off = value[p];
      }
      below_block(first, last, [&](int k, int r, double v) { s[k - first] -= v * x[r]; });
      solve_block(first, last, s, d, off, forward, x);
      if (forward) below_block(first, last, [&](int k, int r, double v) { acc[r] += v * x[k]; });
    });
  }
}

/// One block Gauss-Seidel sweep of a x = b (a: lower triangle) from x, the blocks (vertex_blocks) in
/// increasing order (forward) or decreasing: each block's unknowns solved for together (a vertex's u
/// and v are coupled strongly where its triangles shear), the others as they stand. acc[i] holds
/// row i's part to the left of its block, which the lower triangle stores in the columns before it:
/// gathered as the sweep goes where it goes forward (from the new values), from the values before the
/// sweep where it goes backward (those unknowns are solved for after i). The backward sweep is the
/// forward one's transpose, so the two around a coarse correction make a symmetric preconditioner.
/// On two threads (Sweeps), each half is swept so by its own, the other half's unknowns taken at
/// their values before the sweep (gathered into acc first): still each other's transpose.
void block_sweep(const Matrix& a, const Sweeps& sw, const Eigen::VectorXd& b, Eigen::VectorXd& x, Eigen::VectorXd& acc, bool forward) {
  acc.setZero();
  if (!sw.two_threads()) {
    sweep_half(a, sw, 0, b, x, acc, forward);
    return;
  }
  const double* value = a.valuePtr();
  for (const Sweeps::Crossing& e : sw.crossings) {
    acc[e.row] += value[e.entry] * x[e.column];
    acc[e.column] += value[e.entry] * x[e.row];
  }
  tbb::parallel_invoke([&] { sweep_half(a, sw, 0, b, x, acc, forward); }, [&] { sweep_half(a, sw, 1, b, x, acc, forward); });
}

/// y = a x (a: the lower triangle of a symmetric matrix). On two threads (sw given, in halves), the
/// first takes the first half's columns, its products into the second half's rows gathered in `spill`
/// (at least a's size), the second the rest; each sums in a fixed order.
void symmetric_product(const Matrix& a, const Sweeps* sw, const Eigen::VectorXd& x, Eigen::VectorXd& y, Eigen::VectorXd& spill) {
  if (!sw || !sw->two_threads()) {
    y.noalias() = a.selfadjointView<Eigen::Lower>() * x;
    return;
  }
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  const int n = int(a.cols()), split = sw->middle;
  const auto columns = [&](int from, int to, double* spilled) {
    for (int c = from; c < to; ++c) {
      double sum = y[c];
      for (int p = outer[c]; p < outer[c + 1]; ++p) {
        const int r = inner[p];
        if (r == c) {
          sum += value[p] * x[c];
          continue;
        }
        sum += value[p] * x[r];
        (r < to || !spilled ? y[r] : spilled[r]) += value[p] * x[c];
      }
      y[c] = sum;
    }
  };
  tbb::parallel_invoke(
      [&] {
        y.head(split).setZero();
        spill.segment(split, n - split).setZero();
        columns(0, split, spill.data());
      },
      [&] {
        y.tail(n - split).setZero();
        columns(split, n, nullptr);
      });
  y.tail(n - split) += spill.segment(split, n - split);
}

/// Per unknown, its aggregate (the pair of the vertex standing for its vertex and its axis); the
/// aggregates numbered by vertex in order of first appearance, a vertex's axes one after the other
/// (so the coarser level's sweeps take them as one block). `count` gets the aggregates' number,
/// `vertex` and `axis` each aggregate's.
std::vector<int> aggregate_unknowns(const std::vector<uint32_t>& stands_for, std::vector<uint32_t>& vertex, std::vector<uint8_t>& axis,
                                    int& count) {
  std::vector<uint8_t> axes(stands_for.size(), 0);  // per standing vertex, a bit per axis its aggregates have
  for (size_t k = 0; k < vertex.size(); ++k) axes[stands_for[vertex[k]]] |= uint8_t(1 << axis[k]);
  std::vector<int> id(2 * stands_for.size(), -1);
  std::vector<uint32_t> coarse_vertex;
  std::vector<uint8_t> coarse_axis;
  std::vector<int> coarse_of(vertex.size());
  for (size_t k = 0; k < vertex.size(); ++k) {
    const uint32_t v = stands_for[vertex[k]];
    if (id[2 * size_t(v) + axis[k]] < 0)
      for (uint8_t a = 0; a < 2; ++a)
        if (axes[v] & (1 << a)) {
          id[2 * size_t(v) + a] = int(coarse_vertex.size());
          coarse_vertex.push_back(v);
          coarse_axis.push_back(a);
        }
    coarse_of[k] = id[2 * size_t(v) + axis[k]];
  }
  count = int(coarse_vertex.size());
  vertex.swap(coarse_vertex);
  axis.swap(coarse_axis);
  return coarse_of;
}

}  // namespace

/// The step from one level to the next coarser: which aggregate each unknown is in, and the coarser
/// level's matrix, the Galerkin restriction P^T A P (P: 1 where an unknown is in an aggregate).
struct MultilevelSolver::Level {
  std::vector<int> coarse_of;  // per unknown of this level, its aggregate (the next level's unknown)
  Matrix coarse;               // the next level's matrix, lower triangle
  /// Per entry of this level's matrix, where it lands in `coarse`, times 2, plus 1 where it is an
  /// off-diagonal entry that lands on the diagonal (counted twice there: its transpose too).
  std::vector<int> slot;

  Level(const Matrix& a, std::vector<int> aggregate, int count) : coarse_of(std::move(aggregate)), coarse(count, count) {
    build_pattern(a, count);
    slot.resize(size_t(a.nonZeros()));
    for_each_entry(a, [&](int p, int row, int col, bool diagonal) {
      const int lo = std::min(row, col), hi = std::max(row, col);
      const int* begin = coarse.innerIndexPtr() + coarse.outerIndexPtr()[lo];
      const int* end = coarse.innerIndexPtr() + coarse.outerIndexPtr()[lo + 1];
      const int s = int(std::lower_bound(begin, end, hi) - coarse.innerIndexPtr());
      slot[size_t(p)] = 2 * s + (row == col && !diagonal ? 1 : 0);
    });
  }

  /// The coarse values from a's (same pattern as at construction).
  void restrict_values(const Matrix& a) {
    double* to = coarse.valuePtr();
    std::fill(to, to + coarse.nonZeros(), 0.0);
    const double* from = a.valuePtr();
    for (size_t p = 0; p < slot.size(); ++p) to[slot[p] >> 1] += (slot[p] & 1 ? 2.0 : 1.0) * from[p];
  }

 private:
  /// Calls f(entry, coarse row, coarse column, whether the entry is on a's diagonal) for each entry of a.
  template <class F>
  void for_each_entry(const Matrix& a, F&& f) const {
    for (int c = 0; c < a.cols(); ++c)
      for (int p = a.outerIndexPtr()[c]; p < a.outerIndexPtr()[c + 1]; ++p) {
        const int r = a.innerIndexPtr()[p];
        f(p, coarse_of[size_t(r)], coarse_of[size_t(c)], r == c);
      }
  }

  /// coarse's lower-triangle pattern: each coarse column's rows bucketed (a counting sort of the
  /// entries by coarse column), then sorted and made unique per column.
  void build_pattern(const Matrix& a, int count) {
    std::vector<int> start(size_t(count) + 1, 0);
    for_each_entry(a, [&](int, int row, int col, bool) { ++start[size_t(std::min(row, col)) + 1]; });
    for (int c = 0; c < count; ++c) start[size_t(c) + 1] += start[size_t(c)];
    std::vector<int> rows(size_t(start.back())), fill(start.begin(), start.end() - 1);
    for_each_entry(a, [&](int, int row, int col, bool) { rows[size_t(fill[size_t(std::min(row, col))]++)] = std::max(row, col); });
    int* outer = coarse.outerIndexPtr();
    outer[0] = 0;
    size_t kept = 0;
    for (int c = 0; c < count; ++c) {
      auto begin = rows.begin() + start[size_t(c)], end = rows.begin() + start[size_t(c) + 1];
      std::sort(begin, end);
      end = std::unique(begin, end);
      for (auto it = begin; it != end; ++it) rows[kept++] = *it;
      outer[c + 1] = int(kept);
    }
    coarse.resizeNonZeros(Eigen::Index(kept));
    std::copy(rows.begin(), rows.begin() + std::ptrdiff_t(kept), coarse.innerIndexPtr());
    std::fill(coarse.valuePtr(), coarse.valuePtr() + kept, 0.0);
  }
};

/// One solve's vectors per level: right-hand side, solution, residual and a sweep's accumulator;
/// and the products' first thread's spill (symmetric_product), one for every level.
struct MultilevelSolver::Workspace {
  std::vector<Eigen::VectorXd> b, x, r, acc;
  Eigen::VectorXd spill;
};

MultilevelSolver::MultilevelSolver(const Matrix& pattern, const std::vector<uint32_t>& unknown_vertex,
                                   const std::vector<uint8_t>& unknown_axis, const VertexAggregates& aggregates, bool halves) {
  std::vector<uint32_t> vertex = unknown_vertex;
  std::vector<uint8_t> axis = unknown_axis;
  const Matrix* a = &pattern;
  for (const std::vector<uint32_t>& stands_for : aggregates.levels) {
    std::vector<uint32_t> next_vertex = vertex;
    std::vector<uint8_t> next_axis = axis;
    int count = 0;
    std::vector<int> coarse_of = aggregate_unknowns(stands_for, next_vertex, next_axis, count);
    if (count > kMinCoarsening * double(a->cols())) continue;
    sweeps_.emplace_back(*a, vertex, halves);
    levels_.push_back(std::make_unique<Level>(*a, std::move(coarse_of), count));
    vertex.swap(next_vertex);
    axis.swap(next_axis);
    a = &levels_.back()->coarse;
  }
  coarsest_.analyzePattern(*a);
}

MultilevelSolver::~MultilevelSolver() = default;

bool MultilevelSolver::update(const Matrix& a) {
  fine_ = &a;
  const Matrix* from = &a;
  for (const auto& level : levels_) {
    level->restrict_values(*from);
    from = &level->coarse;
  }
  coarsest_.factorize(*from);
  // A positive semi-definite system (a projected Hessian) can leave the coarsest level singular in
  // rounding: its diagonal raised a little is still a fine preconditioner.
  for (double lift = 1e-12; coarsest_.info() != Eigen::Success && lift < 1e-3; lift *= 100) {
    Matrix lifted = *from;
    for (int c = 0; c < lifted.cols(); ++c) lifted.coeffRef(c, c) *= 1 + lift;
    coarsest_.factorize(lifted);
  }
  return coarsest_.info() == Eigen::Success;
}

std::vector<size_t> MultilevelSolver::level_sizes() const {
  std::vector<size_t> sizes{size_t(fine_ ? fine_->cols() : 0)};
  for (const auto& level : levels_) sizes.push_back(size_t(level->coarse.cols()));
  return sizes;
}

void MultilevelSolver::v_cycle(size_t k, const Eigen::VectorXd& b, Eigen::VectorXd& x, Workspace& work) const {
  if (k == levels_.size()) {
    x = coarsest_.solve(b);
    return;
  }
  const Matrix& a = k == 0 ? *fine_ : levels_[k - 1]->coarse;
  const Level& level = *levels_[k];
  x.setZero();
  block_sweep(a, sweeps_[k], b, x, work.acc[k], true);
  Eigen::VectorXd& r = work.r[k];
  symmetric_product(a, &sweeps_[k], x, r, work.spill);
  r = b - r;
  Eigen::VectorXd& coarse_b = work.b[k + 1];
  coarse_b.setZero();
  for (Eigen::Index i = 0; i < r.size(); ++i) coarse_b[level.coarse_of[size_t(i)]] += r[i];
  Eigen::VectorXd& coarse_x = work.x[k + 1];
  v_cycle(k + 1, coarse_b, coarse_x, work);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += coarse_x[level.coarse_of[size_t(i)]];
  block_sweep(a, sweeps_[k], b, x, work.acc[k], false);
}

IterativeSolve MultilevelSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int max_iterations) const {
  IterativeSolve out;
  const Matrix& a = *fine_;
  const double b_norm = b.norm();
  if (x.size() != b.size()) x = Eigen::VectorXd::Zero(b.size());
  if (b_norm == 0) {
    x.setZero();
    out.converged = true;
    return out;
  }
  Workspace work;
  const size_t nl = levels_.size() + 1;
  for (auto* vectors : {&work.b, &work.x, &work.r, &work.acc}) {
    vectors->resize(nl);
    for (size_t k = 0; k < nl; ++k) (*vectors)[k].resize(k == 0 ? a.cols() : levels_[k - 1]->coarse.cols());
  }
  if (!sweeps_.empty() && sweeps_[0].two_threads()) work.spill.resize(a.cols());
  // The fine level's product, on two threads where its sweeps are.
  const Sweeps* fine_sweeps = sweeps_.empty() ? nullptr : &sweeps_[0];
  Eigen::VectorXd ap(b.size());
  symmetric_product(a, fine_sweeps, x, ap, work.spill);
  Eigen::VectorXd r = b - ap, z(b.size()), p;
  v_cycle(0, r, z, work);
  p = z;
  double rz = r.dot(z);
  for (; out.iterations < max_iterations; ++out.iterations) {
    out.relative_residual = r.norm() / b_norm;
    if (!std::isfinite(out.relative_residual)) return out;
    if (out.relative_residual <= tolerance) {
      out.converged = true;
      return out;
    }
    symmetric_product(a, fine_sweeps, p, ap, work.spill);
    const double curvature = p.dot(ap);
    if (!(curvature > 0)) return out;  // a is not positive definite along p
    const double alpha = rz / curvature;
    x += alpha * p;
    r -= alpha * ap;
    v_cycle(0, r, z, work);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  out.relative_residual = r.norm() / b_norm;
  out.converged = out.relative_residual <= tolerance;
  return out;
}

}  // namespace tightex
