// Alg. 2 of the paper (§4.2): the harmonic map of a disk with its boundary fixed.
#pragma once
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "param/square_map_options.hpp"

namespace tightex {

class SparseCholesky;
class MultilevelSolver;
struct VertexAggregates;

/// The edge weights of the Laplacian: cotangent (the paper's), cotangent with negative weights clamped
/// to 1e-3 of the mean absolute weight (positive, so the map of a convex boundary cannot fold:
/// Tutte/Floater), or uniform (Tutte's, for numerically extreme meshes).
enum class EdgeWeights { kCotangent, kClamped, kUniform };

/// The weighting's name in SquareMapStats::weights: "cotangent", "clamped-cotangent" or "uniform".
std::string_view to_string(EdgeWeights kind);

/// Per edge, stored on the smaller of its two halfedges (boundary edges on their one halfedge; the
/// other entries 0): the Laplacian weight of `kind`. Non-finite cotangents count as 0. `negative`
/// (optional) gets the number of edges whose cotangent weight is negative.
std::vector<double> edge_weights(const Surface& mesh, EdgeWeights kind, size_t* negative = nullptr);

/// 1 for every vertex in `boundary`, 0 elsewhere.
std::vector<char> boundary_mask(size_t num_vertices, const std::vector<uint32_t>& boundary);

/// Solves the Dirichlet problem of a weighted Laplacian (one sparse Cholesky factorisation for u and
/// v). The weights may change between solves, never the sparsity pattern: the symbolic analysis is
/// done at the first solve and reused.
class DirichletSolver {
 public:
  /// vertex_order (optional): nested_dissection_order of the meshes solved, the systems' fill-reducing order.
  explicit DirichletSolver(long supernodal_from = kSupernodalFrom, std::shared_ptr<const std::vector<int>> vertex_order = {});
  ~DirichletSolver();
  DirichletSolver(const DirichletSolver&) = delete;
  DirichletSolver& operator=(const DirichletSolver&) = delete;

  /// Overwrites uv of the vertices not on_boundary with the solution of the Laplace equation
  /// (weights: as edge_weights returns them), the on_boundary ones held where uv has them. False, and
  /// uv unchanged, if the factorisation or the solve failed numerically.
  bool solve(const Surface& mesh, const std::vector<double>& weights, const std::vector<char>& on_boundary, std::vector<Vec2>& uv);

  /// Builds the system's pattern for `mesh` with `on_boundary` held, and analyses it: what the first
  /// solve with them would do, done ahead (for a caller with a core to spare). A solve with other
  /// vertices held builds its own again.
  void prepare(const Surface& mesh, const std::vector<char>& on_boundary);

  /// From now on solves by conjugate gradients preconditioned over `aggregates` of the mesh's vertices
  /// (MultilevelSolver), from the values uv holds, to a relative residual of `tolerance`, instead of
  /// factorising (memory linear in the mesh; a start near the solution, as a reweighting step's, saves
  /// iterations). Where that does not converge, the solve factorises after all.
  void solve_iteratively(std::shared_ptr<const VertexAggregates> aggregates, double tolerance);

 private:
  struct Laplacian;
  void analyse();
  /// The iterative solve from x's values; false (x unspecified) where either coordinate does not converge.
  bool solve_by_iterations(const Eigen::MatrixX2d& rhs, Eigen::MatrixX2d& x);
  std::shared_ptr<const VertexAggregates> aggregates_;
  double tolerance_ = 0;
  std::unique_ptr<MultilevelSolver> multilevel_;
  bool cholesky_analysed_ = false;
  std::unique_ptr<SparseCholesky> cholesky_;
  std::shared_ptr<const std::vector<int>> vertex_order_;
  std::unique_ptr<Laplacian> laplacian_;  // the pattern, built at the first solve
};

/// Alg. 2, in the manner of libigl's harmonic(V, F, b, bc, k): the map of `mesh` whose vertex
/// boundary[i] sits at boundary_uv[i] and whose other vertices solve the Laplace equation with
/// `weights` (edge_weights). uv gets one entry per vertex. Returns false if the solve failed
/// numerically; uv then holds the boundary and the origin elsewhere. Requires boundary_uv.size() ==
/// boundary.size(). Guarantees nothing about folds: with positive weights and a convex boundary
/// (the square) there are none in exact arithmetic.
bool harmonic_map(const Surface& mesh, const std::vector<uint32_t>& boundary, const std::vector<Vec2>& boundary_uv,
                  const std::vector<double>& weights, DirichletSolver& solver, std::vector<Vec2>& uv);

/// The outcome of fold_free_harmonic_map.
struct HarmonicAttempts {
  std::vector<Vec2> uv;                   // the map of the last weighting tried
  std::optional<EdgeWeights> weights;     // the last weighting that solved; none if none did
  std::vector<double> positive_weights;   // the last positive weighting tried; empty if only cotangent was
  size_t flipped = 0;                     // folded triangles of the last weighting that solved
  size_t negative_weights = 0;            // edges whose cotangent weight is negative
  std::vector<size_t> folds_per_attempt;  // folded triangles of each weighting that solved, in order
  uint32_t crowded_vertex = kNone;        // a vertex of a triangle folded with the clamped weights
};

/// Alg. 2 with the fold-free fallbacks: harmonic_map with cotangent weights; if any triangle folds
/// (cotangent weights go negative on obtuse triangles), with the clamped weights, then uniform ones,
/// until one gives no fold. A triangle folded even with positive weights means the map crowded a
/// region below floating-point precision: crowded_vertex names one of its vertices. All attempts
/// share `solver` (one symbolic analysis).
HarmonicAttempts fold_free_harmonic_map(const Surface& mesh, const std::vector<uint32_t>& boundary, const std::vector<Vec2>& boundary_uv,
                                        DirichletSolver& solver);

}  // namespace tightex
