// The multilevel density map (param/multilevel.hpp) and the coarse copy it maps (param/coarsen.hpp), on
// a torus cut to a disk, with thresholds lowered so that a small mesh takes the multilevel path.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <set>

#include <tbb/parallel_for.h>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "torus_disk.hpp"

namespace tightex {
namespace {

namespace cat = testing;

/// Targets that vary over the surface (8x between the densest and the sparsest region), as the detail
/// map's do.
std::vector<double> varying_targets(const Surface& m) {
  std::vector<double> t(m.num_faces());
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Vec3 &a = m.positions[m.triangles[f][0]], &b = m.positions[m.triangles[f][1]], &c = m.positions[m.triangles[f][2]];
    const Vec3 centre = (a + b + c) / 3;
    t[f] = triangle_area(a, b, c) * std::exp2(1.5 * std::sin(3 * std::atan2(centre.y(), centre.x())) + 1.5 * centre.z() / 0.4);
  }
  return t;
}

/// Options that send `disk` down the multilevel path (a coarse copy of at most 1000 vertices), with
/// varying_targets.
SquareMapOptions multilevel_options(const Disk& disk) {
  SquareMapOptions options;
  options.face_target = varying_targets(disk.mesh);
  options.multilevel_from = 2000;
  options.coarse_vertices = 1000;
  return options;
}

/// uv (with stats st) is a multilevel map, fold-free, its corners on the square's, with the density of
/// the map `like` reports (within 0.05 in log2).
void expect_multilevel_map_like(const Disk& disk, const std::vector<Vec2>& uv, const SquareMapStats& st, const SquareMapStats& like) {
  ASSERT_GT(st.coarse_vertices, 0u) << "the multilevel path was taken";
  EXPECT_EQ(st.flipped, 0u);
  EXPECT_EQ(count_folds(disk.mesh, uv), 0u);
  for (size_t k = 0; k < 4; ++k) EXPECT_EQ(uv[st.corners[k]], kSquareCorners[k]);
  EXPECT_NEAR(st.spread_p5, like.spread_p5, 0.05);
  EXPECT_NEAR(st.spread_p95, like.spread_p95, 0.05);
}

TEST(Multilevel, CoarseDiskKeepsTheBoundaryTopologyAndTargets) {
  const Disk fine = cat::torus_disk();
  const std::vector<double> target = varying_targets(fine.mesh);
  const CoarseDisk coarse = coarsen_disk(fine, target, 1000);
  const Surface& cm = coarse.disk.mesh;
  EXPECT_LE(cm.num_vertices(), 1000u);
  EXPECT_GE(cm.num_vertices(), fine.boundary.size());
  ASSERT_EQ(coarse.fine_vertex.size(), cm.num_vertices());
  for (size_t c = 0; c + 1 < coarse.fine_vertex.size(); ++c) EXPECT_LT(coarse.fine_vertex[c], coarse.fine_vertex[c + 1]);
  for (size_t c = 0; c < cm.num_vertices(); ++c) EXPECT_EQ(cm.positions[c], fine.mesh.positions[coarse.fine_vertex[c]]);
  // The same boundary, vertex for vertex, and still a disk.
  ASSERT_EQ(coarse.disk.boundary.size(), fine.boundary.size());
  for (size_t i = 0; i < fine.boundary.size(); ++i) EXPECT_EQ(coarse.fine_vertex[coarse.disk.boundary[i]], fine.boundary[i]);
  const Topology t = topology_of(cm);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.euler(), 1);
  // No new chord: an edge between two boundary vertices is one the fine disk has.
  const std::vector<char> fine_on_boundary = boundary_mask(fine.mesh.num_vertices(), fine.boundary);
  std::set<std::pair<uint32_t, uint32_t>> fine_edges;
  for (const Tri& f : fine.mesh.triangles)
    for (int k = 0; k < 3; ++k) fine_edges.insert(std::minmax(f[k], f[(k + 1) % 3]));
  for (const Tri& f : cm.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = coarse.fine_vertex[f[k]], b = coarse.fine_vertex[f[(k + 1) % 3]];
      if (fine_on_boundary[a] && fine_on_boundary[b]) EXPECT_TRUE(fine_edges.count(std::minmax(a, b))) << a << "-" << b;
    }
  // The targets are handed on, not lost; every coarse face keeps an area.
  ASSERT_EQ(coarse.face_target.size(), cm.num_faces());
  const double fine_sum = std::accumulate(target.begin(), target.end(), 0.0);
  EXPECT_NEAR(std::accumulate(coarse.face_target.begin(), coarse.face_target.end(), 0.0), fine_sum, 1e-9 * fine_sum);
  for (const Tri& f : cm.triangles) EXPECT_GT(triangle_area(cm.positions[f[0]], cm.positions[f[1]], cm.positions[f[2]]), 0);
}

// The copies of one run of collapses, stopped at each size in turn, are the copies coarsen_disk gives
// for each size alone (the multilevel map's finer copies, where a coarse one's map folds, cost no
// second coarsening).
TEST(Multilevel, CopiesInStepsAreTheCopiesOfEachSize) {
  const Disk fine = cat::torus_disk();
  const std::vector<double> target = varying_targets(fine.mesh);
  const std::vector<size_t> sizes{2400, 1200, 600};
  const std::vector<CoarseDisk> steps = coarsen_disk_in_steps(fine, target, sizes);
  ASSERT_EQ(steps.size(), sizes.size());
  for (size_t k = 0; k < sizes.size(); ++k) {
    SCOPED_TRACE(sizes[k]);
    const CoarseDisk alone = coarsen_disk(fine, target, sizes[k]);
    EXPECT_LE(steps[k].fine_vertex.size(), sizes[k]);
    EXPECT_EQ(steps[k].fine_vertex, alone.fine_vertex);
    EXPECT_EQ(steps[k].disk.mesh.triangles, alone.disk.mesh.triangles);
    EXPECT_EQ(steps[k].face_target, alone.face_target);
  }
}

