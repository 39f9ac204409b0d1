// The choice of the square's four corners (choose_corners; docs/corners.md): the turning-angle rule
// finds a rectangle's corners, and both rules give four distinct corners in boundary order and a
// fold-free map on every catalogue component.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "report/report.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

const char* rule_name(CornerRule r) { return r == CornerRule::kTurningAngle ? "turning" : "arcs"; }

std::vector<double> arc_lengths(const Disk& disk) {
  const auto& b = disk.boundary;
  std::vector<double> arc(b.size() + 1, 0.0);
  for (size_t i = 0; i < b.size(); ++i)
    arc[i + 1] = arc[i] + (disk.mesh.positions[b[(i + 1) % b.size()]] - disk.mesh.positions[b[i]]).norm();
  return arc;
}

/// A flat nu x nv grid (unit spacing, z = 0) as a disk.
Disk flat_grid(int nu, int nv, const std::function<Vec3(int, int)>& at) {
  const cat::Geometry g = cat::param_grid(nu, nv, false, false, at);
  const auto comps = split_components(prepare_surface(cat::make_textured("grid", g.positions, g.triangles), nullptr));
  EXPECT_EQ(comps.size(), 1u);
  return cut_to_disk(comps.at(0), {.holes = HoleMode::kFill}, nullptr);
}

// On a flat rectangle (a square, and 2:1 and 3:1 ones whose short sides are well above the 10% floor)
// the turning-angle rule puts the four corners of the square map on the rectangle's four corners.
TEST(Corners, TurningAngleFindsTheCornersOfARectangle) {
  for (auto [nu, nv] : {std::pair{9, 9}, std::pair{17, 9}, std::pair{25, 9}, std::pair{9, 25}}) {
    SCOPED_TRACE(std::to_string(nu) + "x" + std::to_string(nv));
    // Sheared a little inside (not on the border), so the interior is not a regular grid.
    const Disk disk = flat_grid(nu, nv, [&](int i, int j) {
      const bool inside = i > 0 && j > 0 && i < nu - 1 && j < nv - 1;
      return Vec3(i + (inside ? 0.2 * ((i * 7 + j * 3) % 5 - 2) / 2.0 : 0.0), j, 0);
    });
    const std::set<std::pair<int, int>> want{{0, 0}, {nu - 1, 0}, {nu - 1, nv - 1}, {0, nv - 1}};
    const auto idx = choose_corners(disk, arc_lengths(disk), CornerRule::kTurningAngle);
    std::set<std::pair<int, int>> got;
    for (size_t i : idx) {
      const Vec3& p = disk.mesh.positions[disk.boundary[i]];
      got.insert({int(std::lround(p.x())), int(std::lround(p.y()))});
    }
    EXPECT_EQ(got, want);
    // Through map_to_square: those vertices land on the square's corners, and nothing folds.
    SquareMapOptions mo;
    mo.corners = CornerRule::kTurningAngle;
    SquareMapStats st;
    const auto uv = map_to_square(disk, mo, &st);
    static const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    got.clear();
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(uv[st.corners[k]], kCorner[k]);
      const Vec3& p = disk.mesh.positions[st.corners[k]];
      got.insert({int(std::lround(p.x())), int(std::lround(p.y()))});
    }
    EXPECT_EQ(got, want);
    EXPECT_EQ(count_folds(disk.mesh, uv), 0u);
  }
}

// Equal arcs on a 3:1 rectangle cannot sit on its corners (the sides are 1/8 and 3/8 of the length):
// the two rules differ where the test above says they should.
TEST(Corners, EqualArcsSplitTheLengthInQuarters) {
  const Disk disk = flat_grid(25, 9, [](int i, int j) { return Vec3(i, j, 0); });
  const auto arc = arc_lengths(disk);
  const auto idx = choose_corners(disk, arc, CornerRule::kEqualArcs);
  const double total = arc.back();
  for (int k = 0; k < 4; ++k) {
    const double len = std::fmod(arc[idx[(k + 1) % 4]] - arc[idx[k]] + total, total);
    EXPECT_NEAR(len, total / 4, 1.0 + 1e-9) << "arc " << k;  // within one edge of a quarter
  }
}

