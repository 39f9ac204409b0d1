#include "layout/float_coordinates.hpp"

#include <cmath>

#include "layout/layout.hpp"

namespace tightex {

namespace {

/// A double rounded to float as a writer stores it. Not inlined: GCC 12's SLP vectorizer at -O3 drops
/// the round trip double -> float -> double where it pairs two of them (a float's value then reads back
/// as the double it came from), and the check would see coordinates no file holds.
[[gnu::noinline]] float to_float(double x) { return float(x); }

/// A disk vertex's texture coordinate as the output model holds it (u right, v up: the pixel divided by
/// the image's size), in doubles.
Vec2 output_uv(const Rect& r, int width, int height, const Vec2& s) {
  const Vec2 px = rect_pixel(r, s);
  return Vec2(px.x() / width, 1.0 - px.y() / height);
}

/// The coordinate as the writers store it: in doubles (OBJ), and as floats with v up (PLY: float(v)) or
/// down (glTF: float(1 - v)).
struct Stored {
  Vec2 uv;
  float u, v_up, v_down;
};
Stored stored(const Vec2& uv) { return {uv, to_float(uv.x()), to_float(uv.y()), to_float(1.0 - uv.y())}; }

/// The unit-square point whose output coordinate is (u, v) (output_uv inverted, up to rounding).
Vec2 unit_point(const Rect& r, int width, int height, double u, double v) {
  const double px = u * width, py = (1.0 - v) * height;
  return Vec2((px - r.x - 0.5 + kChartInset) / (r.w - 1 + 2 * kChartInset),
              1.0 - (py - r.y - 0.5 + kChartInset) / (r.h - 1 + 2 * kChartInset));
}

/// Twice the signed area of a triangle of float coordinates, computed exactly enough in doubles.
double float_area(double au, double av, double bu, double bv, double cu, double cv) {
  return (bu - au) * (cv - av) - (bv - av) * (cu - au);
}

/// Float steps tried per axis around a vertex: a sliver is a few steps high at most.
constexpr int kMaxSteps = 4;

float stepped(float x, int steps) {
  for (; steps > 0; --steps) x = std::nextafter(x, 2.0f);
  for (; steps < 0; ++steps) x = std::nextafter(x, -2.0f);
  return x;
}

class Guard {
 public:
  Guard(const Surface& disk, const Rect& r, int width, int height, std::vector<Vec2>& uv)
      : disk_(disk), r_(r), width_(width), height_(height), uv_(uv), out_(uv.size()) {
    for (size_t v = 0; v < uv.size(); ++v) out_[v] = stored(output_uv(r, width, height, uv[v]));
  }

  /// Whether a face keeps its orientation in every way the writers store it: doubles (OBJ), floats with
  /// v up (PLY: float(v)) and down (glTF: float(1 - v), which mirrors the triangle).
  bool positive(uint32_t face) const {
    const Stored &a = out_[disk_.triangles[face][0]], &b = out_[disk_.triangles[face][1]], &c = out_[disk_.triangles[face][2]];
    return signed_area(a.uv, b.uv, c.uv) > 0 && float_area(a.u, a.v_up, b.u, b.v_up, c.u, c.v_up) > 0 &&
           float_area(a.u, a.v_down, b.u, b.v_down, c.u, c.v_down) < 0;
  }
  bool real(uint32_t face) const { return disk_.input_face.empty() || disk_.input_face[face] != kNone; }

  std::vector<uint32_t> bad_faces() const {
    std::vector<uint32_t> bad;
    for (uint32_t face = 0; face < disk_.num_faces(); ++face)
      if (real(face) && !positive(face)) bad.push_back(face);
    return bad;
  }

  /// Moves vertex v (the faces `around` it) to the nearest point, by float steps of its coordinates on
  /// each axis, where all its real faces are positive; false where none within kMaxSteps is.
  bool move(uint32_t v, const std::vector<uint32_t>& around) {
    const Stored was = out_[v];
    for (int ring = 1; ring <= kMaxSteps; ++ring)
      for (int du = -ring; du <= ring; ++du)
        for (int dv = -ring; dv <= ring; ++dv) {
          if (std::max(std::abs(du), std::abs(dv)) != ring) continue;
          const Vec2 s = unit_point(r_, width_, height_, stepped(was.u, du), stepped(was.v_up, dv));
          out_[v] = stored(output_uv(r_, width_, height_, s));
          bool ok = true;
          for (uint32_t face : around) ok = ok && (!real(face) || positive(face));
          if (ok) {
            uv_[v] = s;
            return true;
          }
        }
    out_[v] = was;
    return false;
  }

 private:
  const Surface& disk_;
  const Rect& r_;
  int width_, height_;
  std::vector<Vec2>& uv_;
  std::vector<Stored> out_;  // per vertex, uv_ as stored
};

}  // namespace

FloatGuard keep_orientation_in_float(const Surface& disk, const Rect& r, int width, int height, std::vector<Vec2>& uv) {
  FloatGuard result;
  Guard guard(disk, r, width, height, uv);
  const std::vector<uint32_t> bad = guard.bad_faces();
  if (bad.empty()) return result;
  // The faces around each vertex of a bad face (one pass over the faces: there are few such vertices).
  std::vector<uint32_t> slot(disk.num_vertices(), kNone);
  std::vector<std::vector<uint32_t>> around;
  for (uint32_t face : bad)
    for (uint32_t v : disk.triangles[face])
      if (slot[v] == kNone) slot[v] = uint32_t(around.size()), around.emplace_back();
  for (uint32_t face = 0; face < disk.num_faces(); ++face)
    for (uint32_t v : disk.triangles[face])
      if (slot[v] != kNone) around[slot[v]].push_back(face);
  for (uint32_t face : bad) {
    if (guard.positive(face)) continue;  // a move for an earlier one fixed it
    bool fixed = false;
    for (uint32_t v : disk.triangles[face])
      if (!fixed && guard.move(v, around[slot[v]])) fixed = true, ++result.moved;
    if (!fixed) ++result.unfixed;
  }
  return result;
}

}  // namespace tightex
