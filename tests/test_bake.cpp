// The bake (§4.3 and beyond): footprint filtering where the input is minified, and the least-squares
// fit for bilinear read-back. Both are checked against what they exist to fix.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <random>

#include "bake/bake.hpp"
#include "core/raster.hpp"
#include "report/metrics.hpp"

namespace tightex {
namespace {

/// A model with one texture and one material; the bake only reads materials and textures.
TexturedMesh textured(Image image) {
  TexturedMesh m;
  Material mat;
  mat.texture = 0;
  m.materials.push_back(mat);
  m.textures.push_back(Texture{"in.png", std::move(image)});
  return m;
}

/// Two triangles covering a W x H output (texel centres of the outermost texels on the square's edge,
/// as the pipeline places them), sourcing the uv square [u0,u1] x [v0,v1] rotated by `angle` about its centre.
std::vector<BakeTriangle> square(int W, int H, double angle, double scale) {
  const Vec2 px[4] = {{0.5, H - 0.5}, {W - 0.5, H - 0.5}, {W - 0.5, 0.5}, {0.5, 0.5}};
  const Vec2 c(0.5, 0.5);
  Vec2 uv[4];
  const Vec2 base[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int k = 0; k < 4; ++k) {
    const Vec2 d = (base[k] - c) * scale;
    uv[k] = c + Vec2(std::cos(angle) * d.x() - std::sin(angle) * d.y(), std::sin(angle) * d.x() + std::cos(angle) * d.y());
  }
  std::vector<BakeTriangle> tris(2);
  const int idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (int t = 0; t < 2; ++t) {
    tris[size_t(t)].material = 0;
    tris[size_t(t)].area3 = 0.5;
    for (int k = 0; k < 3; ++k) {
      tris[size_t(t)].target_px[size_t(k)] = px[idx[t][k]];
      tris[size_t(t)].source_uv[size_t(k)] = uv[idx[t][k]];
    }
  }
  return tris;
}

TEST(Bake, MinifiedInputIsAveragedOverTheFootprint) {
  // A one-pixel checkerboard shrunk 8 times: each output texel covers 64 input pixels, half black.
  Image in(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) in.at(x, y) = (x + y) % 2 ? Rgba8{255, 255, 255, 255} : Rgba8{0, 0, 0, 255};
  const TexturedMesh m = textured(in);
  const auto tris = square(32, 32, 0.0, 1.0);
  const std::vector<Rect> rects = {Rect{0, 0, 0, 32, 32}};
  auto worst = [&](int max_samples) {
    std::vector<Image> out = {Image(32, 32)};
    BakeOptions o;
    o.fit = false;
    o.max_footprint_samples = max_samples;
    BakeStats st;
    bake_texture(m, tris, rects, out, &st, o);
    double w = 0;  // worst texel, away from the square's edge (there the footprint is cut by the triangle)
    for (int y = 1; y < 31; ++y)
      for (int x = 1; x < 31; ++x) w = std::max(w, std::abs(double(out[0].at(x, y).g) - 127.5));
    return std::make_pair(w, st.texels_footprint_filtered);
  };
  const auto [filtered, count] = worst(8);
  EXPECT_LT(filtered, 30.0) << "a minified texel must be the mean of its footprint";
  EXPECT_GE(count, 32u * 32u);  // every texel (those on the shared diagonal twice)
  // The control: one sample per texel aliases (the checkerboard's phase decides each texel).
  EXPECT_GT(worst(1).first, 60.0);
}

/// PSNR of the output read back with bilinear filtering against the input, at random points of the square.
double readback_psnr(const Image& in, const Image& out, const std::vector<BakeTriangle>& tris) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  double se = 0;
  size_t n = 0;
  for (int i = 0; i < 40000; ++i) {
    double a = U(rng), b = U(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const BakeTriangle& t = tris[size_t(i % 2)];
    const Vec2 px = (1 - a - b) * t.target_px[0] + a * t.target_px[1] + b * t.target_px[2];
    const Vec2 uv = (1 - a - b) * t.source_uv[0] + a * t.source_uv[1] + b * t.source_uv[2];
    const auto o = sample_bilinear(out, px.x() / out.width, 1.0 - px.y() / out.height);
    const auto r = sample_bilinear(in, uv.x(), uv.y());
    for (int c = 0; c < 3; ++c) se += double(o[size_t(c)] - r[size_t(c)]) * double(o[size_t(c)] - r[size_t(c)]);
    n += 3;
  }
  return 10 * std::log10(255.0 * 255.0 / (se / double(n)));
}

TEST(Bake, LeastSquaresFitBeatsPointSamplingAndTheFineFitBeatsTheFit) {
  // Detail near the output's resolution (periods of 3 to 7 texels), resampled at a rotation: a
  // point-sampled bake blurs twice (bake, then read-back); the fit undoes much of that. The fine fit's
  // 4x4 points per texel constrain the bilinear reconstruction between the 2x2 points too, so the
  // read-back (at other points than the fit's) is closer still.
  Image in(192, 192);
  for (int y = 0; y < 192; ++y)
    for (int x = 0; x < 192; ++x) {
      const double v = 127.5 + 60 * std::sin(x * 1.9 + y * 0.7) + 60 * std::cos(y * 1.3 - x * 0.4);
      const uint8_t g = uint8_t(std::clamp(v, 0.0, 255.0));
      in.at(x, y) = {g, uint8_t(255 - g), g, 255};
    }
  const TexturedMesh m = textured(in);
  const auto tris = square(128, 128, 0.5, 0.6);  // about 1:1 texels, rotated by 29 degrees
  const std::vector<Rect> rects = {Rect{0, 0, 0, 128, 128}};
  auto psnr = [&](bool fit, bool fine) {
    std::vector<Image> out = {Image(128, 128)};
    BakeOptions o;
    o.fit = fit;
    if (fine) o.fit_samples = kFineFitSamples, o.fit_lambda = kFineFitLambda;
    BakeStats st;
    bake_texture(m, tris, rects, out, &st, o);
    if (fit) EXPECT_GT(st.tiles_fitted, 0u);
    return readback_psnr(in, out[0], tris);
  };
  const double plain = psnr(false, false), fitted = psnr(true, false), fine = psnr(true, true);
  EXPECT_GT(fitted, plain + 1.0) << "plain " << plain << " dB, fitted " << fitted << " dB";
  EXPECT_GT(fine, fitted + 0.1) << "fit " << fitted << " dB, fine fit " << fine << " dB";
}

TEST(Bake, FineFitKeepsTheDefaultFitWhereTheInputIsMinifiedBeyondItsLimit) {
  // 16 input pixels per output texel (a 512-pixel input onto 32 texels): beyond the limit of 12, the
  // fine fit's 4x4 points lost up to 1 dB on real models, so such tiles get the default fit, bit for bit.
  // Under the limit (a 1:1 copy) the fine fit does change the texels.
  Image in(512, 512);
  for (int y = 0; y < 512; ++y)
    for (int x = 0; x < 512; ++x) {
      const uint8_t g = uint8_t(127.5 + 100 * std::sin(x * 0.37 + y * 0.11));
      in.at(x, y) = {g, g, uint8_t(255 - g), 255};
    }
  const TexturedMesh m = textured(in);
  auto bake = [&](int side, double scale, bool fine) {
    std::vector<Image> out = {Image(side, side)};
    BakeOptions o;
    if (fine) o.fit_samples = kFineFitSamples, o.fit_lambda = kFineFitLambda;
    BakeStats st;
    bake_texture(m, square(side, side, 0.3, scale), {Rect{0, 0, 0, side, side}}, out, &st, o);
    EXPECT_GT(st.tiles_fitted, 0u);
    return out[0];
  };
  const Image normal = bake(32, 1.0, false), fine = bake(32, 1.0, true);
  EXPECT_EQ(0, std::memcmp(normal.pixels.data(), fine.pixels.data(), normal.pixels.size() * sizeof(normal.pixels[0])));
  const Image normal_1to1 = bake(64, 0.125, false), fine_1to1 = bake(64, 0.125, true);
  EXPECT_NE(0, std::memcmp(normal_1to1.pixels.data(), fine_1to1.pixels.data(), normal_1to1.pixels.size() * sizeof(normal_1to1.pixels[0])));
}

// Progress: at least one call, fractions in (0, 1] that never go backwards, never two calls at once
// (the tiles are baked in parallel and report from their threads).
TEST(Bake, ProgressIsOrderedAndSerialised) {
  Image in(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) in.at(x, y) = {uint8_t(x), uint8_t(y), uint8_t(x ^ y), 255};
  const TexturedMesh m = textured(in);
  std::vector<Image> out = {Image(512, 512)};
  BakeOptions o;
  o.progress_interval_s = 0;
  std::vector<double> calls;
  std::atomic<int> inside{0};
  bool overlapped = false;
  o.progress = [&](double f) {
    if (inside.fetch_add(1) != 0) overlapped = true;
    calls.push_back(f);
    inside.fetch_sub(1);
  };
  bake_texture(m, square(512, 512, 0.3, 0.9), {Rect{0, 0, 0, 512, 512}}, out, nullptr, o);
  EXPECT_FALSE(overlapped);
  ASSERT_FALSE(calls.empty());
  for (size_t i = 0; i < calls.size(); ++i) {
    EXPECT_GT(calls[i], 0.0);
    EXPECT_LE(calls[i], 1.0);
    if (i > 0) EXPECT_GE(calls[i], calls[i - 1]) << i;
  }
}

TEST(Bake, FitDoesNotDependOnTheModelsUnits) {
  // The fit weighs samples by 3D area per texel. A model in huge units gave weights beyond float's range,
  // an infinite weight and a NaN texel (found by fuzz_pipeline under UBSan at coordinates of 1e15; the
  // input is fuzz/corpus/fuzz_pipeline/regress-bake-huge-weights); in tiny units the weights fell to 0
  // and the fit did nothing. Scaled by a power of two, the areas must give the same texels bit for bit.
  Image in(96, 96);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) in.at(x, y) = {uint8_t((x * 37 + y * 11) % 256), uint8_t((x * 5) % 256), uint8_t(y * 2), 255};
  const TexturedMesh m = textured(in);
  const std::vector<Rect> rects = {Rect{0, 0, 0, 128, 128}};
  auto bake = [&](double area_scale) {
    auto tris = square(128, 128, 0.5, 0.9);
    for (BakeTriangle& t : tris) t.area3 *= area_scale;
    std::vector<Image> out = {Image(128, 128)};
    BakeStats st;
    bake_texture(m, tris, rects, out, &st, {});
    EXPECT_GT(st.tiles_fitted, 0u);
    return out[0];
  };
  const Image ref = bake(1.0);
  EXPECT_TRUE(bake(std::ldexp(1.0, 150)).pixels == ref.pixels);
  EXPECT_TRUE(bake(std::ldexp(1.0, -150)).pixels == ref.pixels);
}

TEST(Bake, AbsurdCoordinatesAreSkippedOrCappedNotOverflowed) {
  // A material's -s/-o can put texture coordinates at 1e300; converted to texel indices they overflowed
  // (undefined behaviour, found by fuzz_pipeline under UBSan; inputs fuzz/corpus/fuzz_pipeline/
  // regress-bake-footprint-overflow and regress-metrics-offset-overflow). Under UBSan this test fails
  // without the clamps; here it checks what is visited.
  size_t visited = 0;
  scan_triangle(Vec2(1e300, 1e300), Vec2(2e300, 1e300), Vec2(1e300, 2e300), 0, 64, 0, 64, EdgeRule::kInclusive,
                [&](long, long, double, double, double) { ++visited; });
  scan_triangle(Vec2(-1e300, 10), Vec2(1e300, 10), Vec2(0, 20), 0, 64, 0, 64, EdgeRule::kInclusive,
                [&](long, long, double, double, double) { ++visited; });
  EXPECT_EQ(visited, 64u * 10u);  // the second: rows 10..19, every column
  // A source footprint of 1e300 texels takes the sample cap.
  Image in(8, 8, Rgba8{90, 90, 90, 255});
  const TexturedMesh m = textured(in);
  auto tris = square(16, 16, 0.0, 1e300);
  std::vector<Image> out = {Image(16, 16)};
  bake_texture(m, tris, {Rect{0, 0, 0, 16, 16}}, out, nullptr, {});
  EXPECT_EQ(out[0].at(8, 8).r, 90);
  // Texture space of a model whose material shifts it by 1e300: nothing addressable is used.
  TexturedMesh shifted = m;
  shifted.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  shifted.triangles = {Tri{0, 1, 2}};
  shifted.corner_uv = {Vec2(0.1, 0.1), Vec2(0.9, 0.1), Vec2(0.1, 0.9)};
  shifted.face_material = {0};
  shifted.materials[0].uv_offset = {1e300, -1e300};
  EXPECT_EQ(measure_texture_space(shifted).used_texels, 0.0);
}

TEST(Bake, FitIsDeterministicAndLeavesMagnifiedTilesAlone) {
  Image in(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) in.at(x, y) = {uint8_t(x * 16), uint8_t(y * 16), 0, 255};
  const TexturedMesh m = textured(in);
  const auto tris = square(256, 256, 0.0, 1.0);  // 16x magnified: bilinear is right, nothing to fit
  const std::vector<Rect> rects = {Rect{0, 0, 0, 256, 256}};
  std::vector<Image> a = {Image(256, 256)}, b = {Image(256, 256)};
  BakeStats st;
  bake_texture(m, tris, rects, a, &st, {});
  EXPECT_EQ(st.tiles_fitted, 0u);
  BakeOptions no_fit;
  no_fit.fit = false;
  bake_texture(m, tris, rects, b, nullptr, no_fit);
  EXPECT_TRUE(a[0].pixels == b[0].pixels);
}

}  // namespace
}  // namespace tightex
