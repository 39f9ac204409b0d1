// The symmetric Dirichlet refinement (slim.hpp): from a fold-free map, minimise the symmetric
// Dirichlet energy of each triangle against its target shape (the 3D triangle scaled to its target UV
// area), with the boundary held. Each step solves the energy's projected Newton system (every face's
// Hessian made positive semi-definite in closed form), then a line search that never lets a triangle
// reach zero area. Where that system does not solve, the step is SLIM's (Scalable Locally Injective
// Maps, Rabinovich, Lipman, Sorkine-Hornung 2017: a reweighted Laplacian-like proxy), which has the
// same pattern. SLIM's steps alone stall short of the minimum: docs/maps.md.
#include "param/slim.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/eigen_vector.hpp"
#include "param/multigrid.hpp"
#include "param/sparse_cholesky.hpp"

namespace tightex {

namespace {

/// Cap on SLIM's squared weights, for a step whose system failed without it: a triangle squeezed to a
/// sliver in the start map gives weights of 1e28 and more, and the system fails to factorise. Capped,
/// it is well conditioned; the line search still takes only steps that lower the true energy. Not
/// applied to every step, as it changes the path of maps that solve without it. Chosen by
/// measurement: docs/decisions.md.
constexpr double kMaxWeight = 1e8;

/// The iterative solves of the steps' systems (a RefinementSystem with a MultilevelSolver): the
/// relative residual a step is solved to (an inexact Newton step: the line search makes any descent
/// direction safe; 1e-2 lost 0.3 dB of surface PSNR at 213k faces, 1e-3 none: BENCHMARKS.md, "Scale"),
/// and the iterations it may take.
constexpr double kStepTolerance = 1e-3;
constexpr int kStepIterations = 100;

/// A bounded coordinate held for a step (hold_pressed) is tied by a spring this many times its own
/// curvature: its step is then that much smaller than the pressure on it would make it.
constexpr double kHoldStiffness = 1e10;

using SpMat = Eigen::SparseMatrix<double>;
using Mat2 = Eigen::Matrix2d;

/// Per face: the gradients of the three hat functions on the target triangle, and its area.
struct TargetFrame {
  std::array<Vec2, 3> g;
  double area = 0;
};

std::vector<TargetFrame> target_frames(const Surface& m, const std::vector<double>& target, const std::vector<Vec2>& start,
                                       const std::vector<FaceShape>* shapes) {
  std::vector<TargetFrame> fr(m.num_faces());
  auto perp = [](const Vec2& v) { return Vec2(-v.y(), v.x()); };
  for (size_t f = 0; f < m.num_faces(); ++f) {
    if (shapes) {
      // The face's triangle in `shapes`, if it has a positive area there.
      const Vec2 &a = (*shapes)[f][0], &b = (*shapes)[f][1], &c = (*shapes)[f][2];
      const double area = signed_area(a, b, c);
      if (area > 0 && std::isfinite(area)) {
        fr[f].g = {perp(c - b) / (2 * area), perp(a - c) / (2 * area), perp(b - a) / (2 * area)};
        fr[f].area = area;
        continue;
      }
    }
    const Vec3 &a = m.positions[m.triangles[f][0]], &b = m.positions[m.triangles[f][1]], &c = m.positions[m.triangles[f][2]];
    const Vec3 e1 = b - a, e2 = c - a;
    const double l1 = e1.norm(), cross = e1.cross(e2).norm();
    if (!(target[f] > 0) || !std::isfinite(target[f])) continue;  // no target: the face does not count
    std::array<Vec2, 3> p;
    double area = target[f];
    if (l1 > 0 && cross > 0) {
      const double s = std::sqrt(target[f] / (0.5 * cross));
      p = {Vec2(0, 0), Vec2(s * l1, 0), Vec2(s * e1.dot(e2) / l1, s * cross / l1)};
    } else {
      // No 3D shape (a cap face over an S-shaped hole has zero area): its start shape in the map, at its
      // start area, is what it keeps. Without a frame such a face would have no energy to keep it open,
      // the step direction would collapse it, and the line search would shrink every step to nothing;
      // an equilateral frame of the target area would pull the hole's rim towards the cap's small target.
      const Vec2 u1 = start[m.triangles[f][1]] - start[m.triangles[f][0]], u2 = start[m.triangles[f][2]] - start[m.triangles[f][0]];
      const double ua = 0.5 * (u1.x() * u2.y() - u1.y() * u2.x());
      if (!(ua > 0) || !std::isfinite(ua)) continue;
      p = {Vec2(0, 0), u1, u2};
      area = ua;
    }
    const double area2 = 2.0 * area;
    fr[f].g = {perp(p[2] - p[1]) / area2, perp(p[0] - p[2]) / area2, perp(p[1] - p[0]) / area2};
    fr[f].area = area;
  }
  return fr;
}

Mat2 jacobian(const TargetFrame& fr, const Vec2& x0, const Vec2& x1, const Vec2& x2) {
  return as_eigen(x0) * as_eigen(fr.g[0]).transpose() + as_eigen(x1) * as_eigen(fr.g[1]).transpose() +
         as_eigen(x2) * as_eigen(fr.g[2]).transpose();
}

/// Signed-free SVD of a 2x2 matrix with positive determinant: J = U diag(sigma) V^T, U and V rotations,
/// sigma(0) >= sigma(1) > 0 (closed form: J = [a b; c d] splits into a similarity and an anti-similarity).
void svd2(const Mat2& J, Mat2& U, Vec2& sigma, Mat2& V) {
  const double e = 0.5 * (J(0, 0) + J(1, 1)), f = 0.5 * (J(0, 0) - J(1, 1));
  const double g = 0.5 * (J(1, 0) + J(0, 1)), h = 0.5 * (J(1, 0) - J(0, 1));
  const double q = std::hypot(e, h), r = std::hypot(f, g);
  sigma = Vec2(q + r, q - r);
  const double a1 = std::atan2(g, f), a2 = std::atan2(h, e);
  const double theta = 0.5 * (a2 - a1), phi = 0.5 * (a2 + a1);  // U = rot(phi), V^T = rot(theta)
  U << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  V << std::cos(theta), std::sin(theta), -std::sin(theta), std::cos(theta);
}

/// Symmetric Dirichlet energy |J|^2 + |J^-1|^2 of every face, area-weighted; +inf if any face folds.
double energy(const Surface& m, const std::vector<TargetFrame>& fr, const std::vector<Vec2>& uv) {
  double e = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    if (fr[f].area <= 0) continue;
    const Tri& t = m.triangles[f];
    const Mat2 J = jacobian(fr[f], uv[t[0]], uv[t[1]], uv[t[2]]);
    const double det = J.determinant();
    if (!(det > 0)) return INFINITY;
    const double n2 = J.squaredNorm();
    e += fr[f].area * (n2 + n2 / (det * det));
  }
  return e;
}

/// Largest t in (0, limit] such that no triangle's signed area reaches zero on uv + s d, s in [0, t).
double max_step(const Surface& m, const std::vector<Vec2>& uv, const std::vector<Vec2>& d, double limit) {
  double t_max = limit;
  for (const Tri& t : m.triangles) {
    const Vec2 a = uv[t[1]] - uv[t[0]], b = uv[t[2]] - uv[t[0]];
    const Vec2 da = d[t[1]] - d[t[0]], db = d[t[2]] - d[t[0]];
    // 2 area(s) = cross(a + s da, b + s db) = c0 + c1 s + c2 s^2
    const double c0 = a.x() * b.y() - a.y() * b.x();
    const double c1 = a.x() * db.y() - a.y() * db.x() + da.x() * b.y() - da.y() * b.x();
    const double c2 = da.x() * db.y() - da.y() * db.x();
    double root = INFINITY;
    if (std::abs(c2) < 1e-300 * std::max(1.0, std::abs(c1))) {
      if (c1 < 0) root = -c0 / c1;
    } else {
      const double disc = c1 * c1 - 4 * c2 * c0;
      if (disc >= 0) {
        const double sq = std::sqrt(disc);
        const double q = -0.5 * (c1 + (c1 >= 0 ? sq : -sq));
        for (double r : {q / c2, q != 0 ? c0 / q : INFINITY})
          if (r > 0) root = std::min(root, r);
      }
    }
    if (root < t_max) t_max = root;
  }
  return t_max;
}

/// Step d from uv kept within `bounds`: a coordinate on its line that d would take across it stays
/// (its component of d zeroed).
void keep_within_bounds(const std::vector<CoordinateBound>& bounds, const std::vector<Vec2>& uv, std::vector<Vec2>& d) {
  for (const CoordinateBound& b : bounds)
    if (b.sign * d[b.vertex](b.axis) > 0 && b.sign * (uv[b.vertex](b.axis) - b.bound) >= 0) d[b.vertex](b.axis) = 0;
}

/// Puts a bounded coordinate that a step took across its line back onto it (the line search's
/// projection).
void clamp_to_bounds(const std::vector<CoordinateBound>& bounds, std::vector<Vec2>& uv) {
  for (const CoordinateBound& b : bounds)
    if (b.sign * (uv[b.vertex](b.axis) - b.bound) > 0) uv[b.vertex](b.axis) = b.bound;
}

/// The free coordinates' unknowns: index[2 v + a] for coordinate a of vertex v, -1 where it is held.
/// fixed[v] bit 0 holds u, bit 1 holds v (a vertex sliding along a side of the square keeps one of
/// them). A vertex all of whose faces have no target frame (no target area, or no 3D shape and no area
/// in the start map) has no energy term: its row of the system would be zero and the factorisation
/// fail, leaving the whole map unrefined, so it stays where it is (the line search still keeps its
/// faces from collapsing).
/// has_frame(f): whether face f has one. The unknowns are numbered vertex by vertex in `numbering`'s
/// order (a permutation of the vertices), in the vertices' own where it is null.
template <class HasFrame>
std::vector<int> free_coordinates(const Surface& m, HasFrame&& has_frame, const std::vector<char>& fixed, int& n,
                                  const std::vector<int>* numbering = nullptr) {
  const size_t nv = m.num_vertices();
  std::vector<char> framed(nv, 0);
  for (size_t f = 0; f < m.num_faces(); ++f)
    if (has_frame(f))
      for (uint32_t v : m.triangles[f]) framed[v] = 1;
  std::vector<int> index(2 * nv, -1);
  n = 0;
  for (size_t k = 0; k < nv; ++k) {
    const size_t v = numbering ? size_t((*numbering)[k]) : k;
    for (int a = 0; a < 2; ++a)
      if (framed[v] && !(fixed[v] & (1 << a))) index[2 * v + size_t(a)] = n++;
  }
  return index;
}

/// Each vertex's neighbours (across an edge) later in `rank` (each vertex's place in the unknowns'
/// numbering; empty: the vertices' own order), in that order, once each: vertex v's are
/// neighbour[start[v]] up to neighbour[start[v + 1]].
struct HigherNeighbours {
  std::vector<uint32_t> start, neighbour;
};

HigherNeighbours higher_neighbours(const Surface& m, const std::vector<uint32_t>& rank) {
  const size_t nv = m.num_vertices();
  HigherNeighbours r;
  std::vector<uint32_t> start(nv + 1, 0);
  const auto earlier = [&](uint32_t a, uint32_t b) { return rank.empty() ? a < b : rank[a] < rank[b]; };
  // Every face's three edges (an inner edge twice; the duplicates go below).
  auto for_each_edge = [&](auto&& f) {
    for (const Tri& t : m.triangles)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = t[k], b = t[(k + 1) % 3];
        if (a != b) earlier(a, b) ? f(a, b) : f(b, a);
      }
  };
  for_each_edge([&](uint32_t lo, uint32_t) { ++start[lo + 1]; });
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  r.neighbour.resize(start[nv]);
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for_each_edge([&](uint32_t lo, uint32_t hi) { r.neighbour[fill[lo]++] = hi; });
  // Sorted, then one entry per pair of vertices (compacted in place).
  r.start.assign(nv + 1, 0);
  size_t out = 0;
  for (size_t v = 0; v < nv; ++v) {
    std::sort(r.neighbour.begin() + start[v], r.neighbour.begin() + start[v + 1], earlier);
    for (uint32_t k = start[v]; k < start[v + 1]; ++k)
      if (out == r.start[v] || r.neighbour[out - 1] != r.neighbour[k]) r.neighbour[out++] = r.neighbour[k];
    r.start[v + 1] = uint32_t(out);
  }
  r.neighbour.resize(out);
  return r;
}

