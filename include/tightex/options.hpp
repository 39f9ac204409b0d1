// tightex's options: what a caller chooses, with one name table per choice (used by the CLI, the report
// and the bindings alike). Every field's default is the CLI's default.
#pragma once
#include <array>
#include <cstddef>
#include <functional>
#include <optional>
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

/// The value of `values` whose to_string is `name`; nullopt if none.
template <typename Enum, size_t N>
constexpr std::optional<Enum> from_string(const std::array<Enum, N>& values, std::string_view name) {
  for (Enum v : values)
    if (to_string(v) == name) return v;
  return std::nullopt;
}

/// Called with a stage name ("repair", "components", "cut+map", "bake", "measure", "done") and the
/// fraction [0, 1] of it done (an estimate within "cut+map" and "bake", at most every 0.2 s there).
/// Calls never overlap and never go backwards within a stage, but within "cut+map" and "bake" they may
/// come from any thread working for the call. Returning false cancels the run: the call in progress
/// throws tightex::Cancelled soon after, and nothing is returned.
using ProgressCallback = std::function<bool(std::string_view stage, double fraction)>;

/// What a caller chooses. Every default is the CLI's; 0 means "choose for this model".
/// Options::max_page_side's default.
constexpr int kDefaultMaxPageSide = 8192;
/// Options::max_piece_faces's default.
constexpr size_t kDefaultMaxPieceFaces = 6000000;

struct Options {
  /// Atlas: the texture's side; per-component: the largest texture's side. 0 (default): default_size,
  /// as many texels as the input uses, so the output keeps the input's information.
  int size = 0;
  /// `size` is the default budget (the input's used texels; always so for `size` 0), not a side the
  /// caller asked for. The CLI sets it when neither --size nor --texels is given. Then:
  /// - the atlas grows where `size` cannot hold a 4 x 4 rectangle for every component, to the side that
  ///   holds `size`^2 texels and 16 more per component, or more if the layout needs it (report
  ///   "options": "size_grown_from"); an asked-for size that cannot hold them is an InputError;
  /// - the per-component textures hold `size`^2 texels together (an asked-for size is the largest's side).
  bool default_budget = false;
  /// Width/height of the texture, which then holds about size x size texels (sides multiples of 4).
  /// 0 (default): chosen per model for the area, texel and detail maps in the atlas layout: the
  /// component that holds most of the texture is mapped into a square and, where its texels are
  /// stretched along one axis, into the 2:1 or 1:2 texture the stretch points to, each map's colour
  /// error estimated, and the square kept unless the other shape's is at least 5% lower
  /// (report "aspect"; not probed beyond 100k triangles). Otherwise 1, the paper's square.
  double aspect = 0;
  Layout layout = Layout::kAtlas;
  /// Atlas: the largest side of one texture page; 0: no cap. A budget whose texture would be wider or
  /// taller goes on several pages of at most max_page_side^2 texels, each component whole on one page;
  /// a component whose share alone is more than a page holds is first split into pieces that fit, each
  /// its own chart (report "pages"). 8192: what WebGL and most engines accept.
  int max_page_side = kDefaultMaxPageSide;
  /// The most triangles one chart holds; 0: no cap. A component of more is split into pieces of at
  /// most this many, each its own chart (and, per component, its own texture; report "pages"), as for
  /// a page. The map's memory grows faster than its triangles (its factorisations' fill): a 10M-face
  /// scan at its default budget peaks at 18.2 GiB in one piece, at 11.9 GiB in two (and takes 220 s,
  /// not 316 s; BENCHMARKS.md, "Memory the run needs").
  size_t max_piece_faces = kDefaultMaxPieceFaces;
  HoleMode holes = HoleMode::kFill;
  /// Default kDetail: the highest surface PSNR of the four maps on every model of ../shared/data at
  /// the input's budget (BENCHMARKS.md, "Quality per map").
  MapKind map = MapKind::kDetail;
  /// Angle/area trade-off of the area, texel and detail maps: 0 = the harmonic map's density (least
  /// angle distortion), 1 = the target density exactly; between, the geometric blend of the two.
  double balance = 1.0;
  /// Which boundary vertices become the square's corners (docs/corners.md).
  CornerRule corners = CornerRule::kEqualArcs;
  /// Least-squares fit of the baked texels to the input under bilinear read-back.
  bool fit = true;
  /// The fit on a 4 x 4 grid of points per texel instead of 2 x 2: a little higher surface PSNR at
  /// about twice the bake time; the texture coordinates do not change. Ignored without `fit`.
  bool fine_fit = false;
  /// The base colour filtered in linear light (each bilinear tap decoded from sRGB, the footprint mean
  /// encoded back), as the other colour maps are; off: filtered as stored (sRGB). An internal switch
  /// for measurement (CLI: the hidden --linear-light-colour); docs/decisions.md has the figures.
  bool linear_light_colour = false;
  /// The maps other than the base colour (metallic-roughness, occlusion, emissive, normal, ...): each is
  /// baked at the base colour's size and read back at 50k surface points, its PSNR taken against the
  /// input's map for each slot over the channels that slot reads (a packed occlusion-roughness-metallic
  /// image: the occlusion's red on its own). Where a slot is below this, on the default texel budget,
  /// the map may be baked again larger (steps of 1/8, 1/4 or 1/2 of the side, whichever divides the
  /// pages' sides, up to as many texels as its input images hold) while some slot falls short of what
  /// its check asks (the base colour's PSNR plus the difference an ideal re-sampler at the input's own
  /// density leaves between that slot and the base colour; at most this), in steps that about double
  /// its texels, each taken only where it gains 0.25 dB and removes as much squared error per added
  /// texel as the base colour's last texels do (its error at half its side); it stops at the first
  /// step that reaches every target (within it, at the interpolated smallest size that does).
  /// Otherwise it is halved (down to 1/16 of the side) while each slot's PSNR stays at or above this,
  /// or within 0.25 dB of the base colour's size's. A normal map is never baked larger and is halved
  /// while its PSNR against its own full-size bake stays at or above this. A flat or smooth map costs a
  /// fraction of the texels; the default keeps a 1 dB margin above 50 dB, beyond which differences are
  /// about 0.8 of an 8-bit level. 0: every map at the base colour's size (CLI --map-budget).
  double map_budget_db = 51;
  /// Compute the METRICS.md figures into report["metrics"]. A caller that writes the result can turn
  /// this off and measure beside the write (the CLI does).
  bool measure = true;
  /// Triangles with nothing to bake (no texture, no vertex colours) are written as they came, with
  /// their material. false: their colour is baked into the new texture like any other (an output
  /// format without materials, PLY, has no other place for it).
  bool keep_untextured = true;
  /// Progress and cancellation (see ProgressCallback); empty: none.
  ProgressCallback progress;
};

}  // namespace tightex
