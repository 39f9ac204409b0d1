// The new texture (paper §4.3, Alg. 3): every output triangle is scan-converted in the new texture
// space and each texel takes the colour of the original texture through the original UVs.
#pragma once
#include <array>
#include <functional>
#include <vector>

#include "core/mesh.hpp"
#include "layout/layout.hpp"

namespace tightex {

/// One triangle to bake: where it lands (pixel coordinates, x right, y down, texel centres at +0.5)
/// and where its colour comes from (texture coordinates in the input, after the material's -s/-o).
struct BakeTriangle {
  uint32_t image = 0;
  std::array<Vec2, 3> target_px;
  std::array<Vec2, 3> source_uv;
  int32_t material = -1;  // input material (-1: none, white)
  double area3 = 0;        // 3D area: the least-squares fit weighs the surface uniformly, as METRICS.md's PSNR does
};

struct BakeOptions {
  /// Footprint filtering: where a texel covers more than one input pixel (the input is minified), its
  /// colour is the mean of n x m bilinear samples spread over the texel's footprint in the input,
  /// n and m the footprint's extent in input pixels along the texel's two axes, at most this many.
  int max_footprint_samples = 8;
  /// Least-squares fit: a texture read back with bilinear filtering (as every renderer and METRICS.md
  /// do) blurs once more what a point-sampled bake already blurred. The fit chooses the texels whose
  /// bilinear reconstruction best matches the input at 4 points per texel, weighted by 3D area; solved
  /// by conjugate gradients on 64-texel tiles with a 3-texel halo (independent, deterministic).
  /// Skipped on tiles where every triangle magnifies the input by 2 or more (bilinear is right there).
  bool fit = true;
  int fit_iterations = 12;
  /// K: the fit's sample points are a K x K grid in each texel. Measured (surface PSNR at the input's
  /// budget, detail map, fuze / tomato / meshroom): K=2 lambda 1: 42.06 / 47.66 / 42.22; K=3 lambda 0.3:
  /// 42.15 / 47.80 / 42.11; K=4 lambda 0.3: 42.28 / 47.93 / 42.44 at about twice the bake time: the
  /// default stays 2, K=4 is the opt-in fine fit (kFineFitSamples).
  int fit_samples = 2;
  /// With fit_samples > 2: a tile where some triangle's footprint exceeds this many input pixels per
  /// texel (along either axis) is fitted with K=2 and lambda 1 instead. Measured with the fine fit
  /// (surface PSNR at the input's budget, --map harmonic, cracker / potted meat; detail map, meshroom):
  /// no limit 37.85 / 40.20; 42.44 (the harmonic map's most squeezed regions lose 1 dB against the 2 x 2
  /// fit's 38.86 / 40.93); limit 3: 38.92 / 41.00; 42.22; 6: 38.99 / 41.02; 42.25; 12: 39.15 / 41.03;
  /// 42.30; 24: 39.15 / 40.91; 42.29.
  double fit_fine_max_footprint = 12.0;
  /// Optional: called with the fraction of the bake done (tiles rasterised, then fitted; a fitted tile
  /// counts as three), from the baking threads, never two calls at once, at most every 0.2 s.
  std::function<void(double)> progress;
  double progress_interval_s = 0.2;  // the least time between two progress calls
  /// Pull of each texel towards its footprint-filtered bake, relative to the mean sample weight. Chosen
  /// by measurement (meshroom_esp32cam, area map, --size 1024, surface PSNR): 0.01: 41.10 dB, 0.1: 41.21,
  /// 0.3: 41.31, 1: 41.35, 3: 41.12, 10: 40.64; without the fit 40.01. A weaker pull over-fits the four
  /// sample points of each texel; a stronger one gives the fit away.
  double fit_lambda = 1.0;
};

/// The fine fit (Options::fine_fit, CLI --fine-fit): BakeOptions::fit_samples and fit_lambda (measured
/// there and in BENCHMARKS.md, "Fine fit"); fit_fine_max_footprint applies.
constexpr int kFineFitSamples = 4;
constexpr double kFineFitLambda = 0.3;

struct BakeStats {
  size_t texels_filled = 0;   // texel centres inside some triangle
  size_t texels_dilated = 0;  // texels of a rectangle that no triangle covers (scaffolding, rounding)
  size_t texels_footprint_filtered = 0;  // texels averaged over more than one sample (minified input)
  size_t tiles_fitted = 0, tiles = 0;    // least-squares fit
};

/// Fills `images` (allocated by the caller). Texels whose centre lies inside a triangle (edges
/// included) get the bilinear sample of the input texture at the interpolated original UV; texels of a
/// rectangle in `rects` that no triangle covers are then filled by dilation from their covered
/// neighbours, within the same rectangle only (no bleeding between charts). Parallel over tiles of
/// the output with oneTBB; each tile processes its triangles in order, so the result is the same for
/// any thread count.
void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles,
                  const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats,
                  const BakeOptions& options = {});

}  // namespace tightex
