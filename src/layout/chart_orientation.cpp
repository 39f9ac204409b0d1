#include "layout/chart_orientation.hpp"

#include <cmath>

namespace tightex {

std::optional<std::array<Vec2, 2>> texel_axes_images(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels,
                                                     const std::array<Vec2, 3>& out_uv, const Vec2& out_texels) {
  // A = E_out E_in^-1, the columns of E the two edges from corner 0, in texels.
  const Vec2 p = (in_uv[1] - in_uv[0]).cwiseProduct(in_texels), q = (in_uv[2] - in_uv[0]).cwiseProduct(in_texels);
  const Vec2 o1 = (out_uv[1] - out_uv[0]).cwiseProduct(out_texels), o2 = (out_uv[2] - out_uv[0]).cwiseProduct(out_texels);
  const double det_in = p.x() * q.y() - q.x() * p.y(), det_out = o1.x() * o2.y() - o2.x() * o1.y();
  if (!(std::abs(det_in) > 0) || !(std::abs(det_out) > 0) || !std::isfinite(det_in) || !std::isfinite(det_out)) return std::nullopt;
  return std::array<Vec2, 2>{(q.y() * o1 - p.y() * o2) / det_in, (p.x() * o2 - q.x() * o1) / det_in};
}

}  // namespace tightex
