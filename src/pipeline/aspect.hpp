// The texture's shape (Options::aspect 0): the component that holds most of the texture is mapped into
// a square, a 1:2 and a 2:1 texture of the same budget, and the shape whose map keeps the most of the
// input's colour (better_map on resampling_mse) is chosen; the square unless another is clearly better.
#pragma once
#include <optional>
#include <vector>

#include "pipeline/map_component.hpp"
#include "report/report.hpp"

namespace tightex {

/// The shapes probed, width/height of the texture; the square first, which stays unless another
/// shape's estimated error is at most kAspectMinGain of it.
constexpr double kAspectProbes[] = {1.0, 0.5, 2.0};

/// The shape chosen, what each probe was estimated to give (estimated_mse < 0: not probed, since the
/// shape cannot hold every component, or not mapped), and the probed component's map in that shape.
struct ShapeChoice {
  double aspect = 1.0;
  std::vector<AspectProbe> probes;
  std::optional<Mapped> dominant_map;  // the probed component's map in the chosen shape
};

/// The component whose shape decides the texture's: the one holding at least half the texels, if the
/// shape is to be chosen (Options::aspect 0, not the harmonic map, atlas layout), its texture's pixels
/// are known and it has at most kProbeMaxFaces faces; kNone otherwise.
size_t aspect_probe_component(const MapContext& ctx, const std::vector<double>& shares);

/// Maps component `dominant` into its rectangle of each probe's texture (size^2 texels) and chooses.
ShapeChoice choose_aspect(const MapContext& ctx, size_t dominant, const std::vector<double>& shares, int size, AtlasShares mode);

}  // namespace tightex