/// A step's system over the free coordinates, Newton's or SLIM's. Its pattern is the same every step:
/// it is built once, with where each face's 2x2 blocks land in the value array, so a step only
/// overwrites values.
class SlimSystem {
 public:
  SpMat A;
  Eigen::VectorXd rhs;

  /// index: free_coordinates' numbering of the n unknowns, in `numbering`'s order of the vertices.
  SlimSystem(const Surface& m, std::vector<int> index, int n, const std::vector<int>* numbering)
      : A(n, n), rhs(n), m_(m), index_(std::move(index)), neighbour_offset_(m.num_faces(), {-1, -1, -1}) {
    build_pattern(numbering);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m.num_faces(), 4096), [&](const tbb::blocked_range<size_t>& faces) {
      for (size_t face = faces.begin(); face != faces.end(); ++face) find_neighbour_offsets(face);
    });
  }

  /// The SLIM system at map uv against the faces' target frames, its squared weights at most max_weight.
  void assemble(const std::vector<TargetFrame>& fr, const std::vector<Vec2>& uv, double max_weight) {
    std::fill(A.valuePtr(), A.valuePtr() + A.nonZeros(), 0.0);
    rhs.setZero();
    for (size_t f = 0; f < m_.num_faces(); ++f)
      if (fr[f].area > 0) add_face(fr[f], f, uv, max_weight);
  }

  /// The projected Newton system at map uv: each face's Hessian of its symmetric Dirichlet energy
  /// with its negative eigenvalues clamped to zero (in the closed form of its four modes), and the
  /// negative gradient; its solution is the step of the free coordinates.
  void assemble_newton(const std::vector<TargetFrame>& fr, const std::vector<Vec2>& uv) {
    std::fill(A.valuePtr(), A.valuePtr() + A.nonZeros(), 0.0);
    rhs.setZero();
    // Each block of faces' terms on every core, then added in face order: the same sums as one core's.
    constexpr size_t kBlock = 8192;
    std::vector<FaceNewton> terms(std::min(kBlock, m_.num_faces()));
    for (size_t first = 0; first < m_.num_faces(); first += kBlock) {
      const size_t last = std::min(first + kBlock, m_.num_faces());
      tbb::parallel_for(tbb::blocked_range<size_t>(first, last, 512), [&](const tbb::blocked_range<size_t>& faces) {
        for (size_t f = faces.begin(); f != faces.end(); ++f)
          if (fr[f].area > 0) face_newton(fr[f], f, uv, terms[f - first]);
      });
      for (size_t f = first; f < last; ++f)
        if (fr[f].area > 0) add_face_newton(f, terms[f - first]);
    }
  }

  const std::vector<int>& index() const { return index_; }

 private:
  /// Vertex v's first and last unknowns (-1 where it has none): consecutive, as the numbering goes
  /// vertex by vertex.
  int first_unknown(uint32_t v) const { return index_[2 * size_t(v)] >= 0 ? index_[2 * size_t(v)] : index_[2 * size_t(v) + 1]; }
  int last_unknown(uint32_t v) const { return index_[2 * size_t(v) + 1] >= 0 ? index_[2 * size_t(v) + 1] : index_[2 * size_t(v)]; }

  /// The edge of a face between its corners i and j (i != j): edge k joins corners k and k + 1.
  static int edge_of(int i, int j) { return i + j == 1 ? 0 : i + j == 3 ? 1 : 2; }

  /// Where face's edges' rows lie in the pattern (build_pattern): for the edge's vertex numbered later,
  /// how many rows of the earlier one's columns, after that vertex's own, come before its first (its
  /// columns list the same neighbours' rows, so one number serves both).
  void find_neighbour_offsets(size_t face) {
    const Tri& t = m_.triangles[face];
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    for (int k = 0; k < 3; ++k) {
      uint32_t u = t[size_t(k)], w = t[size_t((k + 1) % 3)];
      if (u == w || first_unknown(u) < 0 || first_unknown(w) < 0) continue;
      if (first_unknown(w) < first_unknown(u)) std::swap(u, w);
      const int col = first_unknown(u);
      const int own_rows = last_unknown(u) - col + 1;
      neighbour_offset_[face][size_t(k)] =
          int(std::lower_bound(inner + outer[col], inner + outer[col + 1], first_unknown(w)) - inner) - outer[col] - own_rows;
    }
  }

  /// The index in A's values of the entry at (row, col), row >= col, which face f's corner i (row)
  /// and corner j (col) make: within a vertex's own rows where the corners are one vertex, else past
  /// the column vertex's own rows, at the row vertex's place among its neighbours
  /// (find_neighbour_offsets).
  int slot(size_t f, int i, int j, int row, int col) const {
    const Tri& t = m_.triangles[f];
    const int start = A.outerIndexPtr()[col];
    if (t[size_t(i)] == t[size_t(j)]) return start + row - col;
    const int past_own = last_unknown(t[size_t(j)]) - col + 1;
    return start + past_own + neighbour_offset_[f][size_t(edge_of(i, j))] + row - first_unknown(t[size_t(i)]);
  }

  /// A's lower triangle (zeros) in compressed columns, straight from the mesh's edges: two unknowns
  /// are coupled where they are one vertex's or the two ends of an edge (every pair of a face's corners
  /// is an edge). The unknowns are numbered vertex by vertex (free_coordinates), so a column's rows are
  /// its own vertex's from its coordinate on, then those of its vertex's later neighbours in turn.
  /// The same pattern as the faces' entries summed through triplets, built without sorting 21 of them
  /// per face (2.5 s of the symmetric Dirichlet steps at 854k faces).
  void build_pattern(const std::vector<int>* numbering) {
    const size_t nv = m_.num_vertices();
    std::vector<uint32_t> rank;
    if (numbering) {
      rank.resize(nv);
      for (size_t i = 0; i < nv; ++i) rank[size_t((*numbering)[i])] = uint32_t(i);
    }
    const HigherNeighbours higher = higher_neighbours(m_, rank);
    const auto vertex = [&](size_t i) { return numbering ? size_t((*numbering)[i]) : i; };
    const std::vector<uint32_t>& start = higher.start;
    auto free_of = [&](size_t v, int from) {
      int count = 0;
      for (int a = from; a < 2; ++a) count += index_[2 * v + size_t(a)] >= 0;
      return count;
    };
    int* outer = A.outerIndexPtr();
    outer[0] = 0;
    for (size_t i = 0; i < nv; ++i)
      for (int a = 0; a < 2; ++a) {
        const size_t v = vertex(i);
        const int col = index_[2 * v + size_t(a)];
        if (col < 0) continue;
        int rows = free_of(v, a);
        for (uint32_t k = start[v]; k < start[v + 1]; ++k) rows += free_of(higher.neighbour[k], 0);
        outer[col + 1] = outer[col] + rows;
      }
    A.resizeNonZeros(outer[A.cols()]);
    int* inner = A.innerIndexPtr();
    for (size_t i = 0; i < nv; ++i)
      for (int a = 0; a < 2; ++a) {
        const size_t v = vertex(i);
        const int col = index_[2 * v + size_t(a)];
        if (col < 0) continue;
        int p = outer[col];
        auto add_rows = [&](size_t w, int from) {
          for (int b = from; b < 2; ++b)
            if (const int row = index_[2 * w + size_t(b)]; row >= 0) inner[p++] = row;
        };
        add_rows(v, a);
        for (uint32_t k = start[v]; k < start[v + 1]; ++k) add_rows(higher.neighbour[k], 0);
      }
    std::fill(A.valuePtr(), A.valuePtr() + A.nonZeros(), 0.0);
  }

  /// The singular value decomposition of face f's Jacobian at uv.
  void face_svd(const TargetFrame& F, size_t f, const std::vector<Vec2>& uv, Mat2& U, Vec2& sigma, Mat2& V) const {
    const Tri& t = m_.triangles[f];
    svd2(jacobian(F, uv[t[0]], uv[t[1]], uv[t[2]]), U, sigma, V);
  }

  void add_face(const TargetFrame& F, size_t f, const std::vector<Vec2>& uv, double max_weight) {
    double* values = A.valuePtr();
    const Tri& t = m_.triangles[f];
    Mat2 U, V;
    Vec2 sigma;
    face_svd(F, f, uv, U, sigma, V);
    const Mat2 R = U * V.transpose();
    Vec2 w2;
    for (int k = 0; k < 2; ++k) {
      const double s = sigma(k);
      // w^2 of SLIM's symmetric Dirichlet weights, at most max_weight.
      w2(k) = std::min(max_weight, std::abs(s - 1) < 1e-8 ? 4.0 : (s - 1 / (s * s * s)) / (s - 1));
    }
    const Mat2 M = U * as_eigen(w2).asDiagonal() * U.transpose();
    const Mat2 MR = M * R;
    for (int i = 0; i < 3; ++i) {
      const Vec2 b = F.area * MR * as_eigen(F.g[i]);
      for (int a = 0; a < 2; ++a) {
        const int row = index_[2 * t[i] + size_t(a)];
        if (row < 0) continue;
        rhs(row) += b(a);
        for (int j = 0; j < 3; ++j) {
          const Mat2 H = F.area * F.g[i].dot(F.g[j]) * M;
          for (int b2 = 0; b2 < 2; ++b2) {
            const int col = index_[2 * t[j] + size_t(b2)];
            if (col < 0)
              rhs(row) -= H(a, b2) * uv[t[j]](b2);  // a fixed coordinate
            else if (row >= col)                    // the lower triangle: the pair's other order adds the upper entry
              values[slot(f, i, j, row, col)] += H(a, b2);
          }
        }
      }
    }
  }

  /// One face's terms of the projected Newton system: the negative gradient's per free coordinate of
  /// its corners (corner i's a-th at 2 i + a), and the Hessian's entries the system takes, in the order
  /// for_each_newton_entry visits them (21 where the face's corners are distinct).
  struct FaceNewton {
    std::array<double, 6> gradient;
    std::array<double, 36> hessian;
  };

  /// Calls on_row(i, a, row) for each free coordinate of face f's corners (corner i's a-th, the
  /// system's row), then on_entry(i, a, j, b, row, col) for each entry of the lower triangle that row
  /// takes from corner j's b-th coordinate (the system's column col).
  template <class OnRow, class OnEntry>
  void for_each_newton_entry(size_t f, OnRow&& on_row, OnEntry&& on_entry) const {
    const Tri& t = m_.triangles[f];
    for (int i = 0; i < 3; ++i)
      for (int a = 0; a < 2; ++a) {
        const int row = index_[2 * t[i] + size_t(a)];
        if (row < 0) continue;
        on_row(i, a, row);
        for (int j = 0; j < 3; ++j)
          for (int b = 0; b < 2; ++b) {
            const int col = index_[2 * t[j] + size_t(b)];
            if (col >= 0 && row >= col) on_entry(i, a, j, b, row, col);
          }
      }
  }

  /// Face f's projected Hessian and negative gradient into `out`. With J = U diag(s1, s2) V^T, the
  /// energy's Hessian in J has the eigenvectors U D V^T for D = diag(1, 0), diag(0, 1), the twist
  /// [0 -1; 1 0] and the flip [0 1; 1 0] (the last two over sqrt 2), with the eigenvalues 2 + 6 / s1^4,
  /// 2 + 6 / s2^4, (f1 + f2) / (s1 + s2) and (f1 - f2) / (s1 - s2), f_k = 2 s_k - 2 / s_k^3 (Smith,
  /// De Goes and Kim 2019; the flip's in a form without the division, which s1 = s2 would make 0 / 0);
  /// only the twist's can be negative. Reads the system's numbering only, so faces can be computed in
  /// parallel.
  void face_newton(const TargetFrame& F, size_t f, const std::vector<Vec2>& uv, FaceNewton& out) const {
    Mat2 U, V;
    Vec2 s;
    face_svd(F, f, uv, U, s, V);
    const double s1 = s(0), s2 = s(1);
    const double f1 = 2 * s1 - 2 / (s1 * s1 * s1), f2 = 2 * s2 - 2 / (s2 * s2 * s2);
    const Mat2 gradient = F.area * U * Eigen::Vector2d(f1, f2).asDiagonal() * V.transpose();
    Mat2 scale1, scale2, twist, flip;
    scale1 << 1, 0, 0, 0;
    scale2 << 0, 0, 0, 1;
    twist << 0, -M_SQRT1_2, M_SQRT1_2, 0;
    flip << 0, M_SQRT1_2, M_SQRT1_2, 0;
    const double flip_value = 2 + 2 * (s1 * s1 + s1 * s2 + s2 * s2) / (s1 * s1 * s1 * s2 * s2 * s2);
    const std::array<double, 4> lambda = {2 + 6 / (s1 * s1 * s1 * s1), 2 + 6 / (s2 * s2 * s2 * s2), std::max(0.0, (f1 + f2) / (s1 + s2)),
                                          flip_value};
    const std::array<Mat2, 4> mode = {U * scale1 * V.transpose(), U * scale2 * V.transpose(), U * twist * V.transpose(),
                                      U * flip * V.transpose()};
    std::array<std::array<Vec2, 3>, 4> q;  // q[k][i]: mode k's derivative in corner i's coordinates
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) q[size_t(k)][size_t(i)] = mode[size_t(k)] * as_eigen(F.g[size_t(i)]);
    size_t n = 0;
    for_each_newton_entry(
        f, [&](int i, int a, int) { out.gradient[size_t(2 * i + a)] = (gradient * as_eigen(F.g[size_t(i)]))(a); },
        [&](int i, int a, int j, int b, int, int) {
          double h = 0;
          for (size_t k = 0; k < 4; ++k) h += lambda[k] * q[k][size_t(i)](a) * q[k][size_t(j)](b);
          out.hessian[n++] = F.area * h;
        });
  }

  /// Adds face f's terms (face_newton's) to the system, in the order one loop over the faces did.
  void add_face_newton(size_t f, const FaceNewton& terms) {
    double* values = A.valuePtr();
    size_t n = 0;
    for_each_newton_entry(
        f, [&](int i, int a, int row) { rhs(row) -= terms.gradient[size_t(2 * i + a)]; },
        [&](int i, int, int j, int, int row, int col) { values[slot(f, i, j, row, col)] += terms.hessian[n++]; });
  }

  const Surface& m_;
  std::vector<int> index_;
  /// Per face and edge (find_neighbour_offsets), in place of each of its 21 entries' index: 12 bytes a
  /// face, not 84 (the system's largest array at 3.4M faces).
  std::vector<std::array<int, 3>> neighbour_offset_;
};

}  // namespace

