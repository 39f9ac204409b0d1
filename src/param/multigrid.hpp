// Conjugate gradients preconditioned by a multilevel V-cycle: the iterative solver of the multilevel
// map's systems on the full mesh, where a sparse Cholesky factor would need memory far beyond the
// matrix's own.
#pragma once
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cstdint>
#include <memory>
#include <vector>

namespace tightex {

/// Nested aggregates of a mesh's vertices, finest first: levels[k][v] is the vertex that stands for v at
/// level k (v itself where it is still there), each level coarser than the one before, and every
/// vertex standing for others at level k standing for itself at every level before (the half-edge
/// collapses of coarsen_disk_in_steps, which record them).
struct VertexAggregates {
  std::vector<std::vector<uint32_t>> levels;
};

/// The outcome of MultilevelSolver::solve.
struct IterativeSolve {
  int iterations = 0;
  double relative_residual = 0;  // |b - a x| / |b| at the end
  bool converged = false;        // the residual reached the tolerance (false also on a breakdown)
};

/// A symmetric positive definite (or semi-definite: a projected Hessian) system over a mesh's vertex
/// coordinates (unknown k: coordinate unknown_axis[k] of vertex unknown_vertex[k]), solved by
/// conjugate gradients preconditioned by one V-cycle per iteration: the system's Galerkin
/// restrictions to the aggregates of each level (the unknowns of one axis at the vertices one vertex
/// stands for summed into one; piecewise constant prolongation), a forward block Gauss-Seidel sweep
/// (a vertex's coordinates one block) before the coarser level's correction and a backward one after
/// it (so the preconditioner is symmetric), the coarsest level solved by a sparse Cholesky
/// factorisation. The pattern is fixed at construction; the values may change (update) between solves.
/// Where the unknowns are numbered in nested dissection's order (`halves`), a level of at least
/// kTwoThreadsFrom (multigrid.cpp) unknowns is swept on two threads, one per half of its unknowns (two regions of the
/// mesh with a short border between them, contiguous in memory): each thread's sweep takes the other
/// half's unknowns as they stood before the sweep, so the smoother couples the halves as Jacobi does
/// and each half within itself as Gauss-Seidel does; its matrix products run on two threads too. The
/// result depends only on the inputs, not on timing.
/// Memory: the coarser levels' matrices (about a third of the system's entries), one int per entry
/// of every level but the coarsest (where it lands in the next), and a few vectors per solve.
class MultilevelSolver {
 public:
  using Matrix = Eigen::SparseMatrix<double>;  // the lower triangle, compressed, rows sorted in each column

  /// `pattern`: the system's lower triangle (its values unused). Levels of `aggregates` that merge
  /// fewer than a tenth of the unknowns left are skipped. `halves`: the unknowns are numbered in the
  /// order of nested_dissection_order's vertices, so that the large levels' sweeps may run in halves
  /// on two threads (the aggregates, numbered as their unknowns first appear, keep that order).
  MultilevelSolver(const Matrix& pattern, const std::vector<uint32_t>& unknown_vertex, const std::vector<uint8_t>& unknown_axis,
                   const VertexAggregates& aggregates, bool halves = false);
  ~MultilevelSolver();
  MultilevelSolver(const MultilevelSolver&) = delete;
  MultilevelSolver& operator=(const MultilevelSolver&) = delete;

  /// Takes the values of `a` (the pattern given at construction): the coarser levels' matrices and the
  /// coarsest factorisation. False if that factorisation fails (a not positive definite).
  bool update(const Matrix& a);

  /// Solves a x = b (a: the matrix of the last update, which must still exist) from x's values, until
  /// |b - a x| <= tolerance |b| or after max_iterations; x = 0 where b is. Safe to call from several
  /// threads at once.
  IterativeSolve solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int max_iterations) const;

  /// Unknowns per level, finest first (the last solved directly).
  std::vector<size_t> level_sizes() const;

  struct Sweeps;  // how a level's sweeps and products run (multigrid.cpp)

 private:
  struct Level;
  struct Workspace;
  void v_cycle(size_t level, const Eigen::VectorXd& b, Eigen::VectorXd& x, Workspace& work) const;

  const Matrix* fine_ = nullptr;
  std::vector<std::unique_ptr<Level>> levels_;  // levels_[k]: from level k to k + 1 (level 0: the system)
  std::vector<Sweeps> sweeps_;                  // per level but the coarsest, how its sweeps and products run
  Eigen::SimplicialLLT<Matrix, Eigen::Lower> coarsest_;
};

}  // namespace tightex
