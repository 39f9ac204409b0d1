#include "bake/fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/raster.hpp"

namespace tightex {

namespace {

/// The fit's unknowns: the tile and its halo, clipped to the image, as a row-major array of w x h.
struct FitRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int w = 0, h = 0;
  size_t n = 0;  // w * h

  size_t index(int x, int y) const { return size_t(y - y0) * size_t(w) + size_t(x - x0); }
};

FitRegion fit_region(const TexelTile& tile, const Image& out) {
  FitRegion r;
  r.x0 = std::max(0, tile.x0 - kFitHalo), r.y0 = std::max(0, tile.y0 - kFitHalo);
  r.x1 = std::min(out.width, tile.x1 + kFitHalo), r.y1 = std::min(out.height, tile.y1 + kFitHalo);
  r.w = r.x1 - r.x0, r.h = r.y1 - r.y0;
  r.n = size_t(r.w) * size_t(r.h);
  return r;
}

/// The sample points of the fit: a K x K grid inside each texel (offsets from its centre, one class
/// per point), and the pull towards the plain bake.
struct SampleGrid {
  int K = 2;
  int classes = 4;  // K * K
  double lambda = 1;
  std::vector<std::array<double, 2>> offsets;  // per class
};

/// The options' grid, or the default 2 x 2 fit where a nearby triangle minifies the input beyond
/// fit_fine_max_footprint (see BakeOptions::fit_fine_max_footprint).
SampleGrid sample_grid(const FitTileInput& input, const BakeOptions& options) {
  bool coarse = false;
  if (options.fit_samples > 2)
    for (const TriangleSampler& smp : input.samplers) {
      if (smp.valid && std::max(smp.footprint_x, smp.footprint_y) > options.fit_fine_max_footprint) {
        coarse = true;
        break;
      }
    }
  SampleGrid g;
  g.K = coarse ? BakeOptions{}.fit_samples : std::clamp(options.fit_samples, 1, 8);
  g.classes = g.K * g.K;
  g.lambda = coarse ? BakeOptions{}.fit_lambda : options.fit_lambda;
  g.offsets.resize(static_cast<size_t>(g.classes));
  for (int j = 0; j < g.K; ++j)
    for (int i = 0; i < g.K; ++i) g.offsets[size_t(j * g.K + i)] = {(i + 0.5) / g.K - 0.5, (j + 0.5) / g.K - 0.5};
  return g;
}

/// A sample at a triangle's corner (TriangleSampler::corner_samples): its four bilinear taps (region
/// indices, in the order x0y0, x1y0, x0y1, x1y1, and their weights), its target colour and weight.
struct CornerSample {
  std::array<size_t, 4> tap;
  std::array<float, 4> tap_weight;
  std::array<float, 3> target;
  float weight = 0;
};

/// The weight of a corner sample relative to one grid sample of the same triangle. A vertex is the
/// corner of about six triangles, so its colour weighs as much as some 36 grid samples: the bilinear
/// read-back at the vertex gives its colour back within a few 1/255, for a little of the surface
/// PSNR between the vertices. Chosen by measurement (docs/decisions.md).
constexpr double kCornerSampleWeight = 6.0;

/// The fit's samples: per class k and texel i (index k * n + i), the target colour and its weight
/// (0: no sample); and the corner samples.
struct FitSamples {
  std::vector<std::array<float, 3>> target;
  std::vector<float> weight;
  double weight_sum = 0;
  size_t count = 0;
  std::vector<CornerSample> corners;
};

/// Appends triangle `smp`'s corner samples whose four taps lie inside the region: the input's colour
/// at each corner (point-sampled: a vertex-coloured input is exact there), at `weight`.
void add_corner_samples(const TriangleSampler& smp, const BakeTriangle& tri, const FitRegion& region, float weight,
                        std::vector<CornerSample>& corners) {
  for (int k = 0; k < 3; ++k) {
    const double fx = tri.target_px[size_t(k)].x() - 0.5, fy = tri.target_px[size_t(k)].y() - 0.5;
    const double x0 = std::floor(fx), y0 = std::floor(fy);
    if (!(x0 >= region.x0 && x0 + 1 < region.x1 && y0 >= region.y0 && y0 + 1 < region.y1)) continue;
    const size_t i = region.index(int(x0), int(y0));
    const float tx = float(fx - x0), ty = float(fy - y0);
    const auto c = sample_bilinear(*smp.src, smp.corner_uv[size_t(k)].x(), smp.corner_uv[size_t(k)].y());
    corners.push_back({{i, i + 1, i + size_t(region.w), i + size_t(region.w) + 1},
                       {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty},
                       {c[0], c[1], c[2]},
                       weight});
  }
}

/// Samples every class point of every texel whose taps stay inside the region (its centre at least one
/// texel from the region's border) and that lies inside a nearby triangle; the first triangle in
/// `nearby` order wins. The weights (3D area per texel) are brought to [1, 2) for the largest by a
/// power of two: a model in large or tiny units would have weights beyond float's range (an infinite
/// weight makes the solve NaN). The fit depends only on ratios of weights, and scaling by a power of
/// two is exact, so the scale changes nothing else.
FitSamples collect_samples(const FitTileInput& input, const SampleGrid& grid, const FitRegion& region, int max_samples) {
  FitSamples s;
  s.target.resize(size_t(grid.classes) * region.n);
  s.weight.assign(size_t(grid.classes) * region.n, 0.0f);
  double max_weight = 0;
  for (const TriangleSampler& smp : input.samplers)
    if (smp.valid && smp.weight > 0) max_weight = std::max(max_weight, smp.weight);
  if (!(max_weight > 0)) return s;
  const double weight_scale = std::ldexp(1.0, -std::ilogb(max_weight));
  for (size_t n = 0; n < input.nearby.size(); ++n) {
    const TriangleSampler& smp = input.samplers[n];
    if (!smp.valid || !(smp.weight > 0) || smp.unread) continue;
    const double smp_weight = smp.weight * weight_scale;
    const BakeTriangle& tri = input.triangles[input.nearby[n]];
    for (int k = 0; k < grid.classes; ++k) {
      const Vec2 off(grid.offsets[size_t(k)][0], grid.offsets[size_t(k)][1]);
      scan_triangle(tri.target_px[0] - off, tri.target_px[1] - off, tri.target_px[2] - off, region.x0 + 1, region.x1 - 1, region.y0 + 1,
                    region.y1 - 1, EdgeRule::kInclusive, [&](long x, long y, double, double, double) {
                      const size_t i = size_t(k) * region.n + size_t(y - region.y0) * size_t(region.w) + size_t(x - region.x0);
                      if (s.weight[i] > 0) return;
                      const auto c = smp.footprint_colour(double(x) + 0.5 + off.x(), double(y) + 0.5 + off.y(), 1.0 / grid.K, max_samples);
                      s.target[i] = {c[0], c[1], c[2]};
                      s.weight[i] = float(smp_weight);
                      s.weight_sum += smp_weight;
                      ++s.count;
                    });
    }
    if (smp.corner_samples) add_corner_samples(smp, tri, region, float(kCornerSampleWeight * smp_weight), s.corners);
  }
  return s;
}

/// Calls f(j, weight) for the four bilinear taps of the sample at `offset` from the centre of texel i of
/// a region `w` texels wide.
template <typename F>
void for_each_bilinear_tap(const std::array<double, 2>& offset, int w, size_t i, F&& f) {
  const double ox = offset[0], oy = offset[1];
  const int dx0 = ox < 0 ? -1 : 0, dy0 = oy < 0 ? -1 : 0;
  const float wx1 = float(ox < 0 ? 1 + ox : ox), wy1 = float(oy < 0 ? 1 + oy : oy);  // weight of the +1 tap
  const long base_i = long(i) + dy0 * w + dx0;
  f(size_t(base_i), (1 - wx1) * (1 - wy1));
  f(size_t(base_i + 1), wx1 * (1 - wy1));
  f(size_t(base_i + w), (1 - wx1) * wy1);
  f(size_t(base_i + w + 1), wx1 * wy1);
}

/// The normal matrix A = B^T W B + lambda I as a 9-point stencil per texel (slot (dy + 1) * 3 + dx + 1
/// couples texel i with texel i + dy * w + dx).
using Stencil = std::vector<std::array<float, 9>>;
/// Colours of the region's texels, row-major.
using TexelColours = std::vector<std::array<float, 3>>;

/// Adds the corner samples' terms to A (their four taps form a 2x2 block, as a grid sample's do).
void add_corner_samples_to_normal_matrix(const std::vector<CornerSample>& corners, Stencil& stencil) {
  constexpr int kPosX[4] = {0, 1, 0, 1}, kPosY[4] = {0, 0, 1, 1};
  for (const CornerSample& cs : corners)
    for (int a = 0; a < 4; ++a) {
      auto& st = stencil[cs.tap[size_t(a)]];
      const float wa = cs.weight * cs.tap_weight[size_t(a)];
      for (int b = 0; b < 4; ++b) st[size_t((kPosY[b] - kPosY[a] + 1) * 3 + (kPosX[b] - kPosX[a] + 1))] += wa * cs.tap_weight[size_t(b)];
    }
}

/// Assembles A: every sample's 4 taps lie in a 2x2 block. A class's taps (offsets, weights) are the
/// same for all its samples, and so is the stencil slot of tap b seen from tap a: tabulated once per
/// class.
Stencil assemble_normal_matrix(const SampleGrid& grid, const FitSamples& samples, const FitRegion& region, float lambda) {
  Stencil stencil(region.n);
  for (size_t i = 0; i < region.n; ++i) stencil[i] = {0, 0, 0, 0, lambda, 0, 0, 0, 0};
  for (int k = 0; k < grid.classes; ++k) {
    long tap_offset[4];
    float tap_weight[4];
    int m = 0;
    // Offsets from texel 0 (they wrap as size_t; added to a texel index they come back in range).
    for_each_bilinear_tap(grid.offsets[size_t(k)], region.w, 0,
                          [&](size_t j, float wt) { tap_offset[m] = long(j), tap_weight[m] = wt, ++m; });
    constexpr int kPosX[4] = {0, 1, 0, 1}, kPosY[4] = {0, 0, 1, 1};
    int slot[4][4];
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) slot[a][b] = (kPosY[b] - kPosY[a] + 1) * 3 + (kPosX[b] - kPosX[a] + 1);
    const float* wk = samples.weight.data() + size_t(k) * region.n;
    for (size_t i = 0; i < region.n; ++i) {
      const float w = wk[i];
      if (w == 0) continue;
      for (int a = 0; a < 4; ++a) {
        auto& st = stencil[size_t(long(i) + tap_offset[a])];
        const float wa = w * tap_weight[a];
        for (int b = 0; b < 4; ++b) st[size_t(slot[a][b])] += wa * tap_weight[b];
      }
    }
  }
  add_corner_samples_to_normal_matrix(samples.corners, stencil);
  return stencil;
}