class RefinementSystem {
 public:
  /// index: free_coordinates', in `numbering`'s order of the vertices (numbering_for). aggregates
  /// (optional): the steps are solved by conjugate gradients preconditioned over them
  /// (MultilevelSolver) instead of factorised.
  RefinementSystem(const Surface& m, std::vector<int> index, int n, long supernodal_from, const std::vector<int>* vertex_order,
                   const VertexAggregates* aggregates = nullptr, const std::vector<int>* numbering = nullptr)
      : system(m, std::move(index), n, numbering), solver(supernodal_from), numbered_in_vertex_order(numbering != nullptr) {
    if (aggregates) {
      std::vector<uint32_t> vertex(static_cast<size_t>(n));
      std::vector<uint8_t> axis(static_cast<size_t>(n));
      for (size_t k = 0; k < system.index().size(); ++k)
        if (const int i = system.index()[k]; i >= 0) vertex[size_t(i)] = uint32_t(k / 2), axis[size_t(i)] = uint8_t(k % 2);
      multilevel = std::make_unique<MultilevelSolver>(system.A, vertex, axis, *aggregates, numbered_in_vertex_order);
      return;
    }
    const std::vector<int> order =
        vertex_order && vertex_order->size() == m.num_vertices() ? order_of_unknowns(*vertex_order, system.index(), 2) : std::vector<int>{};
    solver.analyzePattern(system.A, order.empty() ? nullptr : &order);
    analysed = true;
  }

