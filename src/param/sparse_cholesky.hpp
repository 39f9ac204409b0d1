// The sparse Cholesky factorisation of the map's symmetric positive definite systems (CHOLMOD).
#pragma once
#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <vector>

#include "param/square_map_options.hpp"

namespace tightex {

namespace detail {

/// Eigen's CHOLMOD wrapper, with the analysis also from a given fill-reducing order (Eigen's own
/// analyzePattern always lets CHOLMOD order the system), or in the matrix's own order.
class OrderedCholmod : public Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  /// CHOLMOD's symbolic analysis of `a` in `order` (order[k]: the unknown eliminated k-th; CHOLMOD
  /// may still postorder it).
  void analyzePatternInOrder(const Eigen::SparseMatrix<double>& a, std::vector<int> order) {
    analyze(a, CHOLMOD_GIVEN, order.data(), true);
  }
  /// CHOLMOD's symbolic analysis of `a` eliminated in its own order, not postordered: for a matrix
  /// permuted into an analysed factor's order (permutation()), which CHOLMOD then factorises without
  /// copying it.
  void analyzePatternAsOrdered(const Eigen::SparseMatrix<double>& a) { analyze(a, CHOLMOD_NATURAL, nullptr, false); }
  /// Allocates a supernodal factor's numeric storage, as its first factorisation would, and writes it
  /// on every core. Each fresh page costs a fault, about 10 us on a paravirtualised VM (1.4 s of sys
  /// for the 415 MB factor of the 854k-face symmetric Dirichlet system), which the factorisation would
  /// take one by one on its one core. Nothing where the factor has its storage already, is simplicial,
  /// or holds fewer than 4M entries (32 MB).
  void allocate_supernodal_factor();
  /// The analysed factor's order: permutation()[k] is the unknown eliminated k-th. Null before an analysis.
  const int* permutation() const { return m_cholmodFactor ? static_cast<const int*>(m_cholmodFactor->Perm) : nullptr; }

 private:
  void analyze(const Eigen::SparseMatrix<double>& a, int ordering, int* order, bool postorder) {
    cholmod_common& common = cholmod();
    if (m_cholmodFactor) {
      cholmod_free_factor(&m_cholmodFactor, &common);
      m_cholmodFactor = nullptr;
    }
    cholmod_sparse view = Eigen::viewAsCholmod(a.selfadjointView<Eigen::Lower>());
    const int methods = common.nmethods, was_ordering = common.method[0].ordering, was_postorder = common.postorder;
    common.nmethods = 1;
    common.method[0].ordering = ordering;
    common.postorder = postorder;
    m_cholmodFactor = cholmod_analyze_p(&view, order, nullptr, 0, &common);
    common.nmethods = methods;
    common.method[0].ordering = was_ordering;
    common.postorder = was_postorder;
    m_isInitialized = true;
    m_info = m_cholmodFactor ? Eigen::Success : Eigen::NumericalIssue;
    m_analysisIsOk = m_cholmodFactor != nullptr;
    m_factorizationIsOk = false;
  }
};

}  // namespace detail

/// A fill-reducing order of a mesh's vertices: METIS's nested dissection of its edge graph (through
/// CHOLMOD), order[k] the vertex eliminated k-th. Every system of a map is over some of the vertices
/// (a Laplacian's unknowns) or their coordinates (a symmetric Dirichlet step's): restricted to those
/// (order_of_unknowns), one order serves them all, computed once per mesh, where CHOLMOD's own
/// minimum degree ordering (AMD) orders each system again and, on a large planar mesh, leaves 2.7x
/// the flops (BENCHMARKS.md, "Scale"). Empty where METIS fails.
std::vector<int> nested_dissection_order(const Surface& mesh);

/// nested_dissection_order of `mesh` where it has at least `from` vertices (and METIS succeeds); null
/// otherwise: CHOLMOD then orders each system itself.
std::shared_ptr<const std::vector<int>> vertex_order_from(const Surface& mesh, size_t from);

/// `vertex_order` restricted to a system's unknowns: unknown[k * per_vertex + j] is vertex k's j-th
/// unknown (per_vertex 1: a Laplacian's; 2: u and v), -1 where it has none.
std::vector<int> order_of_unknowns(const std::vector<int>& vertex_order, const std::vector<int>& unknown, int per_vertex);

/// Serialises the supernodal factorisations and solves of all threads. The components are mapped in
/// parallel, and a BLAS built without locking (Debian's serial OpenBLAS) returns garbage when two
/// threads call it at once. One BLAS call at a time is correct with any BLAS, and costs little: a
/// threaded BLAS uses every core within the call.
std::mutex& blas_mutex();

