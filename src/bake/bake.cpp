#include "bake/bake.hpp"

#include "core/progress.hpp"
#include "core/raster.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace tightex {

namespace {

constexpr int kTile = 64;

Rgba8 to_rgba(const std::array<float, 4>& c) {
  auto q = [](float x) { return uint8_t(std::clamp(x + 0.5f, 0.0f, 255.0f)); };
  return {q(c[0]), q(c[1]), q(c[2]), q(c[3])};
}

/// What sampling one triangle needs, computed once.
struct TriangleSampler {
  const Image* src = nullptr;
  Rgba8 flat{255, 255, 255, 255};
  Vec2 uv0, du_dx, du_dy;    // source uv at target pixel (0,0) and its derivatives (affine per triangle)
  double bary_x[3], bary_y[3], bary_0[3];  // barycentric weights as affine functions of the target pixel
  double footprint_x = 0, footprint_y = 0;  // input pixels spanned by one output texel along x and y
  double weight = 0;         // 3D area per output texel (least-squares fit)
  bool valid = false;

  void init(const BakeTriangle& tri, const Image* source, Rgba8 flat_colour) {
    src = source;
    flat = flat_colour;
    corner_uv = tri.source_uv;
    const Vec2 &p0 = tri.target_px[0], &p1 = tri.target_px[1], &p2 = tri.target_px[2];
    const double det = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p1.y() - p0.y()) * (p2.x() - p0.x());
    if (!(std::abs(det) > 0) || !std::isfinite(det)) return;
    // w1, w2 from the 2x2 inverse; w0 = 1 - w1 - w2.
    const double i00 = (p2.y() - p0.y()) / det, i01 = -(p2.x() - p0.x()) / det;
    const double i10 = -(p1.y() - p0.y()) / det, i11 = (p1.x() - p0.x()) / det;
    bary_x[1] = i00, bary_y[1] = i01, bary_0[1] = -(i00 * p0.x() + i01 * p0.y());
    bary_x[2] = i10, bary_y[2] = i11, bary_0[2] = -(i10 * p0.x() + i11 * p0.y());
    bary_x[0] = -bary_x[1] - bary_x[2], bary_y[0] = -bary_y[1] - bary_y[2], bary_0[0] = 1 - bary_0[1] - bary_0[2];
    uv0 = Vec2::Zero(), du_dx = Vec2::Zero(), du_dy = Vec2::Zero();
    for (int k = 0; k < 3; ++k) {
      uv0 += bary_0[k] * tri.source_uv[k];
      du_dx += bary_x[k] * tri.source_uv[k];
      du_dy += bary_y[k] * tri.source_uv[k];
    }
    if (src) {
      footprint_x = std::hypot(du_dx.x() * src->width, du_dx.y() * src->height);
      footprint_y = std::hypot(du_dy.x() * src->width, du_dy.y() * src->height);
    }
    weight = tri.area3 / (0.5 * std::abs(det));
    valid = std::isfinite(weight);
  }