TEST(Multilevel, MapIsFoldFreeOnTheSquareAndNearTheFullMapsDensity) {
  const Disk disk = cat::torus_disk();
  SquareMapOptions options;
  options.face_target = varying_targets(disk.mesh);
  options.refine_keeps_density = false;
  options.refine_iterations = 30;
  options.multilevel_from = size_t(-1);
  SquareMapStats full;
  map_to_square(disk, options, &full);
  ASSERT_EQ(full.coarse_vertices, 0u);
  options.multilevel_from = 2000;
  options.coarse_vertices = 1000;
  SquareMapStats st;
  const std::vector<Vec2> uv = map_to_square(disk, options, &st);
  ASSERT_GT(st.coarse_vertices, 0u) << "the multilevel path was taken";
  EXPECT_LE(st.coarse_vertices, 1000u);
  EXPECT_EQ(st.flipped, 0u);
  EXPECT_EQ(count_folds(disk.mesh, uv), 0u);
  for (size_t k = 0; k < 4; ++k) EXPECT_EQ(uv[st.corners[k]], kSquareCorners[k]);
  const double bump = 1.0 / 1024;  // a bump lies at most bump_texels outside its side
  for (const Vec2& p : uv) {
    EXPECT_GE(p.minCoeff(), -bump);
    EXPECT_LE(p.maxCoeff(), 1 + bump);
  }
  // The density follows the targets about as well as the full-resolution map's.
  EXPECT_GT(st.spread_p5, full.spread_p5 - 0.5);
  EXPECT_LT(st.spread_p95, full.spread_p95 + 0.5);
}

// Every system of the multilevel map in one nested dissection order of the full mesh (as from
// kVertexOrderFrom vertices): the map stays fold-free on the square, with the density of the map whose
// systems CHOLMOD orders one by one, up to rounding.
TEST(Multilevel, OneVertexOrderForEverySystemGivesTheSameMap) {
  const Disk disk = cat::torus_disk();
  SquareMapOptions options = multilevel_options(disk);
  options.vertex_order_from = size_t(-1);
  SquareMapStats own;
  const std::vector<Vec2> own_uv = map_to_square(disk, options, &own);
  options.vertex_order_from = 0;
  SquareMapStats ordered;
  const std::vector<Vec2> uv = map_to_square(disk, options, &ordered);
  expect_multilevel_map_like(disk, uv, ordered, own);
  double worst = 0;
  for (size_t v = 0; v < uv.size(); ++v) worst = std::max(worst, (uv[v] - own_uv[v]).norm());
  EXPECT_LT(worst, 1e-6) << "the same map but for the rounding of another elimination order";
  EXPECT_GT(worst, 0.0) << "the order was taken (another elimination order rounds otherwise)";
}

// The full mesh's symmetric Dirichlet steps solved by conjugate gradients over the collapses'
// aggregates (as from iterative_from vertices; their unknowns numbered in the nested dissection's
// order, as a large disk's are), the Laplacians too (iterative_laplacians): fold-free on the square,
// with the density of the map whose systems are factorised.
TEST(Multilevel, IterativeFineStageGivesTheFactorisedMapsDensity) {
  const Disk disk = cat::torus_disk();
  SquareMapOptions options = multilevel_options(disk);
  options.refine_keeps_density = false;  // every step taken
  SquareMapStats factorised;
  map_to_square(disk, options, &factorised);
  ASSERT_GT(factorised.fine_steps, 0);
  for (bool laplacians : {false, true}) {
    options.iterative_from = 0;
    options.vertex_order_from = 0;
    options.iterative_laplacians = laplacians;
    SquareMapStats st;
    const std::vector<Vec2> uv = map_to_square(disk, options, &st);
    expect_multilevel_map_like(disk, uv, st, factorised);
    EXPECT_EQ(st.fine_reweighting, factorised.fine_reweighting);
    EXPECT_EQ(st.fine_steps, factorised.fine_steps);
  }
}

// A model's pieces are mapped side by side (their supernodal factorisations one at a time, blas_mutex;
// the orders CHOLMOD finds one at a time, metis_mutex): four multilevel maps at once, on every core,
// each the map it is alone, bit for bit.
TEST(Multilevel, MapsMadeSideBySideAreTheMapsMadeAlone) {
  const Disk disk = cat::torus_disk();
  SquareMapOptions options = multilevel_options(disk);
  options.supernodal_from = 0;  // every system supernodal, as a large piece's are
  options.refine_keeps_density = false;
  SquareMapStats alone_st;
  const std::vector<Vec2> alone = map_to_square(disk, options, &alone_st);
  ASSERT_GT(alone_st.coarse_vertices, 0u) << "the multilevel path was taken";
  ASSERT_GT(alone_st.fine_steps, 0);
  std::vector<std::vector<Vec2>> side_by_side(4);
  tbb::parallel_for(size_t(0), side_by_side.size(), [&](size_t i) { side_by_side[i] = map_to_square(disk, options, nullptr); });
  for (const std::vector<Vec2>& uv : side_by_side) EXPECT_EQ(uv, alone);
}

}  // namespace
}  // namespace tightex
