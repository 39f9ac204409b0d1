#include "param/folds.hpp"

#include <algorithm>
#include <cmath>

namespace tightex {

size_t count_folds(const Surface& mesh, const std::vector<Vec2>& uv) {
  size_t folds = 0;
  for (const Tri& f : mesh.triangles) folds += !(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0);
  return folds;
}

size_t count_collapsed(const Surface& mesh, const std::vector<Vec2>& uv, const SquareMapOptions& options, uint32_t* worst_vertex) {
  const double sx = double(std::max(1, options.rect_width - 1)), sy = double(std::max(1, options.rect_height - 1));
  const double extent = std::max({options.texel_extent, double(options.rect_width), double(options.rect_height)});
  const double rounding = std::ldexp(extent, -52);  // texels
  size_t collapsed = 0;
  double worst = 1;
  for (const Tri& f : mesh.triangles) {
    const Vec2 a(uv[f[0]].x() * sx, uv[f[0]].y() * sy), b(uv[f[1]].x() * sx, uv[f[1]].y() * sy), c(uv[f[2]].x() * sx, uv[f[2]].y() * sy);
    const double margin = signed_area(a, b, c) / (rounding * ((b - a).norm() + (c - b).norm() + (a - c).norm()));
    if (!(margin >= 1)) {
      collapsed++;
      if (!(margin >= worst)) {
        worst = margin;
        if (worst_vertex) *worst_vertex = f[0];
      }
    }
  }
  return collapsed;
}

}  // namespace tightex