// Both rules, every catalogue component, both hole modes, the harmonic and the area map: four distinct
// corners in counter-clockwise boundary order, each arc between them a fair share of the length
// (turning rule: >= 10% unless the boundary has too few vertices), and no fold (the harmonic map may
// report a crowded region instead).
TEST(Corners, BothRulesGiveOrderedCornersAndFoldFreeMapsOnTheCatalogue) {
  for (const auto& [name, make] : cat::catalogue()) {
    const auto comps = split_components(prepare_surface(make(), nullptr));
    for (HoleMode mode : {HoleMode::kFill, HoleMode::kCut})
      for (size_t c = 0; c < comps.size(); ++c) {
        const Disk disk = cut_to_disk(comps[c], {.holes = mode}, nullptr);
        const size_t nb = disk.boundary.size();
        const auto arc = arc_lengths(disk);
        for (CornerRule rule : {CornerRule::kEqualArcs, CornerRule::kTurningAngle})
          for (bool area : {false, true}) {
            SCOPED_TRACE(name + (mode == HoleMode::kFill ? " fill" : " cut") + " component " + std::to_string(c) + " " + rule_name(rule) +
                         (area ? " area" : " harmonic"));
            const auto idx = choose_corners(disk, arc, rule);
            if (nb == 3) {
              EXPECT_EQ(idx, (std::array<size_t, 4>{0, 1, 2, 2}));
            } else {
              for (int k = 0; k < 4; ++k) ASSERT_LT(idx[k], nb);
              const std::set<size_t> distinct(idx.begin(), idx.end());
              EXPECT_EQ(distinct.size(), 4u);
              for (int k = 1; k < 4; ++k)
                EXPECT_GT((idx[k] + nb - idx[0]) % nb, (idx[k - 1] + nb - idx[0]) % nb) << "corner " << k << " out of order";
              if (rule == CornerRule::kTurningAngle && nb >= 40)
                for (int k = 0; k < 4; ++k) {
                  const double len = std::fmod(arc[idx[(k + 1) % 4]] - arc[idx[k]] + arc[nb], arc[nb]);
                  EXPECT_GE(len, 0.1 * arc[nb] * (1 - 1e-12)) << "arc " << k;
                }
            }
            SquareMapOptions mo;
            mo.rect_width = mo.rect_height = 256;
            mo.corners = rule;
            if (area) {
              mo.face_target.resize(disk.mesh.num_faces());
              for (size_t f = 0; f < mo.face_target.size(); ++f) {
                const Tri& t = disk.mesh.triangles[f];
                mo.face_target[f] =
                    std::max(triangle_area(disk.mesh.positions[t[0]], disk.mesh.positions[t[1]], disk.mesh.positions[t[2]]), 1e-300);
              }
            }
            SquareMapStats st;
            const auto uv = map_to_square(disk, mo, &st);
            EXPECT_EQ(count_folds(disk.mesh, uv), 0u);
            // The harmonic map may crowd a region below what written coordinates hold (the holey slab cut
            // open, turning rule: 35 triangles of 3e-14 .. 2e-12 texels): it must say so, and where, so
            // the pipeline slits there (or maps that component with the area map).
            if (area || st.flipped == 0)
              EXPECT_EQ(st.flipped, 0u);
            else
              EXPECT_NE(st.crowded_vertex, kNone);
            if (nb > 3) {
              static const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
              for (int k = 0; k < 4; ++k) EXPECT_EQ(uv[st.corners[k]], kCorner[k]) << "corner " << k;
            }
          }
      }
  }
}

// The option reaches the map through optimize() and the report says which rule ran.
TEST(Corners, OptionReachesThePipeline) {
  Options opt;
  opt.size = 64;
  opt.corners = CornerRule::kTurningAngle;
  const Result r = optimize(cat::disk(), opt);
  EXPECT_EQ(report_json(r.report)["options"]["corners"], "turning");
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
}

}  // namespace
}  // namespace tightex