/// Serialises the calls that may reach METIS: its nested dissection and CHOLMOD's analyses in an order
/// of its own choosing (which try METIS where minimum degree leaves much fill). Debian's METIS draws
/// from the C library's rand(), one sequence for the whole process, reseeded at each call: two orders
/// found at once interleave their draws, and each then follows the other's timing (a 10M-face model
/// cut into two pieces mapped side by side gave other texture coordinates from run to run).
std::mutex& metis_mutex();

/// Makes the dense kernels under CHOLMOD run on the calling thread only: OpenBLAS's thread pool (for
/// the process, once) and libgomp's teams (for this thread: libgomp keeps those settings per thread).
/// The components and shape probes are mapped in parallel already, and the BLAS calls are serialised (blas_mutex), so the kernels' own
/// threads mostly spin and yield in the kernel (BENCHMARKS.md, "Where the default run's time goes"). Looked up by name: a no-op with a BLAS
/// or OpenMP runtime that lacks these functions. On such a thread the regions CHOLMOD opens skip libgomp
/// altogether (GOMP_parallel in sparse_cholesky.cpp).
void use_serial_dense_kernels();

/// Eigen's CHOLMOD wrapper: supernodal from supernodal_from unknowns on; below, as CHOLMOD's analysis
/// chooses (supernodal where the factor is dense: a simplicial factorisation of a fill-heavy system of
/// 30k unknowns is 2x slower; docs/decisions.md).
class SparseCholesky {
 public:
  using Matrix = Eigen::SparseMatrix<double>;

  /// CHOLMOD's own printing is off: a failed factorisation is reported through factorize() / solve()
  /// and handled by the caller (a retry, the fallback), and `tightex -q` prints nothing but errors.
  explicit SparseCholesky(long supernodal_from = kSupernodalFrom) : supernodal_from_(supernodal_from) { solver_.cholmod().print = 0; }
  /// `order` (optional): the fill-reducing order to analyse in (order_of_unknowns), instead of CHOLMOD's.
  void analyzePattern(const Matrix& a, const std::vector<int>* order = nullptr) {
    use_serial_dense_kernels();
    const bool forced = a.rows() >= supernodal_from_;
    solver_.setMode(forced ? Eigen::CholmodSupernodalLLt : Eigen::CholmodAuto);
    if (!forced) {
      // A simplicial factor as LL' (Eigen's CholmodAuto would leave CHOLMOD's LDL'), so that a
      // system that is not numerically positive definite fails to factorise, as it always has.
      solver_.cholmod().final_asis = 0;
      solver_.cholmod().final_ll = 1;
    }
    const auto analyse = [&] {
      if (order && order->size() == size_t(a.rows())) {
        solver_.analyzePatternInOrder(a, *order);
      } else if (!analyse_by_minimum_degree(a)) {
        const std::lock_guard<std::mutex> lock(metis_mutex());
        solver_.analyzePattern(a);
      }
    };
    analyse();
    permutation_.clear();
    if (forced && solver_.info() == Eigen::Success && !permute_into_factor_order(a)) {
      permutation_.clear();  // analysed as ordered failed: CHOLMOD permutes at each factorisation
      analyse();
    }
    analysed_ = solver_.info() == Eigen::Success;
    // CHOLMOD's own choice below the size: supernodal where the factor is dense enough for its
    // column blocks to pay (flops per factor entry at least supernodal_switch).
    const cholmod_common& c = solver_.cholmod();
    supernodal_ = forced || (c.lnz > 0 && c.fl / c.lnz >= c.supernodal_switch);
    factor_entries_ = analysed_ ? c.lnz : 0;
  }
  /// False if CHOLMOD failed (a not positive definite, numerically), or its analysis had (out of
  /// memory, an order that is not a permutation): there is no factor to compute then.
  bool factorize(const Matrix& a) {
    if (!analysed_) return false;
    use_serial_dense_kernels();
    if (supernodal_) solver_.allocate_supernodal_factor();
    std::unique_lock<std::mutex> lock(blas_mutex(), std::defer_lock);
    if (supernodal_) lock.lock();
    if (permutation_.empty()) {
      solver_.factorize(a);
    } else {
      const double* from = a.valuePtr();
      double* to = permuted_.valuePtr();
      for (size_t k = 0; k < slot_.size(); ++k) to[slot_[k]] = from[k];
      solver_.factorize(permuted_);
    }
    return solver_.info() == Eigen::Success;
  }
  /// x = a^-1 b with the factorisation of `a` (factorize(a) first). False, and x unspecified, if CHOLMOD
  /// failed, x is not finite, or x does not solve the system (solves()).
  template <class B, class X>
  bool solve(const Matrix& a, const Eigen::MatrixBase<B>& b, X& x) const {
    {
      std::unique_lock<std::mutex> lock(blas_mutex(), std::defer_lock);
      if (supernodal_) lock.lock();
      if (permutation_.empty()) {
        x = solver_.solve(b);
      } else {
        using Dense = Eigen::Matrix<double, Eigen::Dynamic, B::ColsAtCompileTime>;
        Dense permuted_b(b.rows(), b.cols());
        for (Eigen::Index k = 0; k < b.rows(); ++k) permuted_b.row(k) = b.row(permutation_[size_t(k)]);
        const Dense permuted_x = solver_.solve(permuted_b);
        x.resize(b.rows(), b.cols());
        for (Eigen::Index k = 0; k < b.rows(); ++k) x.row(permutation_[size_t(k)]) = permuted_x.row(k);
      }
    }
    return solver_.info() == Eigen::Success && x.allFinite() && solves(a, x, b);
  }

