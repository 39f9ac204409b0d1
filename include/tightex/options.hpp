// tightex's options: what a caller chooses, with one name table per choice (used by the CLI, the report
// and the bindings alike). Every field's default is the CLI's default.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace tightex {

/// One texture for all components (kAtlas), or one texture per component (kPerComponent, the paper's).
enum class Layout { kAtlas, kPerComponent };

/// How texels are spread over the surface. kHarmonic: the paper's map exactly (cotangent harmonic,
/// boundary by arc length). kArea: the same number of texels per unit of 3D area everywhere. kTexel: the
/// input's own texel density per triangle. kDetail: texels where the texture has detail (density
/// proportional to the input texture's colour gradient per unit of 3D length, capped at 4x the input's
/// own density, at least an eighth of the mean). All four are fold-free and fill each component's
/// rectangle; all but kHarmonic then lower a symmetric Dirichlet energy with the boundary sliding along
/// the rectangle's sides (kArea only as far as its density spread holds).
enum class MapKind { kHarmonic, kArea, kTexel, kDetail };

/// kFill: holes (and the two sides of each cut handle) are capped with the §4.1 centroid fan, smallest
/// first, while the caps' total area stays within a budget of the component's area; larger ones are
/// opened into the disk boundary, since a large cap would waste its texels. kCut: none is capped.
enum class HoleMode { kFill, kCut };

/// Which boundary vertices go to the square's four corners (docs/corners.md).
enum class CornerRule {
  kEqualArcs,     // four arcs of (nearly) equal boundary length
  kTurningAngle,  // where the boundary turns most, each arc at least 10% of the length
};

/// The model file a run writes: OBJ + MTL, binary PLY, glTF (.gltf + .bin + images) or GLB.
enum class ModelFormat { kObj, kPly, kGltf, kGlb };

/// The texture image codecs tightex writes.
enum class ImageFormat { kPng, kJpeg, kWebp };

/// The name of each choice, as the CLI takes it and the report writes it. The compiler checks that
/// every value has one (-Wswitch); parse_* below read them back through the same switch.
constexpr std::string_view to_string(Layout v) {
  switch (v) {
    case Layout::kAtlas:
      return "atlas";
    case Layout::kPerComponent:
      return "per-component";
  }
  return "";
}
constexpr std::string_view to_string(MapKind v) {
  switch (v) {
    case MapKind::kHarmonic:
      return "harmonic";
    case MapKind::kArea:
      return "area";
    case MapKind::kTexel:
      return "texel";
    case MapKind::kDetail:
      return "detail";
  }
  return "";
}
constexpr std::string_view to_string(HoleMode v) {
  switch (v) {
    case HoleMode::kFill:
      return "fill";
    case HoleMode::kCut:
      return "cut";
  }
  return "";
}
constexpr std::string_view to_string(ModelFormat v) {
  switch (v) {
    case ModelFormat::kObj:
      return "obj";
    case ModelFormat::kPly:
      return "ply";
    case ModelFormat::kGltf:
      return "gltf";
    case ModelFormat::kGlb:
      return "glb";
  }
  return "";
}
constexpr std::string_view to_string(ImageFormat v) {
  switch (v) {
    case ImageFormat::kPng:
      return "png";
    case ImageFormat::kJpeg:
      return "jpg";
    case ImageFormat::kWebp:
      return "webp";
  }
  return "";
}
constexpr std::string_view to_string(CornerRule v) {
  switch (v) {
    case CornerRule::kEqualArcs:
      return "arcs";
    case CornerRule::kTurningAngle:
      return "turning";
  }
  return "";
}

/// Every value of each choice, in the order the CLI lists them.
inline constexpr std::array kLayouts{Layout::kAtlas, Layout::kPerComponent};
inline constexpr std::array kMapKinds{MapKind::kDetail, MapKind::kArea, MapKind::kTexel, MapKind::kHarmonic};
inline constexpr std::array kHoleModes{HoleMode::kFill, HoleMode::kCut};
inline constexpr std::array kCornerRules{CornerRule::kEqualArcs, CornerRule::kTurningAngle};
inline constexpr std::array kModelFormats{ModelFormat::kObj, ModelFormat::kPly, ModelFormat::kGltf, ModelFormat::kGlb};
inline constexpr std::array kImageFormats{ImageFormat::kPng, ImageFormat::kJpeg, ImageFormat::kWebp};

/// The value of `values` whose to_string is `name`; nullopt if none.
template <typename Enum, size_t N>
constexpr std::optional<Enum> from_string(const std::array<Enum, N>& values, std::string_view name) {
  for (Enum v : values)
    if (to_string(v) == name) return v;
  return std::nullopt;
}

/// Called with a stage name and the fraction [0, 1] of it done (an estimate within "cut+map", "bake"
/// and "encode", at most every 0.2 s there). The stages: ("read" for run,) "repair", "components",
/// "cut+map", "bake", then for optimize "measure" (where Options::measure) and "done"; for run "encode" (the images' codec and
/// rate control, --target-psnr's budget search included), "measure", "write" (the files), and "done"
/// once the last file is renamed into place. Calls never overlap and never go backwards within a stage,
/// but within "cut+map", "bake" and "encode" they may come from any thread working for the call.
/// Returning false cancels the run: the call in progress throws tightex::Cancelled soon after, and
/// nothing is returned nor written (run's "done" comes after the files: its answer changes nothing).
using ProgressCallback = std::function<bool(std::string_view stage, double fraction)>;

