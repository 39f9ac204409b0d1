// The input's texture seams: found exactly (find_texture_seams), and preferred by the cut where there is
// a choice of equally short loops and paths.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cut/cut.hpp"
#include "cut/seams.hpp"
#include "genus_surfaces.hpp"
#include "mesh_catalogue.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

constexpr int kNu = 24, kNv = 24;

/// A torus (kNu x kNv grid) whose atlas is the grid itself, wrapped at column i0 and row j0: the input
/// has one texture seam along the meridian at i0 and one along the parallel at j0, nothing else.
TexturedMesh seamed_torus(int i0, int j0) {
  const cat::Geometry g = cat::torus_geometry(kNu, kNv, 1.0, 0.4);
  TexturedMesh m = cat::make_textured("seamed_torus", g.positions, g.triangles);
  // param_grid's triangles: per quad (i, j) in row order, {(i,j), (i+1,j), (i+1,j+1)} and
  // {(i,j), (i+1,j+1), (i,j+1)}.
  auto uv = [&](int i, int j, int di, int dj) {
    const int u = (i - i0 + kNu) % kNu + di, v = (j - j0 + kNv) % kNv + dj;
    return Vec2(0.05 + 0.9 * u / kNu, 0.05 + 0.9 * v / kNv);
  };
  for (int j = 0; j < kNv; ++j)
    for (int i = 0; i < kNu; ++i) {
      const size_t t = 2 * size_t(j * kNu + i);
      m.corner_uv[3 * t + 0] = uv(i, j, 0, 0), m.corner_uv[3 * t + 1] = uv(i, j, 1, 0), m.corner_uv[3 * t + 2] = uv(i, j, 1, 1);
      m.corner_uv[3 * t + 3] = uv(i, j, 0, 0), m.corner_uv[3 * t + 4] = uv(i, j, 1, 1), m.corner_uv[3 * t + 5] = uv(i, j, 0, 1);
    }
  return m;
}

size_t count(const std::vector<char>& flags) { return size_t(std::count(flags.begin(), flags.end(), 1)); }

TEST(TextureSeams, FoundExactly) {
  {  // planar projection: one chart, no seam
    const TexturedMesh m = cat::disk();
    const Surface s = prepare_surface(m, nullptr);
    EXPECT_EQ(count(find_texture_seams(m, split_components(s)[0])), 0u);
  }
  {  // the seamed torus: both halfedges of the kNv meridian edges and the kNu parallel edges
    const TexturedMesh m = seamed_torus(5, 3);
    const Surface s = prepare_surface(m, nullptr);
    const Surface c = split_components(s)[0];
    const auto seams = find_texture_seams(m, c);
    EXPECT_EQ(count(seams), 2u * (kNu + kNv));
    for (uint32_t h = 0; h < seams.size(); ++h)
      if (seams[h]) EXPECT_TRUE(seams[c.opposite[h]]) << "halfedge " << h;
  }
  {  // per-triangle atlas: every interior edge
    const TexturedMesh m = cat::perforated_plate(2);
    const Surface s = prepare_surface(m, nullptr);
    EXPECT_EQ(count(find_texture_seams(m, split_components(s)[0])), 3 * m.num_triangles());
  }
  {  // the same UVs but a second material on half the triangles: the material border is a seam
    TexturedMesh m = cat::disk();
    m.materials.push_back(m.materials[0]);
    const Surface s = prepare_surface(m, nullptr);
    for (size_t t = 0; t < m.num_triangles(); ++t) {
      const Vec3 centre = (m.positions[m.triangles[t][0]] + m.positions[m.triangles[t][1]] + m.positions[m.triangles[t][2]]) / 3;
      m.face_material[t] = centre.x() > 0 ? 1 : 0;
    }
    const Surface c = split_components(s)[0];
    const auto seams = find_texture_seams(m, c);
    size_t border = 0;  // halfedges whose two triangles differ in material, counted directly
    for (uint32_t h = 0; h < c.opposite.size(); ++h)
      if (c.opposite[h] != kNone)
        border += m.face_material[s.face_parent[c.face_parent[h / 3]]] != m.face_material[s.face_parent[c.face_parent[c.opposite[h] / 3]]];
    EXPECT_GT(border, 0u);
    EXPECT_EQ(count(seams), border);
  }
}

// After the handle loop (a meridian) is cut, the path joining the two sides of the cut goes once
// around the torus; the shortest is the inner equator (row kNv / 2). With the input's seam on the
// next row, 2.3% longer, the path follows the seam; with the seam on the outer equator (row 0, 67%
// longer) it does not. Either way the cut stays nearly as short as the shortest.
TEST(TextureSeams, CutFollowsThemWhereThereIsAChoice) {
  auto parallel_length = [](int j) {  // the polygon of row j
    const double radius = 1.0 + 0.4 * std::cos(2 * std::numbers::pi * j / kNv);
    return 2 * radius * kNu * std::sin(std::numbers::pi / kNu);
  };
  const double meridian = 2 * 0.4 * kNv * std::sin(std::numbers::pi / kNv);
  const double shortest = meridian + parallel_length(kNv / 2);
  for (int j0 : {kNv / 2 + 1, 0}) {
    SCOPED_TRACE("seam parallel at row " + std::to_string(j0));
    const TexturedMesh m = seamed_torus(kNu / 3, j0);
    const Surface s = prepare_surface(m, nullptr);
    const Surface c = split_components(s)[0];
    const auto seams = find_texture_seams(m, c);
    CutStats st;
    cut_to_disk(c, {.holes = HoleMode::kCut, .seams = seams}, &st);
    ASSERT_EQ(st.handle_loops.size(), 1u);
    EXPECT_NEAR(st.handle_loops[0], meridian, 1e-9);
    EXPECT_GE(st.seam_length, shortest * (1 - 1e-9));
    EXPECT_LE(st.seam_length, shortest * 1.03);
    if (j0 != 0) {
      EXPECT_GE(st.seam_on_input_seams, parallel_length(j0) * (1 - 1e-9));
    } else {
      EXPECT_LE(st.seam_on_input_seams, meridian * (1 + 1e-9));
    }
    CutStats plain;  // no seams given: nothing preferred, nothing counted
    cut_to_disk(c, {.holes = HoleMode::kCut}, &plain);
    EXPECT_NEAR(plain.seam_length, shortest, 1e-9);
    EXPECT_EQ(plain.seam_on_input_seams, 0.0);
  }
}

}  // namespace
}  // namespace tightex
