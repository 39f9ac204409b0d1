// The sparse Cholesky factorisation of the map's symmetric positive definite systems (CHOLMOD).
#pragma once
#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <mutex>

#include "param/param.hpp"

namespace tightex {

/// Serialises the supernodal factorisations and solves of all threads. The components are mapped in
/// parallel, and a BLAS built without locking (Debian's serial OpenBLAS) returns garbage when two
/// threads call it at once: two 100k-triangle components gave "matrix not positive definite" and a
/// folded map. One BLAS call at a time is correct with any BLAS, and costs little: a threaded BLAS
/// uses every core within the call.
std::mutex& blas_mutex();

/// Eigen's CHOLMOD wrapper, simplicial or supernodal by the system's size (chosen at analyzePattern;
/// kSupernodalFrom).
class SparseCholesky {
 public:
  using Matrix = Eigen::SparseMatrix<double>;

  explicit SparseCholesky(long supernodal_from = kSupernodalFrom) : supernodal_from_(supernodal_from) {}
  void analyzePattern(const Matrix& a) {
    supernodal_ = a.rows() >= supernodal_from_;
    solver_.setMode(supernodal_ ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
    solver_.analyzePattern(a);
  }
  void factorize(const Matrix& a) {
    std::unique_lock<std::mutex> lock(blas_mutex(), std::defer_lock);
    if (supernodal_) lock.lock();
    solver_.factorize(a);
  }
  template <class Rhs>
  Eigen::Matrix<double, Eigen::Dynamic, Rhs::ColsAtCompileTime> solve(const Eigen::MatrixBase<Rhs>& b) const {
    std::unique_lock<std::mutex> lock(blas_mutex(), std::defer_lock);
    if (supernodal_) lock.lock();
    return solver_.solve(b);
  }
  Eigen::ComputationInfo info() const { return solver_.info(); }
  bool supernodal() const { return supernodal_; }

 private:
  Eigen::CholmodDecomposition<Matrix, Eigen::Lower> solver_;
  long supernodal_from_;
  bool supernodal_ = false;
};

}  // namespace tightex
