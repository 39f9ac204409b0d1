// Scan-line conversion of a triangle onto texel centres (paper §4.3, Alg. 3), shared by the bake and by
// the metrics so that "texel covered" means the same everywhere.
#pragma once
#include <algorithm>
#include <cmath>

#include "core/mesh.hpp"

namespace tightex {

enum class EdgeRule {
  kInclusive,  // a centre exactly on an edge belongs to the triangle (coverage, baking)
  kTopLeft,    // it belongs to exactly one of two triangles sharing the edge (overlap counting)
};

/// The scan line of paper Alg. 3: calls f(x, y, w0, w1, w2) for every texel centre (x + 0.5, y + 0.5)
/// inside triangle p0 p1 p2 (pixel coordinates), with x in [x_lo, x_hi) and y in [y_lo, y_hi), row by
/// row, left to right. w are the barycentric weights of p0, p1, p2 at the centre.
/// Requires: nothing of the triangle (either orientation; any coordinates, huge or NaN included).
/// Guarantees: degenerate or non-finite triangles yield nothing; with EdgeRule::kTopLeft, a centre on an
/// edge shared by two triangles is visited for exactly one of them. Each row's span is found
/// analytically from the three edges, so a thin triangle costs its area plus its height, not its
/// bounding box. Throws only what f throws.
template <typename F>
void scan_triangle(const Vec2& p0, const Vec2& p1, const Vec2& p2, long x_lo, long x_hi, long y_lo, long y_hi, EdgeRule rule, F&& f) {
  const Vec2* p[3] = {&p0, &p1, &p2};
  const double area2 = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p1.y() - p0.y()) * (p2.x() - p0.x());
  if (!(area2 != 0) || !std::isfinite(area2)) return;
  const double sign = area2 > 0 ? 1.0 : -1.0;
  // Edge i is opposite vertex i: e_i(x, y) = A_i x + B_i y + C_i, >= 0 inside (after the sign).
  // The exact per-texel test evaluates each edge from its lexicographically smaller end, so two
  // triangles sharing an edge compute the same value up to sign: ties break consistently.
  double A[3], B[3], C[3], esign[3];
  const Vec2* es[3];
  const Vec2* ee[3];
  bool owns[3];
  for (int i = 0; i < 3; ++i) {
    const Vec2& s = *p[(i + 1) % 3];
    const Vec2& e = *p[(i + 2) % 3];
    const bool swap = std::make_pair(e.x(), e.y()) < std::make_pair(s.x(), s.y());
    es[i] = swap ? &e : &s;
    ee[i] = swap ? &s : &e;
    esign[i] = swap ? -sign : sign;
    A[i] = -sign * (e.y() - s.y());
    B[i] = sign * (e.x() - s.x());
    C[i] = -(A[i] * s.x() + B[i] * s.y());
    // top-left: an edge owns its points when the interior lies below-right of it (in y-down pixels).
    owns[i] = A[i] > 0 || (A[i] == 0 && B[i] > 0);
  }
  const double ymin = std::min({p0.y(), p1.y(), p2.y()}), ymax = std::max({p0.y(), p1.y(), p2.y()});
  const double xmin = std::min({p0.x(), p1.x(), p2.x()}), xmax = std::max({p0.x(), p1.x(), p2.x()});
  // Coordinates are clamped to one texel beyond the range before any conversion to long: a huge or NaN
  // coordinate (a material's -s/-o of 1e300) would overflow it. The same rows and columns are visited
  // as without the clamp.
  auto near = [](double v, long lo, long hi) { return std::fmin(std::fmax(v, double(lo) - 1), double(hi) + 1); };
  const long ya = std::max(y_lo, long(std::ceil(near(ymin, y_lo, y_hi) - 0.5)));
  const long yb = std::min(y_hi - 1, long(std::floor(near(ymax, y_lo, y_hi) - 0.5)));
  const double inv = 1.0 / (sign * area2);
  for (long y = ya; y <= yb; ++y) {
    const double py = double(y) + 0.5;
    double lo = xmin, hi = xmax;
    for (int i = 0; i < 3; ++i) {
      const double rest = B[i] * py + C[i];
      if (A[i] > 0)
        lo = std::max(lo, -rest / A[i]);
      else if (A[i] < 0)
        hi = std::min(hi, -rest / A[i]);
      else if (rest < 0)
        hi = lo - 2;  // empty row
    }
    if (hi < lo - 1) continue;
    // One texel of slack on each side: the exact test below decides.
    const long xa = std::max(x_lo, long(std::ceil(near(lo, x_lo, x_hi) - 0.5)) - 1);
    const long xb = std::min(x_hi - 1, long(std::floor(near(hi, x_lo, x_hi) - 0.5)) + 1);
    for (long x = xa; x <= xb; ++x) {
      const double px = double(x) + 0.5;
      double w[3];
      bool in = true;
      for (int i = 0; i < 3 && in; ++i) {
        const Vec2 &s = *es[i], &e = *ee[i];
        w[i] = esign[i] * ((e.x() - s.x()) * (py - s.y()) - (e.y() - s.y()) * (px - s.x()));
        in = rule == EdgeRule::kInclusive ? w[i] >= 0 : (w[i] > 0 || (w[i] == 0 && owns[i]));
      }
      if (in) f(x, y, w[0] * inv, w[1] * inv, w[2] * inv);
    }
  }
}

}  // namespace tightex