/// The plain bake's colours over the region: the fit's starting point.
TexelColours base_colours(const Image& base, const FitRegion& region) {
  TexelColours x(region.n);
  for (int y = region.y0; y < region.y1; ++y)
    for (int xx = region.x0; xx < region.x1; ++xx) {
      const Rgba8& c = base.at(xx, y);
      x[region.index(xx, y)] = {float(c.r), float(c.g), float(c.b)};
    }
  return x;
}

/// The right-hand side B^T W t + lambda base.
TexelColours assemble_right_hand_side(const TexelColours& base, float lambda, const SampleGrid& grid, const FitSamples& samples,
                                      const FitRegion& region) {
  TexelColours rhs(region.n);
  for (size_t i = 0; i < region.n; ++i) rhs[i] = {lambda * base[i][0], lambda * base[i][1], lambda * base[i][2]};
  for (int k = 0; k < grid.classes; ++k)
    for (size_t i = 0; i < region.n; ++i) {
      const float w = samples.weight[size_t(k) * region.n + i];
      if (w == 0) continue;
      const auto& tg = samples.target[size_t(k) * region.n + i];
      for_each_bilinear_tap(grid.offsets[size_t(k)], region.w, i, [&](size_t j, float tw) {
        for (int c = 0; c < 3; ++c) rhs[j][size_t(c)] += w * tw * tg[size_t(c)];
      });
    }
  for (const CornerSample& cs : samples.corners)
    for (size_t a = 0; a < 4; ++a)
      for (size_t c = 0; c < 3; ++c) rhs[cs.tap[a]][c] += cs.weight * cs.tap_weight[a] * cs.target[c];
  return rhs;
}