  /// Mean colour over a box of side `box` output texels centred at target pixel position (x, y); the
  /// sample points are kept inside the triangle (barycentrics clamped), so a texel on a chart's edge
  /// never averages in the input's empty space beyond the triangle.
  std::array<float, 4> colour(double x, double y, double box, int max_samples) const {
    if (!src) return {float(flat.r), float(flat.g), float(flat.b), float(flat.a)};
    // Clamped before the conversion to int: a material's -s can make the footprint 1e300 (found by
    // fuzz_pipeline under UBSan), and a NaN footprint takes one sample.
    auto samples_along = [&](double footprint) {
      const double n = std::ceil(footprint * box - 1e-9);
      return n >= max_samples ? max_samples : n >= 1 ? int(n) : 1;
    };
    // Common case (a footprint of at most one input pixel along both axes): one sample, the same as the
    // general loop below with nx = ny = 1, without its ceil() calls (the fit takes K^2 samples a texel).
    if (footprint_x * box - 1e-9 <= 1 && footprint_y * box - 1e-9 <= 1) {
      double w[3], total = 0;
      for (int k = 0; k < 3; ++k) total += w[k] = std::max(0.0, bary_0[k] + bary_x[k] * x + bary_y[k] * y);
      Vec2 uv = uv0 + x * du_dx + y * du_dy;
      if (w[0] == 0 || w[1] == 0 || w[2] == 0) {
        uv = Vec2::Zero();
        for (int k = 0; k < 3; ++k) uv += (w[k] / total) * corner_uv[k];
      }
      return sample_bilinear(*src, uv.x(), uv.y());
    }
    const int nx = samples_along(footprint_x), ny = samples_along(footprint_y);
    std::array<float, 4> sum{0, 0, 0, 0};
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double sx = x + box * ((i + 0.5) / nx - 0.5), sy = y + box * ((j + 0.5) / ny - 0.5);
        double w[3], total = 0;
        for (int k = 0; k < 3; ++k) total += w[k] = std::max(0.0, bary_0[k] + bary_x[k] * sx + bary_y[k] * sy);
        Vec2 uv = uv0 + sx * du_dx + sy * du_dy;
        if (w[0] == 0 || w[1] == 0 || w[2] == 0) {  // outside: the nearest point of the triangle (approximately)
          uv = Vec2::Zero();
          for (int k = 0; k < 3; ++k) uv += (w[k] / total) * corner_uv[k];
        }
        const auto c = sample_bilinear(*src, uv.x(), uv.y());
        for (int ch = 0; ch < 4; ++ch) sum[size_t(ch)] += c[size_t(ch)];
      }
    const float inv = 1.0f / float(nx * ny);
    for (float& c : sum) c *= inv;
    return sum;
  }
  std::array<Vec2, 3> corner_uv;
};

constexpr int kHalo = 3;

