// The safety net of the pipeline: when the full method throws on a component, the plain cut graph
// must still give a disk, and the map onto the square must still be fold-free.
#include <gtest/gtest.h>

#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "repair/repair.hpp"
#include "topology/topology.hpp"

using namespace tightex;

TEST(PlainCutFallback, EveryCatalogueComponentBecomesAFoldFreeDisk) {
  for (const auto& [name, make] : tightex::testing::catalogue()) {
    SCOPED_TRACE(name);
    const Surface s = prepare_surface(make(), nullptr);
    for (const Surface& comp : split_components(s)) {
      CutStats st;
      const Disk d = cut_to_disk(comp, HoleMode::kFill, &st, {}, nullptr, true);
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
