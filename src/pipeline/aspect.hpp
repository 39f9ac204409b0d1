// The texture's shape (Options::aspect 0): the component that holds most of the texture is mapped into
// a square and, where that map's texels are stretched along one axis, into the texture of the same
// budget that the stretch points to (2:1 where texels are long along x, else 1:2); the shape whose map
// keeps the most of the input's colour (better_map on
// resampling_mse) is chosen, the square unless another is clearly better. A component whose probes would
// be multilevel maps is not probed: the stretch is read off a small coarse copy's map, and the square's
// and the other shape's own maps are made side by side and chosen between.
#pragma once
#include <optional>
#include <vector>

#include "pipeline/map_component.hpp"
#include "report/report.hpp"

namespace tightex {

/// The shapes probed, width/height of the texture; the square first, which stays unless another
/// shape's estimated error is at most kAspectMinGain of it.
constexpr double kAspectProbes[] = {1.0, 0.5, 2.0};

/// Another shape is probed only where the square's map has texels longer on the surface along one
/// axis than along the other by more than this, in squared length (texel_stretch_ratio outside
/// [1/k, k]): the best shape is about sqrt(ratio) wide per high, and where that is near 1 neither 1:2
/// nor 2:1 wins; beyond it only the shape on the stretch's side (2:1 above k, 1:2 below 1/k).
/// Measured on ../shared/data: BENCHMARKS.md, "Options".
constexpr double kAspectProbeStretch = 1.35;

/// For a component chosen on own maps (too large to probe), the stretch of its coarse copy's map (2k
/// vertices) from which the other shape's own map is made too: a coarse copy reads a milder stretch
/// than a probe, and 2:1 is nearer than the square to the best shape only from a ratio of about 2
/// (docs/maps.md, where the measurements are).
constexpr double kShapeLookStretch = 1.6;

/// The shape chosen, what each probe was estimated to give (estimated_mse < 0: not probed, since the
/// shape cannot hold every component, or not mapped; full_map_estimated_mse where own maps were
/// compared instead), and the probed component's map in that shape.
struct ShapeChoice {
  double aspect = 1.0;
  std::vector<AspectProbe> probes;
  std::optional<Mapped> dominant_map;  // the probed component's map in the chosen shape
  double square_texel_stretch = -1;    // texel_stretch_ratio of the square's probe (or coarse copy's) map; < 0: not mapped
};

/// How much longer a texel of the map is on the surface along the texture's x axis than along its y
/// axis, squared, over all texels: the sum of A |dp/dx|^2 over the sum of A |dp/dy|^2 over the disk's
/// triangles (p the surface point, x and y in texels of the map's rectangle, A a triangle's texel
/// area); scaffolding does not count. 1 where texels are as long as wide; 4 for a 2:1 sheet mapped
/// affinely into a square.
double texel_stretch_ratio(const Mapped& m);

/// The component whose shape decides the texture's: the one holding at least half the texels, if the
/// shape is to be chosen (Options::aspect 0, not the harmonic map, atlas layout), its texture's pixels
/// are known and it has at most kProbeMaxFaces faces; kNone otherwise.
size_t aspect_probe_component(const MapContext& ctx, const std::vector<double>& shares);

/// Maps component `dominant` into its rectangle of each probe's texture (size^2 texels) and chooses.
/// `shared`: the component's cut_inputs, which every probe and map of it shares (nullptr where their
/// search met an InternalError: each map then meets it again and reports it as its fallback).
ShapeChoice choose_aspect(const MapContext& ctx, size_t dominant, const CutInputs* shared, const std::vector<double>& shares, int size,
                          AtlasShares mode);

}  // namespace tightex