/// The least-squares fit of one tile (see BakeOptions::fit): texels of the tile and a halo around it are
/// unknowns, starting from the plain bake `base`; samples at the four points (+-1/4, +-1/4) of each
/// texel that lies inside some triangle (and whose bilinear taps stay inside the region); minimises
/// sum w_s (bilinear(c, s) - input(s))^2 + lambda |c - base|^2 by conjugate gradients, per channel.
/// Writes the tile's own texels (not the halo) to `out`.
void fit_tile(const Image& base, Image& out, const std::vector<BakeTriangle>& triangles, const std::vector<TriangleSampler>& samplers,
              const std::vector<uint32_t>& tris, int bx0, int by0, const BakeOptions& options, int max_samples) {
  const int bx1 = std::min(bx0 + kTile, out.width), by1 = std::min(by0 + kTile, out.height);
  const int rx0 = std::max(0, bx0 - kHalo), ry0 = std::max(0, by0 - kHalo);
  const int rx1 = std::min(out.width, bx1 + kHalo), ry1 = std::min(out.height, by1 + kHalo);
  const int rw = rx1 - rx0, rh = ry1 - ry0;
  const size_t n = size_t(rw) * size_t(rh);
  // Sample classes: a K x K grid of points inside each texel (offsets from its centre).
  // A tile holding a triangle that minifies the input beyond fit_fine_max_footprint keeps the default
  // 2 x 2 fit (see BakeOptions::fit_fine_max_footprint).
  bool coarse = false;
  if (options.fit_samples > 2)
    for (uint32_t t : tris)
      if (samplers[t].valid && std::max(samplers[t].footprint_x, samplers[t].footprint_y) > options.fit_fine_max_footprint) {
        coarse = true;
        break;
      }
  const int K = coarse ? BakeOptions{}.fit_samples : std::clamp(options.fit_samples, 1, 8), classes = K * K;
  const double fit_lambda = coarse ? BakeOptions{}.fit_lambda : options.fit_lambda;
  std::vector<std::array<double, 2>> offsets(static_cast<size_t>(classes));
  for (int j = 0; j < K; ++j)
    for (int i = 0; i < K; ++i) offsets[size_t(j * K + i)] = {(i + 0.5) / K - 0.5, (j + 0.5) / K - 0.5};
  // Samples: per class k and texel, the target colour and weight (0: none).
  std::vector<std::array<float, 3>> target(size_t(classes) * n);
  std::vector<float> weight(size_t(classes) * n, 0.0f);
  double weight_sum = 0;
  size_t samples = 0;
  // The weights (3D area per texel) are brought to [1, 2) for the tile's largest by a power of two: a
  // model in large units (a scan in nanometres, or 1e13 m) has weights beyond float's range, and an
  // infinite weight made the solve NaN (found by fuzz_pipeline under UBSan). The fit depends only on
  // ratios of weights, and scaling by a power of two is exact, so every other model bakes bit for bit
  // as before.
  double max_weight = 0;
  for (uint32_t t : tris)
    if (samplers[t].valid && samplers[t].weight > 0) max_weight = std::max(max_weight, samplers[t].weight);
  if (!(max_weight > 0)) return;
  const double weight_scale = std::ldexp(1.0, -std::ilogb(max_weight));
  for (uint32_t t : tris) {
    const TriangleSampler& smp = samplers[t];
    if (!smp.valid || !(smp.weight > 0)) continue;
    const double smp_weight = smp.weight * weight_scale;
    const BakeTriangle& tri = triangles[t];
    for (int k = 0; k < classes; ++k) {
      const Vec2 off(offsets[size_t(k)][0], offsets[size_t(k)][1]);
      scan_triangle(tri.target_px[0] - off, tri.target_px[1] - off, tri.target_px[2] - off, rx0 + 1, rx1 - 1, ry0 + 1, ry1 - 1,
                    EdgeRule::kInclusive, [&](long x, long y, double, double, double) {
                      const size_t i = size_t(k) * n + size_t(y - ry0) * size_t(rw) + size_t(x - rx0);
                      if (weight[i] > 0) return;
                      const auto c = smp.colour(double(x) + 0.5 + off.x(), double(y) + 0.5 + off.y(), 1.0 / K, max_samples);
                      target[i] = {c[0], c[1], c[2]};
                      weight[i] = float(smp_weight);
                      weight_sum += smp_weight;
                      ++samples;
                    });
    }
  }
  if (samples == 0) return;
  const float lambda = float(fit_lambda * weight_sum / double(samples));
  // Bilinear taps of a sample of class k at local texel i: (offset index, weight).
  auto taps = [&](int k, size_t i, auto&& f) {
    const double ox = offsets[size_t(k)][0], oy = offsets[size_t(k)][1];
    const int dx0 = ox < 0 ? -1 : 0, dy0 = oy < 0 ? -1 : 0;
    const float wx1 = float(ox < 0 ? 1 + ox : ox), wy1 = float(oy < 0 ? 1 + oy : oy);  // weight of the +1 tap
    const long base_i = long(i) + dy0 * rw + dx0;
    f(size_t(base_i), (1 - wx1) * (1 - wy1));
    f(size_t(base_i + 1), wx1 * (1 - wy1));
    f(size_t(base_i + rw), (1 - wx1) * wy1);
    f(size_t(base_i + rw + 1), wx1 * wy1);
  };
  // A = B^T W B + lambda I as a 9-point stencil per texel: every sample's 4 taps lie in a 2x2 block.
  // A class's taps (offsets, weights) are the same for all its samples, and so is the stencil slot of
  // tap b seen from tap a: tabulated once per class.
  std::vector<std::array<float, 9>> stencil(n);
  for (size_t i = 0; i < n; ++i) stencil[i] = {0, 0, 0, 0, lambda, 0, 0, 0, 0};
  for (int k = 0; k < classes; ++k) {
    long tap_offset[4];
    float tap_weight[4];
    int m = 0;
    taps(k, 0, [&](size_t j, float wt) { tap_offset[m] = long(j), tap_weight[m] = wt, ++m; });  // offsets from texel 0 (wrap as size_t)
    constexpr int kPosX[4] = {0, 1, 0, 1}, kPosY[4] = {0, 0, 1, 1};
    int slot[4][4];
    for (int a = 0; a < 4; ++a)
      for (int b2 = 0; b2 < 4; ++b2) slot[a][b2] = (kPosY[b2] - kPosY[a] + 1) * 3 + (kPosX[b2] - kPosX[a] + 1);
    const float* wk = weight.data() + size_t(k) * n;
    for (size_t i = 0; i < n; ++i) {
      const float w = wk[i];
      if (w == 0) continue;
      for (int a = 0; a < 4; ++a) {
        auto& st = stencil[size_t(long(i) + tap_offset[a])];
        const float wa = w * tap_weight[a];
        for (int b2 = 0; b2 < 4; ++b2) st[size_t(slot[a][b2])] += wa * tap_weight[b2];
      }
    }
  }
  using Vec = std::vector<std::array<float, 3>>;
  // result = A v. Interior texels take all 9 neighbours without checks; the region's border rows and
  // columns check their bounds (their stencil has zeros there, as no sample's taps leave the region).
  auto apply = [&](const Vec& v, Vec& result) {
    auto general = [&](int y, int xx) {
      const size_t i = size_t(y) * size_t(rw) + size_t(xx);
      const auto& st = stencil[i];
      float s0 = 0, s1 = 0, s2 = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        if (y + dy < 0 || y + dy >= rh) continue;
        for (int dx = -1; dx <= 1; ++dx) {
          if (xx + dx < 0 || xx + dx >= rw) continue;
          const float c = st[size_t((dy + 1) * 3 + dx + 1)];
          const auto& vj = v[size_t(long(i) + dy * rw + dx)];
          s0 += c * vj[0], s1 += c * vj[1], s2 += c * vj[2];
        }
      }
      result[i] = {s0, s1, s2};
    };
    for (int y = 0; y < rh; ++y) {
      if (y == 0 || y == rh - 1 || rw < 3) {
        for (int xx = 0; xx < rw; ++xx) general(y, xx);
        continue;
      }
      general(y, 0);
      for (int xx = 1; xx < rw - 1; ++xx) {
        const size_t i = size_t(y) * size_t(rw) + size_t(xx);
        const auto& st = stencil[i];
        float s0 = 0, s1 = 0, s2 = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const float c = st[size_t((dy + 1) * 3 + dx + 1)];
            const auto& vj = v[size_t(long(i) + dy * rw + dx)];
            s0 += c * vj[0], s1 += c * vj[1], s2 += c * vj[2];
          }
        result[i] = {s0, s1, s2};
      }
      general(y, rw - 1);
    }
  };
  Vec x(n), rhs(n), r(n), p(n), ap(n);
  for (int y = ry0; y < ry1; ++y)
    for (int xx = rx0; xx < rx1; ++xx) {
      const Rgba8& c = base.at(xx, y);
      const size_t i = size_t(y - ry0) * size_t(rw) + size_t(xx - rx0);
      x[i] = {float(c.r), float(c.g), float(c.b)};
      rhs[i] = {lambda * x[i][0], lambda * x[i][1], lambda * x[i][2]};
    }
  for (int k = 0; k < classes; ++k)
    for (size_t i = 0; i < n; ++i) {
      const float w = weight[size_t(k) * n + i];
      if (w == 0) continue;
      const auto& tg = target[size_t(k) * n + i];
      taps(k, i, [&](size_t j, float tw) {
        for (int c = 0; c < 3; ++c) rhs[j][size_t(c)] += w * tw * tg[size_t(c)];
      });
    }
  apply(x, ap);
  double rr[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      r[i][size_t(c)] = rhs[i][size_t(c)] - ap[i][size_t(c)];
      p[i][size_t(c)] = r[i][size_t(c)];
      rr[c] += double(r[i][size_t(c)]) * r[i][size_t(c)];
    }
  for (int it = 0; it < options.fit_iterations; ++it) {
    apply(p, ap);
    double pap[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) pap[c] += double(p[i][size_t(c)]) * ap[i][size_t(c)];
    double alpha[3], rr_new[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) alpha[c] = pap[c] > 0 ? rr[c] / pap[c] : 0.0;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) {
        x[i][size_t(c)] += float(alpha[c]) * p[i][size_t(c)];
        r[i][size_t(c)] -= float(alpha[c]) * ap[i][size_t(c)];
        rr_new[c] += double(r[i][size_t(c)]) * r[i][size_t(c)];
      }
    for (int c = 0; c < 3; ++c) {
      const double beta = rr[c] > 0 ? rr_new[c] / rr[c] : 0.0;
      for (size_t i = 0; i < n; ++i) p[i][size_t(c)] = r[i][size_t(c)] + float(beta) * p[i][size_t(c)];
      rr[c] = rr_new[c];
    }
  }
  auto q = [](float v) { return uint8_t(std::clamp(v + 0.5f, 0.0f, 255.0f)); };
  for (int y = by0; y < by1; ++y)
    for (int xx = bx0; xx < bx1; ++xx) {
      const auto& v = x[size_t(y - ry0) * size_t(rw) + size_t(xx - rx0)];
      Rgba8& o = out.at(xx, y);
      o.r = q(v[0]), o.g = q(v[1]), o.b = q(v[2]);
    }
}

}  // namespace

