// orient_chart: a chart's square turned by quarter turns so that the input's texture axes point the way
// they did (printed matter upright), exactly, fold-free, on the unit square.
#include <gtest/gtest.h>

#include <cmath>

#include "layout/chart_orientation.hpp"
#include "layout/layout.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"

namespace tightex {
namespace {

using namespace tightex::testing;

/// A flat n x n grid of the unit square (z = 0) with its input texture coordinates axis-aligned (the
/// catalogue's planar ones), and its disk: the same triangles, each its own input triangle.
struct Grid {
  TexturedMesh input;
  Surface disk;
  explicit Grid(int n) {
    Geometry g;
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) g.add(Vec3(double(x) / n, double(y) / n, 0));
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
        g.triangles.push_back({a, b, d});
        g.triangles.push_back({a, d, c});
      }
    input = make_textured("grid", g.positions, g.triangles, gradient_image(64, 64));
    disk.positions = g.positions;
    disk.triangles = g.triangles;
    for (uint32_t f = 0; f < disk.num_faces(); ++f) {
      disk.input_face.push_back(f);
      disk.input_corner.insert(disk.input_corner.end(), {0, 1, 2});
    }
  }
  /// The grid's square map turned by `degrees` about the centre and shrunk to stay inside the square.
  std::vector<Vec2> turned_map(double degrees) const {
    const double a = degrees * M_PI / 180;
    std::vector<Vec2> uv;
    for (const Vec3& p : disk.positions) {
      const Vec2 d(p.x() - 0.5, p.y() - 0.5);
      uv.push_back(Vec2(0.5, 0.5) + 0.7 * Vec2(std::cos(a) * d.x() - std::sin(a) * d.y(), std::sin(a) * d.x() + std::cos(a) * d.y()));
    }
    return uv;
  }
};

double min_signed_area(const Surface& disk, const std::vector<Vec2>& uv) {
  double least = 1e300;
  for (const Tri& f : disk.triangles) least = std::min(least, signed_area(uv[f[0]], uv[f[1]], uv[f[2]]));
  return least;
}

// In a square rectangle (or within 1% of one) a quarter turn keeps the texel stretch: the one that leaves the least turn is
// taken, and the map is the same map turned exactly (same areas, still positive, still inside).
TEST(ChartOrientation, ASquareChartTurnsByTheQuarterThatLeavesTheLeastTurn) {
  const Grid grid(6);
  for (const Rect& square : {Rect{0, 0, 0, 64, 64}, Rect{0, 0, 0, 400, 397}})  // within 1% of square
    for (const double degrees : {0.0, 10.0, 100.0, -100.0, 170.0, 260.0}) {
      std::vector<Vec2> uv = grid.turned_map(degrees);
      const std::vector<Vec2> before = uv;
      const ChartTurn turn = orient_chart(grid.input, grid.disk, square, uv);
      const double tolerance = square.w == square.h ? 1e-6 : 0.5;  // 400 x 397 texels shear the turn a little
      EXPECT_NEAR(std::remainder(turn.mean_turn_deg - degrees, 360.0), 0.0, tolerance) << degrees;
      const double left = std::remainder(degrees + 90.0 * turn.quarter_turns, 360.0);
      EXPECT_LE(std::abs(left), 45.0 + 1e-9) << degrees;
      EXPECT_NEAR(std::abs(left), std::abs(std::remainder(degrees, 90.0)), 1e-9) << degrees;
      EXPECT_LE(std::abs(std::remainder(turn.mean_turn_deg + 90.0 * turn.quarter_turns, 360.0)), 45.0) << degrees;
      // The same map, turned: every triangle's area kept, orientation kept, on the unit square.
      for (size_t f = 0; f < grid.disk.num_faces(); ++f) {
        const Tri& t = grid.disk.triangles[f];
        EXPECT_NEAR(signed_area(uv[t[0]], uv[t[1]], uv[t[2]]), signed_area(before[t[0]], before[t[1]], before[t[2]]), 1e-15);
      }
      EXPECT_GT(min_signed_area(grid.disk, uv), 0.0);
      for (const Vec2& s : uv) EXPECT_TRUE(s.x() >= 0 && s.x() <= 1 && s.y() >= 0 && s.y() <= 1);
      // Upright now: a second call turns nothing.
      std::vector<Vec2> again = uv;
      EXPECT_EQ(orient_chart(grid.input, grid.disk, square, again).quarter_turns, 0) << degrees;
      EXPECT_EQ(again, uv);
    }
}

// A quarter turn of a long rectangle's square would swap its stretch: only the half turn is tried.
TEST(ChartOrientation, ALongChartOnlyTurnsHalfway) {
  const Grid grid(6);
  const Rect wide{0, 0, 0, 128, 32};
  for (const double degrees : {0.0, 30.0, 100.0, 200.0, -60.0}) {
    std::vector<Vec2> uv = grid.turned_map(degrees);
    const ChartTurn turn = orient_chart(grid.input, grid.disk, wide, uv);
    EXPECT_TRUE(turn.quarter_turns == 0 || turn.quarter_turns == 2) << degrees;
    std::vector<Vec2> again = uv;
    const ChartTurn second = orient_chart(grid.input, grid.disk, wide, again);
    EXPECT_EQ(second.quarter_turns, 0) << degrees;
    EXPECT_LE(std::abs(second.mean_turn_deg), 90.0 + 1e-9) << degrees;
    EXPECT_GT(min_signed_area(grid.disk, uv), 0.0);
  }
}

// docs/metrics.md's texture axes angle folds quarter turns away: turning a chart upright does not
// change it; an upright chart of an axis-aligned input measures 0.
TEST(ChartOrientation, QuarterTurnsLeaveTheTextureAxesAngle) {
  const Grid grid(4);
  const Rect square{0, 0, 0, 64, 64};
  std::vector<Vec2> uv = grid.turned_map(100);
  auto mean_angle = [&](const std::vector<Vec2>& map) {
    double sum = 0, area = 0;
    for (size_t f = 0; f < grid.disk.num_faces(); ++f) {
      const Tri& t = grid.disk.triangles[f];
      const std::array<Vec2, 3> in{grid.input.sampled_uv(f, 0), grid.input.sampled_uv(f, 1), grid.input.sampled_uv(f, 2)};
      const double a = texture_axes_angle(in, Vec2(64, 64), {map[t[0]], map[t[1]], map[t[2]]}, Vec2(64, 64));
      const double w = triangle_area(grid.disk.positions, t);
      sum += a * w, area += w;
    }
    return sum / area;
  };
  const double before = mean_angle(uv);
  EXPECT_NEAR(before, 10.0, 1e-9);
  orient_chart(grid.input, grid.disk, square, uv);
  EXPECT_NEAR(mean_angle(uv), before, 1e-9);
  std::vector<Vec2> straight = grid.turned_map(-90);
  orient_chart(grid.input, grid.disk, square, straight);
  EXPECT_NEAR(mean_angle(straight), 0.0, 1e-9);
}

}  // namespace
}  // namespace tightex
