// Handle loops: the radius-limited tree-cotree behind the loop search keeps its promises, and
// remove_handles tightens a loop found off a handle's waist down to the waist.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <numbers>

#include "cut/graph.hpp"
#include "genus_surfaces.hpp"
#include "mesh_catalogue.hpp"
#include "prepare/components.hpp"
#include "prepare/handles.hpp"
#include "prepare/repair.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

/// The loop closed by tree_cotree's first leftover edge: that edge plus both tree paths to the root.
std::vector<uint32_t> first_loop(const Surface& s, const EdgeGraph& g, const TreeCotree& tc) {
  const uint32_t e = tc.leftover.front();
  std::vector<uint32_t> edges{e};
  for (uint32_t v : {s.from(g.edge_halfedge[e]), s.to(g.edge_halfedge[e])})
    for (; tc.pred[v] != kNone; v = other_end(s, g, tc.pred[v], v)) edges.push_back(tc.pred[v]);
  return edges;
}

/// Cutting along `edges` (an edge used twice, on the shared stem, counts as not cut) lowers the genus.
bool non_separating(const Surface& s, const EdgeGraph& g, const std::vector<uint32_t>& edges) {
  std::vector<int> uses(g.num_edges(), 0);
  for (uint32_t e : edges) uses[e]++;
  uint32_t groups = 0;
  const auto corner = group_corners(s, [&](uint32_t h) { return uses[g.halfedge_edge[h]] != 1; }, &groups);
  const Surface cut = regroup(s, corner, groups);
  std::vector<uint32_t> label;
  return face_components(cut, label) == 1 && topology_of(cut).genus() < topology_of(s).genus();
}

// With radius (c + longest edge) / 2 the limited search finds the same cheapest loop cost c as the
// unlimited one; with a smaller radius every loop it leaves over is still non-separating (and below
// (c - longest edge) / 2 there is none, as none cheaper than c exists).
TEST(TreeCotree, RadiusKeepsTheCheapestLoopAndNeverSeparates) {
  const std::vector<std::pair<std::string, TexturedMesh>> meshes = {
      {"torus", cat::torus()}, {"double_torus", cat::double_torus()}, {"arches_g5", cat::arched_block(5)}};
  for (const auto& [name, m] : meshes) {
    const Surface s = split_components(prepare_surface(m, nullptr))[0];
    const EdgeGraph g(s);
    const double longest = *std::max_element(g.cost.begin(), g.cost.end());
    size_t checked = 0;
    for (uint32_t root = 0; root < s.num_vertices(); root += 17) {
      SCOPED_TRACE(name + " root " + std::to_string(root));
      const TreeCotree full = tree_cotree(s, g, {root}, {});
      ASSERT_EQ(full.leftover.size(), size_t(2 * topology_of(s).genus()));
      const double c = full.loop_length(s, g, full.leftover.front());
      const TreeCotree near = tree_cotree(s, g, {root}, {}, (c + longest) / 2);
      ASSERT_FALSE(near.leftover.empty());
      EXPECT_NEAR(near.loop_length(s, g, near.leftover.front()), c, 1e-12 * c);
      EXPECT_TRUE(tree_cotree(s, g, {root}, {}, (c - longest) / 2 * 0.999).leftover.empty());
      for (double f : {0.55, 0.8, 1.2}) {
        const TreeCotree part = tree_cotree(s, g, {root}, {}, f * c);
        for (size_t i = 0; i < part.leftover.size(); ++i) {
          ASSERT_TRUE(std::isfinite(part.loop_length(s, g, part.leftover[i])));
          TreeCotree one = part;
          one.leftover = {part.leftover[i]};
          EXPECT_TRUE(non_separating(s, g, first_loop(s, g, one))) << "radius " << f << " c, leftover " << i;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 0u) << name;
  }
}

// A torus whose tube narrows to a waist: the meridians range from 2 pi 0.45 down to 2 pi 0.12 at the
// waist. The loop search starts from roots wherever the global tree-cotree puts them; tightening must
// bring the loop down to the waist.
TEST(RemoveHandles, TightensTheLoopToTheWaist) {
  const int nu = 96, nv = 24;
  const double R = 1.0, theta0 = 0.7;
  auto minor = [&](double t) { return 0.285 + 0.165 * std::cos(t - theta0); };  // 0.45 .. 0.12
  const cat::Geometry g = cat::param_grid(nu, nv, true, true, [&](int i, int j) {
    const double t = 2 * std::numbers::pi * i / nu, p = 2 * std::numbers::pi * j / nv, r = minor(t);
    return Vec3((R + r * std::cos(p)) * std::cos(t), (R + r * std::cos(p)) * std::sin(t), r * std::sin(p));
  });
  const TexturedMesh m = cat::make_textured("waisted_torus", g.positions, g.triangles);
  const Surface s = split_components(prepare_surface(m, nullptr))[0];
  ASSERT_EQ(topology_of(s).genus(), 1);
  std::vector<double> loops;
  remove_handles(s, &loops);
  ASSERT_EQ(loops.size(), 1u);
  const double waist = 2 * nv * 0.12 * std::sin(std::numbers::pi / nv);  // the polygon at the waist
  EXPECT_GE(loops[0], waist * (1 - 1e-9));
  EXPECT_LE(loops[0], waist * 1.02);  // measured: 0.752037 for a waist of 0.751831; 0.914767 untightened
}

// The search tries its roots several at a time where there are cores for it (LoopSearch::try_roots),
// each with the radius it would get one at a time: the loops cut and the surface left must be those of
// the search on one thread.
TEST(RemoveHandles, TheSameLoopsWhateverTheRootsSearchedAtOnce) {
  const std::vector<std::pair<std::string, TexturedMesh>> meshes = {
      {"double_torus", cat::double_torus()}, {"plate_g8", cat::perforated_plate(8)}, {"arches_g5", cat::arched_block(5)}};
  for (const auto& [name, m] : meshes) {
    SCOPED_TRACE(name);
    const Surface s = split_components(prepare_surface(m, nullptr))[0];
    auto search_on = [&](int threads, std::vector<double>& loops) {
      Surface out;
      tbb::task_arena(threads).execute([&] { out = remove_handles(s, &loops); });
      return out;
    };
    std::vector<double> one_loops, four_loops;
    const Surface one = search_on(1, one_loops), four = search_on(4, four_loops);
    ASSERT_EQ(one_loops.size(), size_t(topology_of(s).genus()));
    EXPECT_EQ(four_loops, one_loops);
    EXPECT_EQ(four.triangles, one.triangles);
    EXPECT_EQ(four.vertex_parent, one.vertex_parent);
    EXPECT_EQ(topology_of(four).genus(), 0);
  }
}

}  // namespace
}  // namespace tightex
