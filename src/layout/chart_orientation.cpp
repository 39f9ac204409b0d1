#include "layout/chart_orientation.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

namespace tightex {

namespace {

/// How far from square (|w - h| over the longer side) a rectangle may be for a quarter turn: its
/// texels' aspect changes by at most 2% (the square of 1.01), which the map does not notice.
constexpr double kQuarterTurnAspect = 0.01;

/// (x, y) turned by a quarter turn counter-clockwise about the unit square's centre: exact in floating
/// point, so a map on the square stays on it.
Vec2 quarter_turn(const Vec2& s) { return Vec2(1.0 - s.y(), s.x()); }

/// The turn between two angles in degrees, in (-180, 180].
double wrapped(double degrees) {
  double d = std::fmod(degrees, 360.0);
  if (d > 180) d -= 360;
  if (d <= -180) d += 360;
  return d;
}

/// Whether a quarter turn of the square leaves the texel stretch the map was made for: a square
/// rectangle, or one within kQuarterTurnAspect of it (a component beside specks of 4 x 4 texels gets a
/// few texels less on one side).
bool quarter_turn_keeps_stretch(const Rect& r) { return std::abs(r.w - r.h) <= kQuarterTurnAspect * std::max(r.w, r.h); }

}  // namespace

std::optional<std::array<Vec2, 2>> texel_axes_images(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels,
                                                     const std::array<Vec2, 3>& out_uv, const Vec2& out_texels) {
  // A = E_out E_in^-1, the columns of E the two edges from corner 0, in texels.
  const Vec2 p = (in_uv[1] - in_uv[0]).cwiseProduct(in_texels), q = (in_uv[2] - in_uv[0]).cwiseProduct(in_texels);
  const Vec2 o1 = (out_uv[1] - out_uv[0]).cwiseProduct(out_texels), o2 = (out_uv[2] - out_uv[0]).cwiseProduct(out_texels);
  const double det_in = p.x() * q.y() - q.x() * p.y(), det_out = o1.x() * o2.y() - o2.x() * o1.y();
  if (!(std::abs(det_in) > 0) || !(std::abs(det_out) > 0) || !std::isfinite(det_in) || !std::isfinite(det_out)) return std::nullopt;
  return std::array<Vec2, 2>{(q.y() * o1 - p.y() * o2) / det_in, (p.x() * o2 - q.x() * o1) / det_in};
}

ChartTurn orient_chart(const TexturedMesh& input, const Surface& disk, const Rect& r, std::vector<Vec2>& uv) {
  ChartTurn turn;
  // The input's u axis and v axis (turned back by a quarter) in the output's texels, as unit vectors
  // weighted by 3D area: their sum's direction is the chart's mean turn.
  std::complex<double> sum = 0;
  const Vec2 out_texels(r.w, r.h);
  for (size_t f = 0; f < disk.num_faces() && f < disk.input_face.size(); ++f) {
    const uint32_t t = disk.input_face[f];
    const Image* image = t == kNone ? nullptr : image_of(input, t);
    if (!image) continue;
    const Tri& ft = disk.triangles[f];
    std::array<Vec2, 3> in_uv, out_uv;
    for (size_t k = 0; k < 3; ++k) in_uv[k] = input.sampled_uv(t, disk.input_corner[3 * f + k]), out_uv[k] = uv[ft[k]];
    const auto axes = texel_axes_images(in_uv, Vec2(image->width, image->height), out_uv, out_texels);
    if (!axes) continue;
    const double area = triangle_area(disk.positions, ft);
    const Vec2 &u = (*axes)[0], &v = (*axes)[1];
    if (!(area > 0) || !(u.norm() > 0) || !(v.norm() > 0)) continue;
    sum += area * std::complex<double>(u.x(), u.y()) / u.norm();
    sum += area * std::complex<double>(v.y(), -v.x()) / v.norm();  // v turned back by a quarter
  }
  if (!(std::abs(sum) > 0)) {
    turn.mean_turn_deg = NAN;
    return turn;
  }
  turn.mean_turn_deg = std::arg(sum) * 180 / M_PI;
  // The allowed turn that brings the mean closest to 0 (ties: the smaller turn).
  const int step = quarter_turn_keeps_stretch(r) ? 1 : 2;
  double best = 1e300;
  for (int q = 0; q < 4; q += step)
    if (const double d = std::abs(wrapped(turn.mean_turn_deg + 90.0 * q)); d < best - 1e-9) best = d, turn.quarter_turns = q;
  for (int q = 0; q < turn.quarter_turns; ++q)
    for (Vec2& s : uv) s = quarter_turn(s);
  return turn;
}

}  // namespace tightex