/// result[i] = (A v)[i] for texel (xx, y), checking that each neighbour lies in the region.
void apply_stencil_checked(const Stencil& stencil, const FitRegion& region, int y, int xx, const TexelColours& v, TexelColours& result) {
  const size_t i = size_t(y) * size_t(region.w) + size_t(xx);
  const auto& st = stencil[i];
  float s0 = 0, s1 = 0, s2 = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    if (y + dy < 0 || y + dy >= region.h) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      if (xx + dx < 0 || xx + dx >= region.w) continue;
      const float c = st[size_t((dy + 1) * 3 + dx + 1)];
      const auto& vj = v[size_t(long(i) + dy * region.w + dx)];
      s0 += c * vj[0], s1 += c * vj[1], s2 += c * vj[2];
    }
  }
  result[i] = {s0, s1, s2};
}

/// result = A v. Interior texels take all 9 neighbours without checks; the region's border rows and
/// columns check their bounds (their stencil has zeros there, as no sample's taps leave the region).
void apply_normal_matrix(const Stencil& stencil, const FitRegion& region, const TexelColours& v, TexelColours& result) {
  const int rw = region.w, rh = region.h;
  for (int y = 0; y < rh; ++y) {
    if (y == 0 || y == rh - 1 || rw < 3) {
      for (int xx = 0; xx < rw; ++xx) apply_stencil_checked(stencil, region, y, xx, v, result);
      continue;
    }
    apply_stencil_checked(stencil, region, y, 0, v, result);
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
    apply_stencil_checked(stencil, region, y, rw - 1, v, result);
  }
}

