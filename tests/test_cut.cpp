// The cut's two halves apart (paper §4.2): compute_cut_graph chooses the edges, cut_along_edges opens
// the surface along them. On the catalogue's connected surfaces the pair gives a disk: one boundary
// loop, Euler characteristic 1, every triangle kept with its map back.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "core/cut_along_edges.hpp"
#include "core/graph.hpp"
#include "cut/cut_graph.hpp"
#include "mesh_catalogue.hpp"
#include "prepare/components.hpp"
#include "prepare/holes.hpp"
#include "prepare/repair.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

std::vector<Surface> components_of(const TexturedMesh& mesh) { return split_components(prepare_surface(mesh, nullptr)); }

/// Cuts `s` along its own cut graph and checks the disk and its maps back to `s`.
void expect_cut_to_disk(const Surface& s, const std::string& name) {
  const EdgeGraph g(s);
  const CutGraph cut = compute_cut_graph(s, g);
  ASSERT_EQ(cut.cut_edge.size(), g.num_edges()) << name;
  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (cut.cut_edge[e]) EXPECT_NE(s.opposite[g.edge_halfedge[e]], kNone) << name << ": boundary edge " << e << " in the cut graph";
  const Surface d = cut_along_edges(s, g, cut.cut_edge);
  EXPECT_EQ(boundary_loops(d).size(), 1u) << name << " (" << cut.method << ")";
  EXPECT_EQ(topology_of(d).euler(), 1) << name << " (" << cut.method << ")";
  ASSERT_EQ(d.num_faces(), s.num_faces()) << name;
  for (uint32_t f = 0; f < d.num_faces(); ++f) {
    EXPECT_EQ(d.face_parent[f], f) << name;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(d.vertex_parent[d.triangles[f][k]], s.triangles[f][k]) << name;
  }
  EXPECT_EQ(d.input_face, s.input_face) << name;
  EXPECT_EQ(d.input_corner, s.input_corner) << name;
}

TEST(CutGraph, CatalogueSurfacesBecomeDisks) {
  for (const auto& [name, make] : cat::catalogue()) {
    const auto comps = components_of(make());
    for (size_t c = 0; c < comps.size(); ++c) expect_cut_to_disk(comps[c], name + " component " + std::to_string(c));
  }
}

TEST(CutGraph, MethodFollowsTopology) {
  const EdgeGraph disk_graph(components_of(cat::disk())[0]);
  EXPECT_EQ(compute_cut_graph(components_of(cat::disk())[0], disk_graph).method, "disk");
  const Surface sphere = components_of(cat::sphere())[0];
  const CutGraph path = compute_cut_graph(sphere, EdgeGraph(sphere));
  EXPECT_EQ(path.method, "path");
  EXPECT_GE(std::count(path.cut_edge.begin(), path.cut_edge.end(), 1), 2);  // a one-edge cut opens nothing
  const Surface torus = components_of(cat::torus())[0];
  EXPECT_EQ(compute_cut_graph(torus, EdgeGraph(torus)).method, "cut-graph");
}

TEST(CutGraph, CappedSurfaceBecomesDisk) {
  const Surface s = components_of(cat::sphere_with_holes())[0];
  const Surface capped = fill_holes(s, boundary_loops(s));
  ASSERT_EQ(boundary_loops(capped).size(), 0u);
  expect_cut_to_disk(capped, "sphere_with_holes, every hole capped");
}

TEST(CutAlongEdges, NothingCutKeepsTheTopology) {
  const Surface s = components_of(cat::open_cylinder())[0];
  const EdgeGraph g(s);
  const Surface d = cut_along_edges(s, g, std::vector<char>(g.num_edges(), 0));
  EXPECT_EQ(d.num_vertices(), s.num_vertices());
  EXPECT_EQ(topology_of(d).euler(), topology_of(s).euler());
  EXPECT_EQ(boundary_loops(d).size(), boundary_loops(s).size());
  EXPECT_EQ(d.opposite, s.opposite);
}

}  // namespace
}  // namespace tightex