  /// Whether x solves a x = b (a: lower triangle stored) as a backward-stable factorisation would: the
  /// normwise backward error |a x - b| / (|a| |x| + |b|) (infinity norms) at most 1e-8, far above the
  /// rounding of a sound solve (about 1e-16 times a small multiple of the size), far below a wrong one
  /// (a solution 1% off gives about 1e-2). Catches a factorisation that went wrong without saying so,
  /// such as the finite garbage of a BLAS unsafe for concurrent calls.
  template <class X, class B>
  static bool solves(const Matrix& a, const Eigen::MatrixBase<X>& x, const Eigen::MatrixBase<B>& b) {
    if (a.rows() == 0) return true;
    const double residual = (a.selfadjointView<Eigen::Lower>() * x - b).template lpNorm<Eigen::Infinity>();
    // |a|_inf (largest absolute row sum) from the lower triangle: an off-diagonal entry is in two rows.
    Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(a.rows());
    for (int col = 0; col < a.outerSize(); ++col)
      for (Matrix::InnerIterator it(a, col); it; ++it) {
        row_sum(it.row()) += std::abs(it.value());
        if (it.row() != col) row_sum(col) += std::abs(it.value());
      }
    const double scale = row_sum.maxCoeff() * x.template lpNorm<Eigen::Infinity>() + b.template lpNorm<Eigen::Infinity>();
    return residual <= 1e-8 * scale;
  }
  bool supernodal() const { return supernodal_; }
  /// Entries of the analysed factor (CHOLMOD's count; 0 before an analysis).
  double factor_entries() const { return factor_entries_; }
  /// Whether the system is factorised as a copy permuted into the factor's order (supernodal systems).
  bool factorises_permuted_copy() const { return !permutation_.empty(); }

 private:
  /// CHOLMOD's own order where it is AMD's, found without METIS and so without metis_mutex (a
  /// multilevel map's fine order holds it for seconds, and the maps beside it waited on it for
  /// nothing): its default tries AMD and goes on to METIS only where AMD's factor is costly (flops per
  /// factor entry at least 500 and factor entries per entry of a at least 5), keeping AMD's order
  /// otherwise. False where it would go on, or the analysis failed: the caller then analyses as CHOLMOD
  /// does by default, under the lock.
  bool analyse_by_minimum_degree(const Matrix& a) {
    cholmod_common& c = solver_.cholmod();
    const int methods = c.nmethods, first_ordering = c.method[0].ordering;
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_AMD;
    solver_.analyzePattern(a);
    c.nmethods = methods;
    c.method[0].ordering = first_ordering;
    if (solver_.info() != Eigen::Success || !(c.lnz > 0)) return false;
    return c.fl / c.lnz < 500 || c.lnz / double(a.nonZeros()) < 5;
  }

  /// `a` permuted into the analysed factor's order (permuted_, where each of a's values lands in
  /// slot_) and analysed again as ordered: each factorisation then scatters the values, and CHOLMOD
  /// copies nothing (with its own permutation it makes two permuted transposes of a lower-triangle
  /// system every time: 13% of the page faults at 3.4M faces, BENCHMARKS.md). False if that analysis
  /// fails or `a` is not compressed.
  bool permute_into_factor_order(const Matrix& a);

  detail::OrderedCholmod solver_;
  long supernodal_from_;
  bool supernodal_ = false;
  bool analysed_ = false;
  double factor_entries_ = 0;
  std::vector<int> permutation_;  // the factor's order (permutation_[k]: the unknown at k); empty: CHOLMOD's own path
  Matrix permuted_;
  std::vector<int> slot_;
};

}  // namespace tightex
