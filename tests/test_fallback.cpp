// The safety net of the pipeline: when the full method throws on a component, the plain cut graph
// must still give a disk, and the map onto the square must still be fold-free.
#include <gtest/gtest.h>

#include <cmath>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"

using namespace tightex;

TEST(PlainCutFallback, EveryCatalogueComponentBecomesAFoldFreeDisk) {
  for (const auto& [name, make] : tightex::testing::catalogue()) {
    SCOPED_TRACE(name);
    const Surface s = prepare_surface(make(), nullptr);
    for (const Surface& comp : split_components(s)) {
      CutStats st;
      const Disk d = cut_to_disk(comp, {.holes = HoleMode::kFill, .method = CutMethod::kPlain}, &st);
      const auto loops = boundary_loops(d.mesh);
      ASSERT_EQ(loops.size(), 1u);
      EXPECT_EQ(topology_of(d.mesh).euler(), 1);
      EXPECT_EQ(st.holes_filled, 0u);  // the plain cut adds no scaffolding
      for (uint32_t p : d.mesh.face_parent) EXPECT_NE(p, kNone);
      if (d.boundary.size() < 4) continue;  // a lone triangle: three corners
      SquareMapStats ms;
      const auto uv = map_to_square(d, {}, &ms);
      EXPECT_EQ(count_folds(d.mesh, uv), 0u);
    }
  }
}

#include "core/error.hpp"
#include "tightex/tightex.hpp"

// The library's entry point refuses a mesh it cannot trust with an InputError naming the element.
TEST(LibraryEntry, RefusesNonFiniteAndOutOfRangeInput) {
  const TexturedMesh good = tightex::testing::catalogue().front().second();
  Options opt;
  opt.size = 64;
  TexturedMesh nan_position = good;
  nan_position.positions[3].y() = std::nan("");
  EXPECT_THROW(optimize(nan_position, opt), InputError);
  TexturedMesh bad_index = good;
  bad_index.triangles[0][1] = uint32_t(good.positions.size() + 5);
  EXPECT_THROW(optimize(bad_index, opt), InputError);
  TexturedMesh bad_uv = good;
  bad_uv.corner_uv[4].x() = INFINITY;
  EXPECT_THROW(optimize(bad_uv, opt), InputError);
  TexturedMesh bad_material = good;
  bad_material.face_material[0] = 7;
  EXPECT_THROW(optimize(bad_material, opt), InputError);
  EXPECT_NO_THROW(optimize(good, opt));
}