/// Options::aspect: the shape chosen per model, `size` given or not.
constexpr double kAspectAuto = -1;

/// Options::max_page_side's default: what WebGL and most engines accept.
constexpr int kDefaultMaxPageSide = 8192;
/// Options::max_piece_faces's default.
constexpr size_t kDefaultMaxPieceFaces = 6000000;

/// What a caller chooses, for the method (plan_charts, bake_plan, optimize) and for a whole run from
/// file to files (run). Every default is the CLI's; 0 means "choose for this model". The reasons and
/// figures behind the defaults: docs/decisions.md, "Options".
struct Options {
  // The texel budget and the texture's shape.
  /// The texture's side (per-component: the largest texture's). 0: the input's used texels (default_size).
  int size = 0;
  /// The texture holds this many texels (a square of side size_for_texels, or the shape `aspect` gives);
  /// 0: `size` decides. Not together with `size`.
  double texels = 0;
  /// Width / height of the texture, 1/16..16. 0: the square where `size` is given (a side is promised,
  /// as the command's --size: the library, the command, Python and the tile runner agree), else chosen
  /// per model (the square unless 2:1 or 1:2 keeps clearly more of the input; atlas layout, area, texel
  /// and detail maps). kAspectAuto: chosen per model even with `size` (the command's --aspect auto).
  double aspect = 0;
  /// A default budget's texture may be wider than 16384 texels, and `size` above 16384 is allowed.
  bool allow_large_textures = false;
  Layout layout = Layout::kAtlas;
  /// Atlas: the largest side of one texture page (0: no cap); a larger budget goes on several pages.
  int max_page_side = kDefaultMaxPageSide;
  /// The most triangles one chart holds (0: no cap); a larger component is split into pieces.
  size_t max_piece_faces = kDefaultMaxPieceFaces;

  // The method.
  HoleMode holes = HoleMode::kFill;
  MapKind map = MapKind::kDetail;
  /// Area, texel and detail maps: 1 = the target density exactly, 0 = the harmonic map's; between, a blend.
  double balance = 1.0;
  CornerRule corners = CornerRule::kEqualArcs;
  /// Least-squares fit of the baked texels to the input under bilinear read-back.
  bool fit = true;
  /// The fit on 4 x 4 points per texel instead of 2 x 2: a little higher PSNR, about twice the bake time.
  bool fine_fit = false;
  /// Maps other than the base colour: a map short of its check is baked larger where its texels pay
  /// for themselves, one at or above this PSNR (dB) smaller while it stays there; 0: all at the base colour's size.
  double material_map_budget_db = 51;
  /// Triangles with nothing to bake (no texture, no vertex colours) are written as they came; false:
  /// their colour is baked like any other (PLY has no material to keep it in).
  bool keep_untextured = true;
  /// Compute the docs/metrics.md figures into the report (optimize, bake_plan; run always measures).
  bool measure = true;

  // The run's resources.
  /// The files the input model names may lie outside its folder (ModelReadOptions::allow_outside_files).
  bool allow_outside_files = false;
  /// Refuse a run whose estimated memory exceeds this many MiB, before any pixel is allocated; 0: 90% of RAM.
  double max_memory_mib = 0;
  /// Progress and cancellation (see ProgressCallback); empty: none.
  ProgressCallback progress;

  // What run() writes.
  /// The model's format; nullopt: the input's kind (.ply, .gltf, .glb as the input, anything else OBJ).
  std::optional<ModelFormat> model_format;
  /// The textures' codec; nullopt: the input's base colour's (PNG for vertex colours or mixed inputs).
  std::optional<ImageFormat> texture_format;
  /// PNG: zlib level 0..9 with the adaptive filter, or kPngLevelFast (-1: level 1, run-length, Up
  /// filter); nullopt: kDefaultPngLevel (6).
  std::optional<int> png_level;
  /// JPEG quality 1..100; nullopt: rate control (the highest quality within the input's bytes, or below).
  std::optional<int> jpeg_quality;
  /// Lossy WebP quality 1..100; nullopt: rate control, as for JPEG.
  std::optional<int> webp_quality;
  /// WebP: lossless instead of lossy.
  bool webp_lossless = false;
  /// Lossy codecs: the fewest bytes whose written images reach this surface PSNR (dB; 0: none), choosing
  /// the quality and, without `size` or `texels`, the texel budget.
  double target_psnr_db = 0;
  /// Lossy codecs: the highest quality whose images take at most this many bytes (0: none).
  uint64_t max_bytes = 0;
  /// A lossy output: the report also gives the bytes the input's own images take re-encoded in the same
  /// codec at the surface PSNR the output's reach (report.json bytes.reencode): what tightex saves.
  bool compare_reencode = false;
  /// report.json's path; empty: OUTDIR/report.json.
  std::string report_path;
  /// A PNG of the input texture(s) beside the output's; empty: none.
  std::string preview_path;
  /// Write OUTDIR/report.html (the figures, the atlases and a 3D before/after viewer in one page).
  bool html = true;
};

/// The aspect a run makes of `o` (Options::aspect): 1 for 0 with a size, 0 (chosen per model) for
/// kAspectAuto, else as given.
inline double effective_aspect(const Options& o) { return o.aspect == kAspectAuto ? 0.0 : o.aspect == 0 && o.size > 0 ? 1.0 : o.aspect; }

}  // namespace tightex
