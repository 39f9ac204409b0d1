// Where the texels go: the target texel density of every face, per map kind (Options::map), from which
// the layout shares the texture out and the square map takes its per-face targets.
#pragma once
#include <vector>

#include "core/disk.hpp"
#include "core/mesh.hpp"
#include "core/surface.hpp"
#include "param/param.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// Target texel density (texels per unit of 3D area, any common scale) of each face of a component.
struct ComponentDensity {
  std::vector<double> face;  // per component face
  double median = 1.0;       // area-weighted median of face
  double texels = 0.0;       // sum of density x 3D area: the component's share of the texture
  bool textured = true;      // false: no face had a texture of known size (area density used)
  // Detail map only: per face its 3D area, texture detail (input_detail) and input texel density,
  // allocate_detail's inputs, which it releases.
  std::vector<double> area3, detail, input_density;
};

/// The density of one component for `map`: uniform for kArea and kHarmonic; for kTexel the input's own
/// texels per area, clamped to within kDensityRange of its median; for kDetail the per-face inputs of
/// allocate_detail (the densities themselves come from there). Requires the component's input map.
ComponentDensity component_density(const TexturedMesh& input, const Surface& component, MapKind map);

/// The detail map's densities over all components for a budget of `budget` texels: c x detail, capped
/// at kDetailCap times the input's own density and at least kDetailFloor of the mean, c chosen by
/// bisection so the surface takes the budget; then smoothed over face neighbours in log space where faces
/// get few texels. Leaves the uniform density where no face has texture detail. Releases each
/// density's area3, detail and input_density.
void allocate_detail(const std::vector<Surface>& components, std::vector<ComponentDensity>& density, double budget);

/// Gives components without any texture the mean density of the textured ones (per unit area), so
/// that they share the texture by area; returns every component's share of the texture (its texels).
std::vector<double> texture_shares(std::vector<ComponentDensity>& density, const std::vector<double>& areas);

/// The square map's options for a disk cut from a component of density `density`: per-face targets
/// (the face's 3D area times its density; scaffolding gets kScaffoldDensity of the median), balance,
/// and the refinement settings of the map kind. Nothing for the harmonic map.
void set_face_targets(const Disk& disk, const ComponentDensity& density, MapKind map, double balance, SquareMapOptions& mo);

}  // namespace tightex