  /// The free coordinates' next positions x from uv: the projected Newton step; where its system does
  /// not solve (curvatures of 1e28 and more, from a sliver in the start map), SLIM's proxy, then that
  /// with its weights capped at kMaxWeight. False if none solves.
  bool solve_step(const std::vector<TargetFrame>& fr, const std::vector<Vec2>& uv, Eigen::VectorXd& x, SlimStats& st,
                  const std::vector<CoordinateBound>* bounds) {
    system.assemble_newton(fr, uv);
    x = Eigen::VectorXd::Zero(system.rhs.size());
    if (bounds) hold_pressed(*bounds, uv);
    if (solve_newton(x)) {
      const std::vector<int>& index = system.index();
      for (size_t v = 0; v < uv.size(); ++v)
        for (int a = 0; a < 2; ++a)
          if (const int k = index[2 * v + size_t(a)]; k >= 0) x(k) += uv[v](a);
      return true;
    }
    ++st.proxy_steps;
    system.assemble(fr, uv, INFINITY);
    if (solve_proxy(uv, x)) return true;
    system.assemble(fr, uv, kMaxWeight);
    if (!solve_proxy(uv, x)) return false;
    ++st.capped_steps;
    return true;
  }

  /// The iterative solver's unknowns in vertex_order's order of the vertices (which halves its
  /// sweeps), a factorised system's in the vertices' own (in which its results were measured).
  static const std::vector<int>* numbering_for(const Surface& m, const std::vector<int>* vertex_order, const VertexAggregates* aggregates) {
    return aggregates && vertex_order && vertex_order->size() == m.num_vertices() ? vertex_order : nullptr;
  }