/// `iterations` steps of conjugate gradients on A x = rhs from the given x, each channel on its own
/// (float vectors, double dot products).
void solve_by_conjugate_gradients(const Stencil& stencil, const FitRegion& region, const TexelColours& rhs, int iterations,
                                  TexelColours& x) {
  const size_t n = region.n;
  TexelColours r(n), p(n), ap(n);
  apply_normal_matrix(stencil, region, x, ap);
  double rr[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      r[i][size_t(c)] = rhs[i][size_t(c)] - ap[i][size_t(c)];
      p[i][size_t(c)] = r[i][size_t(c)];
      rr[c] += double(r[i][size_t(c)]) * r[i][size_t(c)];
    }
  for (int it = 0; it < iterations; ++it) {
    apply_normal_matrix(stencil, region, p, ap);
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
}

/// Writes the fitted colours of the tile's own texels (red, green, blue) to `out`, rounded and clamped.
void write_tile(const TexelColours& x, const FitRegion& region, const TexelTile& tile, Image& out) {
  auto q = [](float v) { return uint8_t(std::clamp(v + 0.5f, 0.0f, 255.0f)); };
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int xx = tile.x0; xx < tile.x1; ++xx) {
      const auto& v = x[region.index(xx, y)];
      Rgba8& o = out.at(xx, y);
      o.r = q(v[0]), o.g = q(v[1]), o.b = q(v[2]);
    }
}

}  // namespace

void fit_tile(const FitTileInput& input, const TexelTile& tile, const BakeOptions& options, Image& out) {
  const FitRegion region = fit_region(tile, out);
  const SampleGrid grid = sample_grid(input, options);
  const int max_samples = std::max(1, options.max_footprint_samples);
  const FitSamples samples = collect_samples(input, grid, region, max_samples);
  if (samples.count == 0) return;
  const float lambda = float(grid.lambda * samples.weight_sum / double(samples.count));
  const Stencil stencil = assemble_normal_matrix(grid, samples, region, lambda);
  TexelColours x = base_colours(input.base, region);
  const TexelColours rhs = assemble_right_hand_side(x, lambda, grid, samples, region);
  solve_by_conjugate_gradients(stencil, region, rhs, options.fit_iterations, x);
  write_tile(x, region, tile, out);
}

}  // namespace tightex
