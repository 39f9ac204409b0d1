#include "bake/resampling_error.hpp"

#include "bake/bake.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include <tbb/parallel_for.h>

namespace tightex {

BakeTriangle bake_triangle(const TexturedMesh& input, const Surface& disk, uint32_t f, const std::vector<Vec2>& uv, const Rect& rect) {
  const uint32_t t = disk.input_face[f];
  const Tri& ft = disk.triangles[f];
  BakeTriangle bt;
  bt.material = input.face_material[t];
  bt.area3 = triangle_area(disk.positions, ft);
  for (size_t k = 0; k < 3; ++k) {
    bt.target_px[k] = rect_pixel(rect, uv[ft[k]]);
    bt.source_uv[k] = input.sampled_uv(t, disk.input_corner[3 * size_t(f) + k]);
  }
  return bt;
}

double resampling_mse(const TexturedMesh& input, const Surface& disk, const std::vector<Vec2>& uv, int w, int h, size_t samples) {
  const size_t nf = disk.num_faces();
  if (w < 2 || h < 2 || samples == 0 || uv.size() != disk.num_vertices() || disk.input_face.size() != nf) return -1;
  // The faces that have pixels to read, baked as bake_plan places them (the unit square's corners on
  // the corner texels' centres), without the fit.
  std::vector<uint32_t> real;
  std::vector<BakeTriangle> tris;
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t t = disk.input_face[f];
    if (t == kNone || !image_of(input, t)) continue;
    real.push_back(f);
    tris.push_back(bake_triangle(input, disk, f, uv, Rect{0, 0, 0, w, h}));
  }
  if (real.empty()) return -1;
  std::vector<Image> images(1, Image(w, h));
  BakeOptions bo;
  bo.fit = false;
  bake_texture(input, tris, {Rect{0, 0, 0, w, h}}, images, nullptr, bo);

  // Sample points, uniform by 3D area over the real faces; both colours bilinear, as docs/metrics.md reads.
  std::vector<double> cdf(real.size());
  double acc = 0;
  for (size_t i = 0; i < real.size(); ++i) {
    const Tri& t = disk.triangles[real[i]];
    cdf[i] = acc += triangle_area(disk.positions[t[0]], disk.positions[t[1]], disk.positions[t[2]]);
  }
  if (!(acc > 0)) return -1;
  // Stratified along the cumulative area: sample s lies at (s + jitter) / samples of it, so the points
  // come in face order and each chunk reads both images along its faces instead of at random (the
  // estimate's cost is the memory traffic of these reads), with less variance than independent
  // picks. In chunks with their own seeds, summed in order: the same figure for any thread count.
  constexpr size_t kChunk = 16384;
  const size_t chunks = (samples + kChunk - 1) / kChunk;
  std::vector<double> chunk_se(chunks, 0.0);
  tbb::parallel_for(size_t(0), chunks, [&](size_t ch) {
    std::mt19937_64 rng(20241201 + ch);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    double se = 0;
    const size_t first = ch * kChunk;
    const double start = double(first) / double(samples) * acc;
    size_t i = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), start) - cdf.begin()), real.size() - 1);
    for (size_t s = first; s < std::min(samples, first + kChunk); ++s) {
      const double pick = (double(s) + uni(rng)) / double(samples) * acc;
      while (i + 1 < real.size() && cdf[i] <= pick) ++i;
      double r1 = uni(rng), r2 = uni(rng);
      if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
      const double b[3] = {1 - r1 - r2, r1, r2};
      const BakeTriangle& bt = tris[i];
      Vec2 px = Vec2::Zero(), src = Vec2::Zero();
      for (int k = 0; k < 3; ++k) px += b[k] * bt.target_px[size_t(k)], src += b[k] * bt.source_uv[size_t(k)];
      const auto out = sample_bilinear(images[0], px.x() / w, 1.0 - px.y() / h);
      const auto in = sample_bilinear(*image_of(input, disk.input_face[real[i]]), src.x(), src.y());
      for (int c = 0; c < 3; ++c) se += double(out[size_t(c)] - in[size_t(c)]) * double(out[size_t(c)] - in[size_t(c)]);
    }
    chunk_se[ch] = se;
  });
  double se = 0;
  for (double x : chunk_se) se += x;
  return se / (3.0 * double(samples));
}

}  // namespace tightex
