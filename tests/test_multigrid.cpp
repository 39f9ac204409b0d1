// The multilevel map's iterative solver (param/multigrid.hpp): conjugate gradients preconditioned by
// a V-cycle over the coarsening's aggregates, against the sparse Cholesky factorisation it replaces on
// large disks, on a generated torus and on a real scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "cut/cut.hpp"
#include "io/obj_reader.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "param/sparse_cholesky.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "torus_disk.hpp"

namespace tightex {
namespace {

namespace cat = testing;
namespace fs = std::filesystem;

/// The largest component of the Meshroom scan cut to a disk; nullopt without ../shared/data.
std::optional<Disk> scan_disk() {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "meshroom_esp32cam" / "texturedMesh.obj";
  if (!fs::exists(input)) return std::nullopt;
  std::vector<Surface> parts = split_components(prepare_surface(read_obj(input.string()), nullptr));
  const auto largest =
      std::max_element(parts.begin(), parts.end(), [](const Surface& a, const Surface& b) { return a.num_faces() < b.num_faces(); });
  return cut_to_disk(*largest, CutOptions{}, nullptr);
}

std::vector<double> face_areas(const Surface& m) {
  std::vector<double> area(m.num_faces());
  for (size_t f = 0; f < m.num_faces(); ++f)
    area[f] = triangle_area(m.positions[m.triangles[f][0]], m.positions[m.triangles[f][1]], m.positions[m.triangles[f][2]]);
  return area;
}

/// Aggregates of a quarter of the vertices each, down to 200.
VertexAggregates aggregates_of(const Disk& disk) {
  std::vector<size_t> sizes;
  for (size_t size = disk.mesh.num_vertices() / 4; size >= 200; size /= 4) sizes.push_back(size);
  VertexAggregates aggregates;
  coarsen_disk_in_steps(disk, face_areas(disk.mesh), {}, sizes, &aggregates);
  return aggregates;
}

/// The Tutte map with clamped cotangent weights, the boundary on the unit circle, solved by `solver`.
std::vector<Vec2> tutte_map(const Disk& disk, DirichletSolver& solver) {
  const size_t nb = disk.boundary.size();
  std::vector<Vec2> circle(nb);
  for (size_t i = 0; i < nb; ++i)
    circle[i] = Vec2(std::cos(2 * std::numbers::pi * double(i) / double(nb)), std::sin(2 * std::numbers::pi * double(i) / double(nb)));
  std::vector<Vec2> uv;
  EXPECT_TRUE(harmonic_map(disk.mesh, disk.boundary, circle, edge_weights(disk.mesh, EdgeWeights::kClamped), solver, uv));
  return uv;
}

double largest_difference(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  double worst = 0;
  for (size_t v = 0; v < a.size(); ++v) worst = std::max(worst, (a[v] - b[v]).norm());
  return worst;
}

TEST(Multigrid, AggregatesAreNestedAndCoarsen) {
  const Disk disk = cat::torus_disk();
  const VertexAggregates aggregates = aggregates_of(disk);
  ASSERT_GE(aggregates.levels.size(), 2u);
  size_t before = disk.mesh.num_vertices();
  for (size_t k = 0; k < aggregates.levels.size(); ++k) {
    const std::vector<uint32_t>& level = aggregates.levels[k];
    ASSERT_EQ(level.size(), disk.mesh.num_vertices());
    std::vector<char> standing(level.size(), 0);
    for (uint32_t v : level) standing[v] = 1;
    size_t count = 0;
    for (uint32_t v = 0; v < level.size(); ++v)
      if (standing[v]) {
        ++count;
        EXPECT_EQ(level[v], v) << "a vertex standing for others stands for itself";
        for (size_t j = 0; j < k; ++j) EXPECT_EQ(aggregates.levels[j][v], v) << "and did at every finer level";
      }
    EXPECT_LT(count, before);
    before = count;
  }
  for (uint32_t v : disk.boundary) EXPECT_EQ(aggregates.levels.back()[v], v) << "the boundary is never collapsed";
}

// The same Tutte map as the factorisation's, up to the solve's tolerance, from a cold start.
TEST(Multigrid, TutteMapMatchesTheFactorisationOnATorus) {
  const Disk disk = cat::torus_disk();
  auto aggregates = std::make_shared<const VertexAggregates>(aggregates_of(disk));
  DirichletSolver direct, iterative;
  iterative.solve_iteratively(aggregates, 1e-12);
  const std::vector<Vec2> a = tutte_map(disk, direct), b = tutte_map(disk, iterative);
  EXPECT_LT(largest_difference(a, b), 1e-9);
  EXPECT_EQ(count_folds(disk.mesh, b), 0u);
}

TEST(Multigrid, TutteMapMatchesTheFactorisationOnARealScan) {
  const std::optional<Disk> disk = scan_disk();
  if (!disk) GTEST_SKIP() << "../shared/data/meshroom_esp32cam not present";
  auto aggregates = std::make_shared<const VertexAggregates>(aggregates_of(*disk));
  DirichletSolver direct, iterative;
  iterative.solve_iteratively(aggregates, 1e-12);
  const std::vector<Vec2> a = tutte_map(*disk, direct), b = tutte_map(*disk, iterative);
  EXPECT_LT(largest_difference(a, b), 1e-8);
  // The scan's map onto a circle crowds a few triangles below rounding (the factorisation folds 3):
  // the iterative map folds only triangles the factorisation's leaves smaller than 1e-12.
  const Surface& m = disk->mesh;
  for (const Tri& f : m.triangles)
    if (!(signed_area(b[f[0]], b[f[1]], b[f[2]]) > 0)) EXPECT_LT(std::abs(signed_area(a[f[0]], a[f[1]], a[f[2]])), 1e-12);
}

/// A system of two coordinates per vertex (a symmetric Dirichlet step's shape): the Laplacian of each
/// axis, coupled by a small cross term, the boundary held; its unknowns numbered vertex by vertex in
/// `numbering`'s order (the vertices' own where empty).
struct TwoCoordinateSystem {
  MultilevelSolver::Matrix a;
  std::vector<uint32_t> vertex;
  std::vector<uint8_t> axis;
};

TwoCoordinateSystem two_coordinate_system(const Disk& disk, const std::vector<int>& numbering = {}) {
  const Surface& m = disk.mesh;
  const std::vector<double> w = edge_weights(m, EdgeWeights::kClamped);
  const std::vector<char> held = boundary_mask(m.num_vertices(), disk.boundary);
  std::vector<int> unknown(2 * m.num_vertices(), -1);
  TwoCoordinateSystem sys;
  for (uint32_t k = 0; k < m.num_vertices(); ++k) {
    const uint32_t v = numbering.empty() ? k : uint32_t(numbering[k]);
    for (uint8_t a = 0; a < 2; ++a)
      if (!held[v]) unknown[2 * v + a] = int(sys.vertex.size()), sys.vertex.push_back(v), sys.axis.push_back(a);
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (uint32_t h = 0; h < m.opposite.size(); ++h) {
    const uint32_t o = m.opposite[h];
    if (o != kNone && o < h) continue;
    const uint32_t p = m.from(h), q = m.to(h);
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        const double value = (a == b ? 1.0 : 0.1) * w[h];
        const int ip = unknown[2 * p + a], iq = unknown[2 * q + b], jp = unknown[2 * p + b], jq = unknown[2 * q + a];
        if (ip >= 0 && jp >= 0 && ip >= jp) entries.emplace_back(ip, jp, value);
        if (iq >= 0 && jq >= 0 && iq >= jq) entries.emplace_back(iq, jq, value);
        if (ip >= 0 && iq >= 0) entries.emplace_back(std::max(ip, iq), std::min(ip, iq), -value);
      }
  }
  sys.a.resize(Eigen::Index(sys.vertex.size()), Eigen::Index(sys.vertex.size()));
  sys.a.setFromTriplets(entries.begin(), entries.end());
  sys.a.makeCompressed();
  return sys;
}

/// The largest difference between x and the factorisation's solution of a x = rhs, relative to the
/// latter's largest coefficient.
double relative_error_against_factorisation(const MultilevelSolver::Matrix& a, const Eigen::VectorXd& rhs, const Eigen::VectorXd& x) {
  Eigen::SimplicialLDLT<MultilevelSolver::Matrix, Eigen::Lower> direct(a);
  const Eigen::VectorXd expected = direct.solve(rhs);
  return (x - expected).lpNorm<Eigen::Infinity>() / expected.lpNorm<Eigen::Infinity>();
}

TEST(Multigrid, SolvesATwoCoordinateSystemAsTheFactorisationDoes) {
  const Disk disk = cat::torus_disk();
  const TwoCoordinateSystem sys = two_coordinate_system(disk);
  const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(sys.a.rows(), -1.0, 1.0);
  Eigen::VectorXd x;
  MultilevelSolver solver(sys.a, sys.vertex, sys.axis, aggregates_of(disk));
  ASSERT_TRUE(solver.update(sys.a));
  ASSERT_GE(solver.level_sizes().size(), 3u);
  const IterativeSolve outcome = solver.solve(rhs, x, 1e-12, 200);
  ASSERT_TRUE(outcome.converged);
  EXPECT_LT(relative_error_against_factorisation(sys.a, rhs, x), 1e-8);
}

// Unknowns in nested dissection's order, the large levels swept in halves on two threads: after as
// many iterations, a residual about as small as one thread's sweeps leave (the halves' coupling as
// Jacobi's costs little convergence), and the same bits from solve to solve (nothing depends on the
// threads' timing).
TEST(Multigrid, SweepsInHalvesConvergeAsOneThreadsAndRepeatExactly) {
  auto g = cat::torus_geometry(480, 240);
  const TexturedMesh mesh = cat::make_textured("torus", g.positions, g.triangles);
  const Disk disk = cut_to_disk(split_components(prepare_surface(mesh, nullptr)).at(0), CutOptions{}, nullptr);
  const std::vector<int> order = nested_dissection_order(disk.mesh);
  ASSERT_EQ(order.size(), disk.mesh.num_vertices());
  const TwoCoordinateSystem sys = two_coordinate_system(disk, order);
  const VertexAggregates aggregates = aggregates_of(disk);
  const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(sys.a.rows(), -1.0, 1.0);
  constexpr int kIterations = 60;
  double residual[2] = {0, 0};
  for (bool halves : {false, true}) {
    MultilevelSolver solver(sys.a, sys.vertex, sys.axis, aggregates, halves);
    ASSERT_TRUE(solver.update(sys.a));
    ASSERT_GE(solver.level_sizes()[1], 50000u) << "two levels large enough to be swept in halves";
    Eigen::VectorXd x, again;
    const IterativeSolve outcome = solver.solve(rhs, x, 1e-14, kIterations);
    ASSERT_EQ(outcome.iterations, kIterations);
    residual[halves] = (rhs - sys.a.selfadjointView<Eigen::Lower>() * x).norm() / rhs.norm();
    EXPECT_NEAR(residual[halves], outcome.relative_residual, 1e-3 * outcome.relative_residual) << "halves " << halves;
    if (!halves) continue;
    solver.solve(rhs, again, 1e-14, kIterations);
    EXPECT_TRUE(x == again);
  }
  EXPECT_LT(residual[0], 1e-2) << residual[1];
  EXPECT_LT(residual[1], 1.5 * residual[0]) << "one thread " << residual[0];
}

}  // namespace
}  // namespace tightex
