// The sparse Cholesky factorisation of the map's symmetric positive definite systems (CHOLMOD).
#pragma once
#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

namespace tightex {

using SparseCholesky = Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower>;

/// From this many unknowns on, the supernodal factorisation (dense BLAS kernels on column blocks);
/// below it, the simplicial one. Measured (BENCHMARKS.md, "Large models"), cut+map seconds, default
/// map, simplicial -> supernodal with Debian's serial OpenBLAS: vase of 225k triangles 48.8 -> 24.2,
/// of 896k triangles 571 -> 122; 44k triangles 14.5 -> 9.0. With the reference BLAS the supernodal
/// one still wins at 225k (41.8 s). At meshroom's sizes (harmonic systems of 26k unknowns) the
/// simplicial one is as fast, and the maps there stay exactly as they were.
constexpr Eigen::Index kSupernodalFrom = 40000;

/// Call before analyzePattern: the factorisation kind for a system of `unknowns` rows.
inline void choose_factorisation(SparseCholesky& solver, Eigen::Index unknowns) {
  solver.setMode(unknowns >= kSupernodalFrom ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
}

}  // namespace tightex
