// The new texture (paper §4.3, Alg. 3): every output triangle is scan-converted in the new texture
// space and each texel takes the colour of the original texture through the original UVs
// (rasterize_texels, scan_convert_triangle in bake.cpp); then dilation, and the least-squares fit for
// bilinear read-back (bake/fit.hpp). Sampling through one triangle: bake/sampler.hpp.
#pragma once
#include <array>
#include <functional>
#include <vector>

#include "core/mesh.hpp"
#include "core/stage_stats.hpp"
#include "layout/layout.hpp"

namespace tightex {

/// One triangle to bake: where it lands (pixel coordinates, x right, y down, texel centres at +0.5)
/// and where its colour comes from (texture coordinates in the input, after the material's -s/-o).
struct BakeTriangle {
  uint32_t image = 0;
  std::array<Vec2, 3> target_px;
  std::array<Vec2, 3> source_uv;
  int32_t material = -1;  // input material (-1: none, white)
  double area3 = 0;       // 3D area: the least-squares fit weighs the surface uniformly, as docs/metrics.md's PSNR does
};

/// The tangent frame at one corner of a triangle (see TexturedMesh::corner_tangent): the bitangent is
/// sign * cross(normal, tangent).
struct CornerFrame {
  Vec3 tangent = Vec3::UnitX(), normal = Vec3::UnitZ();
  double sign = 1;
};

/// A bake triangle's tangent frames: the input's (through which its normal map was authored) and the
/// output's (through which a renderer reads the new map), corner k of each at the triangle's corner k.
struct NormalFrames {
  std::array<CornerFrame, 3> input, output;
};

/// Which of the input's maps a bake reads (bake_material_map): per input material its texture for the map, and
/// how the texels are filtered (SlotEncoding).
struct MaterialMapSource {
  SlotEncoding encoding = SlotEncoding::kData;
  std::vector<int> texture_of_material;  // per input material: index into input.textures, -1: `flat`
  Rgba8 flat{255, 255, 255, 255};        // the value of a triangle without the map (or without a material)
  /// kTangentNormal: one per bake triangle (the same order). Required then.
  const std::vector<NormalFrames>* frames = nullptr;
};

struct BakeOptions {
  /// Footprint filtering: where a texel covers more than one input pixel (the input is minified), its
  /// colour is the mean of n x m bilinear samples spread over the texel's footprint in the input,
  /// n and m the footprint's extent in input pixels along the texel's two axes, at most this many.
  int max_footprint_samples = 8;
  /// Least-squares fit: a texture read back with bilinear filtering (as every renderer and docs/metrics.md
  /// do) blurs once more what a point-sampled bake already blurred. The fit chooses the texels whose
  /// bilinear reconstruction best matches the input at K x K points per texel, weighted by 3D area;
  /// solved by conjugate gradients on 64-texel tiles with a 3-texel halo (independent, deterministic).
  /// Skipped on tiles where every triangle magnifies the input by 2 or more (bilinear is right there).
  bool fit = true;
  int fit_iterations = 12;
  /// K: the fit's sample points are a K x K grid in each texel (clamped to [1, 8]). 2 is the default;
  /// K = 4 is the opt-in fine fit (kFineFitSamples) at about twice the bake time. Chosen by
  /// measurement (docs/decisions.md).
  int fit_samples = 2;
  /// With fit_samples > 2: a tile where some triangle's footprint exceeds this many input pixels per
  /// texel (along either axis) is fitted with the default K and lambda instead: there the finer grid
  /// loses detail. Chosen by measurement (docs/decisions.md).
  double fit_fine_max_footprint = 12.0;
  /// Optional: called with the fraction of the bake done (tiles rasterised, then fitted; a fitted tile
  /// counts as three), from the baking threads, never two calls at once, at most every progress_interval_s.
  std::function<void(double)> progress;
  double progress_interval_s = 0.2;  // the least time between two progress calls
  /// Pull of each texel towards its footprint-filtered bake, relative to the mean sample weight: a
  /// weaker pull over-fits the sample points of each texel; a stronger one gives the fit away. Chosen
  /// by measurement (docs/decisions.md).
  double fit_lambda = 1.0;
  /// bake_texture only: the base colour filtered in linear light, as bake_material_map filters a kSrgbColour
  /// map (no public option sets it: docs/decisions.md, "Bake and output"); off: as stored.
  bool linear_light_colour = false;
};

/// The fine fit (Options::fine_fit, CLI --fine-fit): BakeOptions::fit_samples and fit_lambda;
/// fit_fine_max_footprint applies. Chosen by measurement (docs/decisions.md).
constexpr int kFineFitSamples = 4;
constexpr double kFineFitLambda = 0.3;

/// The new texture (paper §4.3, Alg. 3, scan-line texture generation), then footprint filtering,
/// dilation and the least-squares fit for bilinear read-back.
/// Requires: `images` allocated by the caller (any size, contents overwritten where baked); each
/// triangle's material is -1 or an index into input.materials, whose texture is -1 or an index into
/// input.textures; triangles with an image index beyond `images` and rectangles with a negative one
/// or beyond are ignored; each rectangle lies inside its image and those of one image do not overlap.
/// Guarantees: texels whose centre lies inside a triangle (edges included) get the colour of the input
/// texture at the interpolated original UV (bilinear, or the footprint mean where the input is
/// minified; the material's flat colour without a texture; later triangles win); texels of a
/// rectangle that no triangle covers are filled by dilation from their covered neighbours, within the
/// same rectangle only (no bleeding between charts; grey when nothing in it is covered); then, with
/// options.fit, the red, green and blue of the tiles worth fitting are replaced by the least-squares
/// fit. Other texels are left as they were. Parallel over tiles of the output with oneTBB; the result
/// is the same for any thread count. Fills `stats` when not null.
/// Throws: nothing but std::bad_alloc (degenerate or non-finite triangles are skipped).
void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles, const std::vector<Rect>& rects,
                  std::vector<Image>& images, BakeStats* stats, const BakeOptions& options = {});

/// bake_texture for another map than the base colour: the same scan conversion, footprint filtering,
/// dilation and fit over the same triangles and rectangles, reading `map` instead of the materials'
/// base colour textures. kSrgbColour maps are filtered in linear light (each bilinear tap decoded from
/// sRGB, the footprint mean encoded back); kData maps as stored; kTangentNormal maps decode each sample
/// to object space through the input frame, average there, and encode the mean in the output frame at
/// the texel (then the fit matches the encoded values for bilinear read-back).
/// Requires: as bake_texture, and map.texture_of_material has one entry per input material; with
/// kTangentNormal, map.frames has one entry per triangle.
/// Guarantees and throws: as bake_texture.
void bake_material_map(const TexturedMesh& input, const MaterialMapSource& map, const std::vector<BakeTriangle>& triangles,
                       const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats, const BakeOptions& options = {});

}  // namespace tightex