  SlimSystem system;
  SparseCholesky solver;
  bool numbered_in_vertex_order;
  bool analysed = false;
  std::unique_ptr<MultilevelSolver> multilevel;

 private:
  /// Holds, for this step, the bounded coordinates that sit on their lines with the energy pressing
  /// them across (projected Newton's active set): each is tied to where it is by a spring far stiffer
  /// than its own curvature, so the others move as they would with it held.
  void hold_pressed(const std::vector<CoordinateBound>& bounds, const std::vector<Vec2>& uv) {
    const std::vector<int>& index = system.index();
    for (const CoordinateBound& b : bounds) {
      const int k = index[2 * size_t(b.vertex) + size_t(b.axis)];
      if (k < 0 || b.sign * (b.bound - uv[b.vertex](b.axis)) > 0 || !(b.sign * system.rhs(k) > 0)) continue;
      system.A.coeffRef(k, k) *= 1 + kHoldStiffness;
    }
  }

  /// The Newton system's step into x (zero on entry): iterated where there is a multilevel solver,
  /// else factorised.
  bool solve_newton(Eigen::VectorXd& x) {
    if (!multilevel) return factorize_and_solve(x);
    return iterate_step(system.rhs, x);
  }

  /// The proxy's positions into x: where there is a multilevel solver, uv plus the step its system
  /// gives from uv, iterated as Newton's; factorised where that fails or there is none.
  bool solve_proxy(const std::vector<Vec2>& uv, Eigen::VectorXd& x) {
    if (multilevel) {
      const std::vector<int>& index = system.index();
      Eigen::VectorXd start(x.size());
      for (size_t v = 0; v < uv.size(); ++v)
        for (int a = 0; a < 2; ++a)
          if (const int k = index[2 * v + size_t(a)]; k >= 0) start(k) = uv[v](a);
      const Eigen::VectorXd rhs = system.rhs - system.A.selfadjointView<Eigen::Lower>() * start;
      x.setZero();
      if (iterate_step(rhs, x)) {
        x += start;
        return true;
      }
    }
    return factorize_and_solve(x);
  }

