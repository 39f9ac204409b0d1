// tightex's options: what a caller chooses, with one name table per choice (used by the CLI, the report
// and the bindings alike). Every field's default is the CLI's default.
#pragma once
#include <array>
#include <cstddef>
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
    case Layout::kAtlas: return "atlas";
    case Layout::kPerComponent: return "per-component";
  }
  return "";
}
constexpr std::string_view to_string(MapKind v) {
  switch (v) {
    case MapKind::kHarmonic: return "harmonic";
    case MapKind::kArea: return "area";
    case MapKind::kTexel: return "texel";
    case MapKind::kDetail: return "detail";
  }
  return "";
}
constexpr std::string_view to_string(HoleMode v) {
  switch (v) {
    case HoleMode::kFill: return "fill";
    case HoleMode::kCut: return "cut";
  }
  return "";
}
constexpr std::string_view to_string(CornerRule v) {
  switch (v) {
    case CornerRule::kEqualArcs: return "arcs";
    case CornerRule::kTurningAngle: return "turning";
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

}  // namespace tightex
