#include "pipeline/budget.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "layout/layout.hpp"
#include "report/metrics.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

std::pair<int, int> atlas_size(int size, double aspect) {
  if (aspect == 1.0) return {size, size};
  const int W = std::max(8, int(std::lround(size * std::sqrt(aspect) / 4)) * 4);
  const long need = (long(size) * long(size) + W - 1) / W;
  return {W, std::max(8, int((need + 3) / 4 * 4))};
}

int atlas_side_holding(const std::vector<double>& areas, int size) {
  auto holds = [&](int s) { return try_layout_atlas(areas, s, s, 4).has_value(); };
  if (holds(size)) return size;
  // Not beyond the default's limit (16M components fit there); past it, the layout's error.
  const int limit = std::max(size, kDefaultSizeMax);
  int side = std::min(limit, size_for_texels(double(size) * double(size) + 16.0 * double(areas.size())));
  while (side < limit && !holds(side)) side = std::min(limit, size_for_texels(1.21 * double(side) * double(side)));
  return side;
}

int per_component_side(const std::vector<double>& shares, int size) {
  const double sum = std::accumulate(shares.begin(), shares.end(), 0.0), largest = *std::max_element(shares.begin(), shares.end());
  if (sum > 0 && largest > 0) return std::max(4, int(std::lround(double(size) * std::sqrt(largest / sum))));
  return size;
}

int size_for_texels(double texels) {
  const double side = std::ceil(std::sqrt(std::max(texels, 0.0)) / 4.0) * 4.0;
  return int(std::clamp(side, 64.0, 65536.0));
}

double input_used_texels(const TexturedMesh& input) { return measure_texture_space(input).used_texels; }

double default_texels(const TexturedMesh& input) {
  const ModelFigures figures = measure_texture_space(input);
  double texels = 0;
  for (size_t i = 0; i < input.textures.size(); ++i) {
    if (input.textures[i].from_vertex_colours) continue;
    const auto [w, h] = texture_size(input, int(i));
    texels += figures.image_utilization[i] * double(w) * double(h);
  }
  for (size_t t = 0; t < input.num_triangles(); ++t) {
    const int32_t m = input.face_material[t];
    const int tex = m < 0 ? -1 : input.materials[size_t(m)].texture;
    if (tex >= 0 && input.textures[size_t(tex)].from_vertex_colours) texels += kTexelsPerColouredTriangle;
  }
  return texels;
}

int default_size(const TexturedMesh& input, int max_side) {
  double texels = std::ceil(default_texels(input) / 4.0) * 4.0;
  if (!(texels > 0)) texels = 1024.0 * 1024.0;  // no texture of known size: a 1K map
  return std::min(size_for_texels(texels), max_side);
}

}  // namespace tightex
