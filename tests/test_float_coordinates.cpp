// keep_orientation_in_float: a sliver that is positive in doubles but folds or collapses once its
// texture coordinates are written as floats (glTF, PLY) is fixed by moving a vertex a few float steps.
#include <gtest/gtest.h>

#include "layout/float_coordinates.hpp"
#include "layout/layout.hpp"

namespace tightex {
namespace {

/// Three triangles splitting (a, b, d) at c, where c lies `height` above the edge a-b: the triangle
/// (a, b, c) is a sliver of that height in the unit square.
struct SplitTriangle {
  Surface disk;
  std::vector<Vec2> uv;
  explicit SplitTriangle(double height) {
    uv = {Vec2(0.25, 0.5), Vec2(0.75, 0.5), Vec2(0.5, 0.5 + height), Vec2(0.5, 0.9)};
    disk.positions.assign(uv.size(), Vec3::Zero());
    disk.triangles = {Tri{0, 1, 2}, Tri{1, 3, 2}, Tri{3, 0, 2}};
  }
};

/// A double rounded to float. Not inlined: GCC 12's SLP vectorizer at -O3 drops a paired
/// double -> float -> double round trip (float_coordinates.cpp).
[[gnu::noinline]] float to_float(double x) { return float(x); }

/// Twice the signed area of triangle f as a writer stores it: the pixel over the image's size, v up
/// (PLY) or down (glTF: 1 - v, which mirrors it; its sign is turned back), each rounded to float.
double written_area(const Surface& disk, const std::vector<Vec2>& uv, uint32_t f, const Rect& r, int w, int h, bool v_down) {
  std::array<std::array<double, 2>, 3> p;
  for (int k = 0; k < 3; ++k) {
    const Vec2 px = rect_pixel(r, uv[disk.triangles[f][k]]);
    const double u = px.x() / w, v = 1.0 - px.y() / h;
    p[k] = {to_float(u), v_down ? to_float(1.0 - v) : to_float(v)};
  }
  const double area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
  return v_down ? -area : area;
}

TEST(FloatCoordinates, ASliverBelowFloatPrecisionIsMovedUntilEveryTriangleIsPositiveInFloats) {
  SplitTriangle t(1e-9);  // a float step at 0.5 is 6e-8: the sliver's three v round to one value
  const Rect r{0, 0, 0, 1000, 1000};
  ASSERT_FALSE(written_area(t.disk, t.uv, 0, r, 1000, 1000, false) > 0);
  const std::vector<Vec2> before = t.uv;
  const FloatGuard g = keep_orientation_in_float(t.disk, r, 1000, 1000, t.uv);
  EXPECT_EQ(g.moved, 1u);
  EXPECT_EQ(g.unfixed, 0u);
  for (uint32_t f = 0; f < 3; ++f)
    for (bool down : {false, true}) EXPECT_GT(written_area(t.disk, t.uv, f, r, 1000, 1000, down), 0) << "face " << f << " down " << down;
  size_t changed = 0;
  for (size_t v = 0; v < before.size(); ++v) {
    changed += before[v] != t.uv[v];
    EXPECT_LT((before[v] - t.uv[v]).norm(), 1e-6) << "vertex " << v << " moved more than a few float steps";
  }
  EXPECT_EQ(changed, 1u);
}

TEST(FloatCoordinates, AMapPositiveInFloatsIsLeftAsItIs) {
  SplitTriangle t(1e-3);
  const Rect r{0, 24, 40, 600, 300};  // a rectangle inside a larger image
  const std::vector<Vec2> before = t.uv;
  const FloatGuard g = keep_orientation_in_float(t.disk, r, 1024, 512, t.uv);
  EXPECT_EQ(g.moved, 0u);
  EXPECT_EQ(g.unfixed, 0u);
  EXPECT_EQ(t.uv, before);
}

TEST(FloatCoordinates, ScaffoldingIsNotWrittenAndNotMoved) {
  SplitTriangle t(1e-9);
  t.disk.input_face = {kNone, 1, 2};  // the sliver is a hole's cap: not in the output
  t.disk.input_corner.assign(9, 0);
  const std::vector<Vec2> before = t.uv;
  const FloatGuard g = keep_orientation_in_float(t.disk, Rect{0, 0, 0, 1000, 1000}, 1000, 1000, t.uv);
  EXPECT_EQ(g.moved, 0u);
  EXPECT_EQ(t.uv, before);
}

}  // namespace
}  // namespace tightex
