// The square map's steps called one by one (paper §4.2): Alg. 1 (map_boundary_to_square) places the
// boundary on the square, Alg. 2 (harmonic_map) solves the interior from that boundary condition, and
// together they give exactly the map map_to_square returns with the paper's cotangent weights.
#include <gtest/gtest.h>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"

namespace tightex {
namespace {

namespace cat = testing;

/// Whether p lies on the unit square's boundary (within rounding).
bool on_square_boundary(const Vec2& p) {
  constexpr double kEps = 1e-12;
  const bool inside = p.x() >= -kEps && p.x() <= 1 + kEps && p.y() >= -kEps && p.y() <= 1 + kEps;
  const bool on_side = std::abs(p.x()) < kEps || std::abs(p.x() - 1) < kEps || std::abs(p.y()) < kEps || std::abs(p.y() - 1) < kEps;
  return inside && on_side;
}

TEST(SquareMapSteps, BoundaryOnTheSquareWithItsCorners) {
  for (auto make : {&cat::disk, &cat::open_cylinder, &cat::sphere_with_holes}) {
    for (const Surface& c : split_components(prepare_surface(make(), nullptr))) {
      const Disk disk = cut_to_disk(c, CutOptions{}, nullptr);
      const SquareMapOptions options;
      const SquareBoundary b = map_boundary_to_square(disk, options);
      ASSERT_EQ(b.uv.size(), disk.boundary.size());
      for (int k = 0; k < 4; ++k) EXPECT_EQ(b.uv[b.corner[k]], kSquareCorners[k]) << "corner " << k;
      for (size_t i = 0; i < b.uv.size(); ++i) {
        if (b.pinned[i] && std::find(b.corner.begin(), b.corner.end(), i) == b.corner.end()) continue;  // a bump: off its side
        EXPECT_TRUE(on_square_boundary(b.uv[i])) << "position " << i << ": (" << b.uv[i].x() << ", " << b.uv[i].y() << ")";
      }
    }
  }
}

TEST(SquareMapSteps, HarmonicMapFromAlg1IsThePapersMap) {
  size_t compared = 0;
  for (auto make : {&cat::disk, &cat::open_cylinder, &cat::sphere_with_holes, &cat::obtuse_strip}) {
    for (const Surface& c : split_components(prepare_surface(make(), nullptr))) {
      const Disk disk = cut_to_disk(c, CutOptions{}, nullptr);
      const SquareMapOptions options;
      SquareMapStats st;
      const std::vector<Vec2> expected = map_to_square(disk, options, &st);
      if (st.weights != "cotangent") continue;  // the fallbacks: fold_free_harmonic_map's business
      const SquareBoundary b = map_boundary_to_square(disk, options);
      DirichletSolver solver(options.supernodal_from);
      std::vector<Vec2> uv;
      ASSERT_TRUE(harmonic_map(disk.mesh, disk.boundary, b.uv, edge_weights(disk.mesh, EdgeWeights::kCotangent), solver, uv));
      ASSERT_EQ(uv.size(), expected.size());
      for (size_t v = 0; v < uv.size(); ++v) EXPECT_EQ(uv[v], expected[v]) << "vertex " << v;
      for (size_t i = 0; i < disk.boundary.size(); ++i) EXPECT_EQ(uv[disk.boundary[i]], b.uv[i]) << "the boundary condition holds";
      ++compared;
    }
  }
  EXPECT_GE(compared, 3u) << "most of these disks keep the cotangent weights";
}

TEST(SquareMapSteps, FallbackWeightsAreFoldFreeOnAConvexBoundary) {
  const auto comps = split_components(prepare_surface(cat::obtuse_strip(), nullptr));
  ASSERT_FALSE(comps.empty());
  const Disk disk = cut_to_disk(comps[0], CutOptions{}, nullptr);
  const SquareBoundary b = map_boundary_to_square(disk, SquareMapOptions{});
  DirichletSolver solver;
  const HarmonicAttempts h = fold_free_harmonic_map(disk.mesh, disk.boundary, b.uv, solver);
  ASSERT_TRUE(h.weights.has_value());
  EXPECT_EQ(h.flipped, 0u);
  EXPECT_EQ(count_folds(disk.mesh, h.uv), 0u);
  EXPECT_EQ(h.folds_per_attempt.back(), 0u);
}

// A solver prepared ahead for one set of held vertices, then asked to solve with another (the
// multilevel map prepares for the coarse copy it tries first, and may settle on another): it builds
// the system it is asked for, and gives a fresh solver's solution, bit for bit.
TEST(SquareMapSteps, APreparedSolverAskedForOtherHeldVerticesSolvesThose) {
  const auto comps = split_components(prepare_surface(cat::sphere_with_holes(), nullptr));
  ASSERT_FALSE(comps.empty());
  const Disk disk = cut_to_disk(comps[0], CutOptions{}, nullptr);
  const Surface& m = disk.mesh;
  const SquareBoundary b = map_boundary_to_square(disk, SquareMapOptions{});
  const std::vector<double> w = edge_weights(m, EdgeWeights::kClamped);
  std::vector<Vec2> start(m.num_vertices(), Vec2::Zero());
  for (size_t i = 0; i < disk.boundary.size(); ++i) start[disk.boundary[i]] = b.uv[i];
  const std::vector<char> boundary = boundary_mask(m.num_vertices(), disk.boundary);
  uint32_t interior = 0;
  while (boundary[interior]) ++interior;
  std::vector<char> held_too = boundary;  // one interior vertex held too, where the start puts it
  held_too[interior] = 1;
  const std::vector<char>& more = held_too;
  start[interior] = Vec2(0.5, 0.5);
  for (const std::vector<char>* held : {&boundary, &more}) {
    DirichletSolver fresh;
    std::vector<Vec2> expected = start;
    ASSERT_TRUE(fresh.solve(m, w, *held, expected));
    DirichletSolver prepared;
    prepared.prepare(m, held == &boundary ? more : boundary);
    std::vector<Vec2> uv = start;
    ASSERT_TRUE(prepared.solve(m, w, *held, uv));
    for (size_t v = 0; v < uv.size(); ++v) EXPECT_EQ(uv[v], expected[v]) << "vertex " << v;
    if (held == &more)
      EXPECT_EQ(uv[interior], Vec2(0.5, 0.5)) << "held where the start put it";
    else
      EXPECT_NE(uv[interior], Vec2(0.5, 0.5)) << "solved, not held";
  }
}

}  // namespace
}  // namespace tightex