void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles,
                  const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats, const BakeOptions& options) {
  std::vector<Rgba8> flat_colour(input.materials.size());
  for (size_t m = 0; m < input.materials.size(); ++m) {
    const auto& kd = input.materials[m].kd;
    flat_colour[m] = to_rgba({float(kd[0] * 255), float(kd[1] * 255), float(kd[2] * 255), 255.f});
  }
  std::vector<TriangleSampler> samplers(triangles.size());
  tbb::parallel_for(size_t(0), triangles.size(), [&](size_t t) {
    const BakeTriangle& tri = triangles[t];
    const Image* src = nullptr;
    Rgba8 flat{255, 255, 255, 255};
    if (tri.material >= 0) {
      const Material& mat = input.materials[size_t(tri.material)];
      if (mat.texture >= 0 && !input.textures[size_t(mat.texture)].image.empty())
        src = &input.textures[size_t(mat.texture)].image;
      else
        flat = flat_colour[size_t(tri.material)];
    }
    samplers[t].init(tri, src, flat);
  });
  const int max_samples = std::max(1, options.max_footprint_samples);
  std::atomic<size_t> filled{0}, dilated{0}, filtered{0}, tiles_fitted{0}, tiles_total{0};
  // Progress by tiles: each is rasterised (1 unit) and, with the fit, fitted (3 units).
  constexpr double kFitUnits = 3.0;
  double all_units = 0;
  for (const Image& out : images)
    all_units += double((out.width + kTile - 1) / kTile) * double((out.height + kTile - 1) / kTile) * (options.fit ? 1 + kFitUnits : 1);
  ProgressCounter progress(options.progress, all_units, options.progress_interval_s);
  // The triangles and rectangles of each image, gathered once: scanning all of them per image took 99
  // of 104 s on 30000 components in the per-component layout (30000 images).
  std::vector<std::vector<uint32_t>> image_triangles(images.size());
  std::vector<std::vector<size_t>> image_rects(images.size());
  for (uint32_t t = 0; t < triangles.size(); ++t)
    if (triangles[t].image < images.size()) image_triangles[triangles[t].image].push_back(t);
  for (size_t r = 0; r < rects.size(); ++r)
    if (rects[r].image >= 0 && size_t(rects[r].image) < images.size()) image_rects[size_t(rects[r].image)].push_back(r);
  for (uint32_t img = 0; img < images.size(); ++img) {
    Image& out = images[img];
    const int tiles_x = (out.width + kTile - 1) / kTile, tiles_y = (out.height + kTile - 1) / kTile;
    std::vector<std::vector<uint32_t>> bins(size_t(tiles_x) * size_t(tiles_y));
    for (uint32_t t : image_triangles[img]) {
      const BakeTriangle& tri = triangles[t];
      double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
      for (const Vec2& p : tri.target_px) x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      const int tx0 = std::clamp(int(std::floor(x0)) / kTile, 0, tiles_x - 1), tx1 = std::clamp(int(std::floor(x1)) / kTile, 0, tiles_x - 1);
      const int ty0 = std::clamp(int(std::floor(y0)) / kTile, 0, tiles_y - 1), ty1 = std::clamp(int(std::floor(y1)) / kTile, 0, tiles_y - 1);
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) bins[size_t(ty) * size_t(tiles_x) + size_t(tx)].push_back(t);
    }
    std::vector<uint8_t, LargeBufferAllocator<uint8_t>> covered(size_t(out.width) * size_t(out.height), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, bins.size()), [&](const tbb::blocked_range<size_t>& range) {
      size_t local = 0, local_filtered = 0;
      for (size_t b = range.begin(); b < range.end(); ++b) {
        const int bx0 = int(b % size_t(tiles_x)) * kTile, by0 = int(b / size_t(tiles_x)) * kTile;
        const int bx1 = std::min(bx0 + kTile, out.width), by1 = std::min(by0 + kTile, out.height);
        for (uint32_t t : bins[b]) {
          const BakeTriangle& tri = triangles[t];
          const TriangleSampler& smp = samplers[t];
          const bool minified = smp.footprint_x > 1 || smp.footprint_y > 1;
          scan_triangle(tri.target_px[0], tri.target_px[1], tri.target_px[2], bx0, bx1, by0, by1, EdgeRule::kInclusive,
                        [&](long x, long y, double w0, double w1, double w2) {
                          Rgba8 c = smp.flat;
                          if (smp.src) {
                            if (minified && smp.valid) {
                              c = to_rgba(smp.colour(double(x) + 0.5, double(y) + 0.5, 1.0, max_samples));
                              ++local_filtered;
                            } else {
                              const Vec2 uv = w0 * tri.source_uv[0] + w1 * tri.source_uv[1] + w2 * tri.source_uv[2];
                              c = to_rgba(sample_bilinear(*smp.src, uv.x(), uv.y()));
                            }
                          }
                          const size_t idx = size_t(y) * size_t(out.width) + size_t(x);
                          out.pixels[idx] = c;
                          local += !covered[idx];
                          covered[idx] = 1;
                        });
        }
      }
      filled += local;
      filtered += local_filtered;
      progress.advance(double(range.size()));
    });

    // Dilation inside each rectangle, layer by layer (deterministic: a layer reads only earlier layers).
    const std::vector<size_t>& my_rects = image_rects[img];
    tbb::parallel_for(size_t(0), my_rects.size(), [&](size_t ri) {
      const Rect& r = rects[my_rects[ri]];
      std::vector<std::pair<int, int>> frontier, next;
      size_t local = 0;
      auto is_cov = [&](int x, int y) { return covered[size_t(y) * size_t(out.width) + size_t(x)] != 0; };
      for (int y = r.y; y < r.y + r.h; ++y)
        for (int x = r.x; x < r.x + r.w; ++x)
          if (!is_cov(x, y)) frontier.push_back({x, y});
      if (frontier.size() == size_t(r.w) * size_t(r.h)) {  // nothing covered: keep a neutral grey
        for (auto [x, y] : frontier) out.at(x, y) = {128, 128, 128, 255};
        dilated += frontier.size();
        return;
      }
      while (!frontier.empty()) {
        std::vector<std::pair<std::pair<int, int>, Rgba8>> updates;
        next.clear();
        for (auto [x, y] : frontier) {
          int sum[4] = {0, 0, 0, 0}, n = 0;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = x + dx, ny = y + dy;
              if ((dx == 0 && dy == 0) || nx < r.x || ny < r.y || nx >= r.x + r.w || ny >= r.y + r.h || !is_cov(nx, ny)) continue;
              const Rgba8& c = out.at(nx, ny);
              sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a, ++n;
            }
          if (n == 0) {
            next.push_back({x, y});
            continue;
          }
          updates.push_back({{x, y}, Rgba8{uint8_t(sum[0] / n), uint8_t(sum[1] / n), uint8_t(sum[2] / n), uint8_t(sum[3] / n)}});
        }
        for (auto& [p, c] : updates) {
          out.at(p.first, p.second) = c;
          covered[size_t(p.second) * size_t(out.width) + size_t(p.first)] = 1;
        }
        local += updates.size();
        if (updates.empty()) break;
        frontier.swap(next);
      }
      dilated += local;
    });

    if (options.fit) {
      const Image base = out;
      tbb::parallel_for(size_t(0), bins.size(), [&](size_t b) {
        if (!bins[b].empty()) ++tiles_total;
        bool worth = false;
        for (uint32_t t : bins[b]) worth = worth || (samplers[t].src && samplers[t].valid && std::max(samplers[t].footprint_x, samplers[t].footprint_y) > 0.5);
        if (worth) {
          // The tile's triangles and its neighbours' (the fit's halo reaches into them).
          const int tx = int(b % size_t(tiles_x)), ty = int(b / size_t(tiles_x));
          std::vector<uint32_t> tris;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = tx + dx, ny = ty + dy;
              if (nx < 0 || ny < 0 || nx >= tiles_x || ny >= tiles_y) continue;
              const auto& bin = bins[size_t(ny) * size_t(tiles_x) + size_t(nx)];
              tris.insert(tris.end(), bin.begin(), bin.end());
            }
          std::sort(tris.begin(), tris.end());
          tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
          fit_tile(base, out, triangles, samplers, tris, tx * kTile, ty * kTile, options, max_samples);
          ++tiles_fitted;
        }
        progress.advance(kFitUnits);
      });
    }
  }
  if (stats) {
    stats->texels_filled = filled;
    stats->texels_dilated = dilated;
    stats->texels_footprint_filtered = filtered;
    stats->tiles_fitted = tiles_fitted;
    stats->tiles = tiles_total;
  }
}

}  // namespace tightex