  /// A step's system A x = rhs solved from x = 0 to kStepTolerance, or as far as kStepIterations take it:
  /// conjugate gradients from zero give a descent direction at any iteration, and the line search
  /// takes what of it lowers the energy without folding. False where the solver cannot start or the
  /// step is not finite.
  bool iterate_step(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
    if (!multilevel->update(system.A)) return false;
    const IterativeSolve r = multilevel->solve(rhs, x, kStepTolerance, kStepIterations);
    return r.iterations > 0 && r.relative_residual < 0.5 && x.allFinite();
  }

  bool factorize_and_solve(Eigen::VectorXd& x) {
    if (!analysed) solver.analyzePattern(system.A), analysed = true;
    return solver.factorize(system.A) && solver.solve(system.A, system.rhs, x);
  }
};

std::shared_ptr<RefinementSystem> prepare_refinement(const Surface& m, const std::vector<char>& fixed, const std::vector<double>& target,
                                                     long supernodal_from, const std::vector<int>* vertex_order,
                                                     const VertexAggregates* aggregates) {
  int n = 0;
  const std::vector<int>* numbering = RefinementSystem::numbering_for(m, vertex_order, aggregates);
  std::vector<int> index = free_coordinates(
      m, [&](size_t f) { return target[f] > 0 && std::isfinite(target[f]); }, fixed, n, numbering);
  if (n == 0) return nullptr;
  return std::make_shared<RefinementSystem>(m, std::move(index), n, supernodal_from, vertex_order, aggregates, numbering);
}

