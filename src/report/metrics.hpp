// The figures of docs/metrics.md, computed from an input and an output model alone, so the same
// code measures tightex's own result (in memory) and any other tool's output (read from its files).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/mesh.hpp"
#include "report/welded_edges.hpp"

namespace tightex {

/// The sample points of the surface PSNR and every map's figures (docs/metrics.md): at 200,000 the seed
/// alone moves the figure by up to 0.8 dB on real scans, at 1,000,000 by under 0.1. The sanitizer
/// preset (CMakePresets.json "asan") builds with fewer: the same code, a tenth of its loop, where it
/// took over half the sanitized tests' time; the Release tests measure with 1,000,000.
#ifndef TIGHTEX_PSNR_POINTS
#define TIGHTEX_PSNR_POINTS 1000000
#endif
constexpr size_t kPsnrPoints = TIGHTEX_PSNR_POINTS;

struct Quantiles {
  double p5 = 0, p50 = 0, p95 = 0;
};

struct ModelFigures {
  double utilization = 0;  // texel-weighted over all images
  std::vector<double> image_utilization;
  double used_texels = 0;
  size_t texels = 0;  // sum of W x H
};

/// One map slot's figures (docs/metrics.md: the surface PSNR of its effective values, over the
/// channels the slot reads; for a tangent-space normal map the angle between the object-space normals
/// decoded from input and output through their own tangent frames, in degrees). Every sample point
/// counts: a face without the slot shows its factor alone (its vertex normal).
struct MaterialMapFigures {
  MaterialSlot slot = MaterialSlot::kMetallicRoughness;
  double surface_psnr = 0;                                    // not for normal maps
  double angle_median = -1, angle_p95 = -1, angle_mean = -1;  // normal maps only
  size_t samples = 0;                                         // the sample points
};

struct Metrics {
  ModelFigures input, output;
  size_t lost_triangles = 0;
  size_t flipped = 0;
  size_t degenerate = 0;
  double overlap = 0;
  size_t charts = 0;
  size_t charts_input = 0;  // shown on report.html, not written by to_json
  double seam_length_input = 0, seam_length = 0;
  Quantiles density_spread;  // log2(d / mean d), area-weighted
  double detail_loss_area = 0;
  double angle_distortion_mean = 0, angle_distortion_p95 = 0;
  /// docs/metrics.md "texture axes angle": how far, in degrees (0..45), the input's texture axes turn
  /// in the output, modulo a right angle; area-weighted mean and quantiles.
  double axes_angle_mean = 0;
  Quantiles axes_angle;
  double surface_psnr = 0;
  /// Where the images are written lossily (the command: JPEG, lossy WebP), surface_psnr is that of the
  /// images as written (decoded back) and this the bake's before encoding; unset otherwise.
  std::optional<double> surface_psnr_bake;
  size_t psnr_samples = 0;
  std::vector<MaterialMapFigures> maps;  // each slot some material of either model binds
};

/// Texel utilization of a model (texel centres inside at least one triangle sampling that image,
/// edges included; coordinates outside [0,1] wrap as a renderer's repeat sampler does). Textures that
/// no material binds as its base colour but some binds as another map (Material::maps) are not
/// counted: they share the base colour's layout.
ModelFigures measure_texture_space(const TexturedMesh& mesh);

/// Charts (triangles joined through edges with equal uv on both sides) of a model; `seam_length`
/// (optional) gets docs/metrics.md's seam length: the 3D length of the edges whose uv differs on the two
/// sides over the square root of the surface area.
size_t count_charts(const TexturedMesh& mesh, double* seam_length);
/// count_charts with the model's welded edges made already (welded_edges).
size_t count_charts(const TexturedMesh& mesh, const WeldedEdges& edges, double* seam_length);

/// Everything in docs/metrics.md for a result `output` of `input`. Triangles correspond by their three
/// corner positions (bit-exact); an input triangle without a counterpart is lost and samples black in
/// the surface PSNR. Requires two valid meshes (as read_obj returns them); the surface PSNR draws
/// `psnr_samples` points with a fixed seed, so the same models always give the same figures. Never
/// throws but for allocation.
Metrics measure(const TexturedMesh& input, const TexturedMesh& output, size_t psnr_samples = kPsnrPoints);
/// measure with both models' welded edges made already (welded_edges), for a caller that shares them.
Metrics measure(const TexturedMesh& input, const TexturedMesh& output, const WeldedEdges& input_edges, const WeldedEdges& output_edges,
                size_t psnr_samples = kPsnrPoints);

/// docs/metrics.md's surface PSNR alone (measure's figure, the same points), for a caller that tries other
/// encodings of the same output's images.
double surface_psnr(const TexturedMesh& input, const TexturedMesh& output, size_t psnr_samples = kPsnrPoints);

/// surface_psnr of one input against outputs that differ from `output` in their images alone (the same
/// triangles and texture coordinates; other sizes allowed): the points, the input's colour at each and
/// where each falls in the output are found once, so a call reads only the output's images, for a
/// caller that tries many encodings or sizes of the same layout.
class SurfacePsnrOfImages {
 public:
  SurfacePsnrOfImages(const TexturedMesh& input, const TexturedMesh& output, size_t psnr_samples = kPsnrPoints);
  ~SurfacePsnrOfImages();
  double operator()(const TexturedMesh& output) const;

 private:
  struct Points;
  std::unique_ptr<Points> points_;
};

/// The judges a search of encodings asks: one at a tenth of the report's points for its steps, one at
/// the report's points for its answer (null where not made). Shared, so that a search of another bake
/// of the same triangles asks them again instead of making its own.
struct PsnrJudges {
  std::shared_ptr<const SurfacePsnrOfImages> few, all;
};

/// The figures of every map slot that both models bind (MaterialMapFigures), at the surface PSNR's points.
std::vector<MaterialMapFigures> measure_material_maps(const TexturedMesh& input, const TexturedMesh& output, size_t samples = kPsnrPoints);

/// docs/metrics.md's correspondence, for tools that look at single triangles: per input triangle the output
/// triangle with the same three corner positions (kNoOutputTriangle where it is lost), and per input
/// corner the output corner at its position.
struct TriangleMatch {
  static constexpr uint32_t kNoOutputTriangle = UINT32_MAX;
  std::vector<uint32_t> output_triangle;
  std::vector<std::array<int, 3>> output_corner;
};
TriangleMatch match_output_triangles(const TexturedMesh& input, const TexturedMesh& output);

/// docs/metrics.md "texture axes angle" of one triangle: the affine map from its input texels to its
/// output texels (corner `in_uv[k]` to `out_uv[k]`, each scaled by its image's width and height) turns
/// the input's u and v axes; the angle of each image to the nearest output axis, folded to 0..45
/// degrees (a quarter or half turn, or a mirror, keeps the axes), averaged over the two. NaN where
/// either triangle has no texture area.
double texture_axes_angle(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels, const std::array<Vec2, 3>& out_uv,
                          const Vec2& out_texels);

/// The metrics as report.json's "metrics" section (and `tightex measure`'s output).
nlohmann::json to_json(const Metrics& m);

}  // namespace tightex