SlimStats refine_map(const Surface& m, const std::vector<char>& fixed, const std::vector<double>& target, int iterations,
                     std::vector<Vec2>& uv, long supernodal_from, const std::function<void(int step)>& on_step,
                     const std::vector<FaceShape>* shapes, const std::vector<int>* vertex_order, std::shared_ptr<RefinementSystem>* system,
                     const std::vector<CoordinateBound>* bounds) {
  SlimStats st;
  const size_t nv = m.num_vertices();
  const auto fr = target_frames(m, target, uv, shapes);
  int n = 0;
  std::shared_ptr<RefinementSystem> own;
  std::shared_ptr<RefinementSystem>& sys = system ? *system : own;
  // Numbered as the given system is, to be compared with its unknowns.
  const auto framed = [&](size_t f) { return fr[f].area > 0; };
  std::vector<int> index = free_coordinates(m, framed, fixed, n, sys && sys->numbered_in_vertex_order ? vertex_order : nullptr);
  st.energy_before = st.energy = energy(m, fr, uv);
  if (n == 0 || !std::isfinite(st.energy)) return st;
  if (!sys || sys->system.index() != index) {
    if (sys && sys->numbered_in_vertex_order) index = free_coordinates(m, framed, fixed, n);
    sys = std::make_shared<RefinementSystem>(m, std::move(index), n, supernodal_from, vertex_order);
  }
  const std::vector<int>& free = sys->system.index();
  std::vector<Vec2> d(nv), trial(nv);
  for (int it = 0; it < iterations; ++it) {
    Eigen::VectorXd x;
    if (!sys->solve_step(fr, uv, x, st, bounds)) {
      st.stopped = "solver";
      break;
    }
    for (size_t v = 0; v < nv; ++v)
      for (int a = 0; a < 2; ++a) {
        const int k = free[2 * v + size_t(a)];
        d[v](a) = k < 0 ? 0.0 : x(k) - uv[v](a);
      }
    // Line search: from the whole step, or 0.9 of the longest that folds nothing where that is
    // shorter, halved until the energy drops; a bounded coordinate stops at its line (projected).
    if (bounds) keep_within_bounds(*bounds, uv, d);
    double t = 0.9 * max_step(m, uv, d, 1 / 0.9);
    double e_new = INFINITY;
    for (int tries = 0; tries < 40; ++tries, t *= 0.5) {
      for (size_t v = 0; v < nv; ++v) trial[v] = uv[v] + t * d[v];
      if (bounds) clamp_to_bounds(*bounds, trial);
      e_new = energy(m, fr, trial);
      if (e_new < st.energy) break;
    }
    if (!(e_new < st.energy)) {
      st.stopped = "no descent";
      break;
    }
    uv.swap(trial);
    const double gain = (st.energy - e_new) / st.energy;
    st.energy = e_new;
    ++st.iterations;
    if (on_step) on_step(st.iterations);
    if (gain < 1e-3) {
      st.stopped = "converged";
      break;
    }
  }
  if (st.stopped.empty()) st.stopped = "iterations";
  return st;
}

}  // namespace tightex
