#include "param/density_targets.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/statistics.hpp"

namespace tightex {

namespace {

/// Scaffolding (hole caps) is not surface: it gets a quarter of the component's median density, so the
/// texels it wastes stay few without squeezing the rim of the hole.
constexpr double kScaffoldDensity = 0.25;
/// A cap face's target is at least that of a cap face of this fraction of the disk's mean surface face
/// area, so that cap faces of zero 3D area cannot be squeezed without end (docs/decisions.md).
constexpr double kMinScaffoldArea = 1e-2;
/// The input's density is followed within a factor of 16 of its median: a triangle the input gave no
/// texels (degenerate UVs) or absurdly many must not take the map to an extreme.
constexpr double kDensityRange = 16.0;
/// Symmetric Dirichlet steps of the texel and detail maps (they stop earlier once a step gains < 0.1%).
constexpr int kRefineToConvergence = 30;
/// The detail map's cap (times the input's own density) and floor (of the mean density); chosen by
/// measurement (docs/decisions.md).
constexpr double kDetailCap = 4.0, kDetailFloor = 0.125;
/// Smoothing rounds of the detail density: kDetailSmoothingTexels / (the budget's texels per face),
/// rounded down, at most kDetailMaxSmoothing, so faces of a few texels are smoothed over their rings and
/// faces of hundreds of texels keep their own density (docs/decisions.md).
constexpr double kDetailSmoothingTexels = 60.0;
constexpr int kDetailMaxSmoothing = 6;

std::vector<double> face_areas(const Surface& s) {
  std::vector<double> a3(s.num_faces());
  for (size_t f = 0; f < s.num_faces(); ++f) a3[f] = triangle_area(s.positions, s.triangles[f]);
  return a3;
}

double weighted_median(std::vector<std::pair<double, double>>& value_weight) { return weighted_quantile(value_weight, 0.5); }

/// kTexel: the input's texels per unit area, clamped around their median.
void set_texel_density(const TexturedMesh& input, const Surface& comp, const std::vector<double>& a3, ComponentDensity& d) {
  std::vector<std::pair<double, double>> vw;
  for (size_t f = 0; f < d.face.size(); ++f) {
    const size_t t = comp.input_face[f];
    d.face[f] = a3[f] > 0 ? input_texel_area(input, t) / a3[f] : 0.0;
    if (d.face[f] > 0 && std::isfinite(d.face[f])) vw.push_back({d.face[f], a3[f]});
  }
  if (vw.empty()) {
    d.textured = false;
    d.face.assign(d.face.size(), 1.0);
    return;
  }
  d.median = weighted_median(vw);
  for (double& x : d.face) x = std::isfinite(x) ? std::clamp(x, d.median / kDensityRange, d.median * kDensityRange) : d.median;
}

/// The detail density of face f for the scale c (see allocate_detail).
double detail_density(const ComponentDensity& d, size_t f, double c, double mean, double floor) {
  const double cap = d.input_density[f] > 0 ? kDetailCap * d.input_density[f] : mean;
  return std::max(floor, std::min(c * d.detail[f], std::max(cap, floor)));
}

/// The scale c at which the detail densities take `budget` texels (bisection).
double detail_scale(const std::vector<ComponentDensity>& density, double budget, double mean, double max_detail) {
  const double floor = kDetailFloor * mean;
  auto texels = [&](double c) {
    double sum = 0;
    for (const ComponentDensity& d : density)
      for (size_t f = 0; f < d.area3.size(); ++f) sum += d.area3[f] * detail_density(d, f, c, mean, floor);
    return sum;
  };
  double lo = 0, hi = mean / max_detail;
  for (int i = 0; i < 200 && texels(hi) < budget && std::isfinite(hi); ++i) hi *= 2;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (texels(mid) < budget ? lo : hi) = mid;
  }
  return hi;
}

/// Area-weighted averages of log density over each face and its edge neighbours, `rounds` times.
void smooth_log_density(const Surface& comp, const std::vector<double>& area3, int rounds, std::vector<double>& lg) {
  std::vector<double> next(lg.size());
  for (int round = 0; round < rounds; ++round) {
    for (size_t f = 0; f < lg.size(); ++f) {
      double sw = area3[f], sv = area3[f] * lg[f];
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = comp.opposite[3 * f + size_t(k)];
        if (o == kNone) continue;
        sw += area3[o / 3], sv += area3[o / 3] * lg[o / 3];
      }
      next[f] = sw > 0 ? sv / sw : lg[f];
    }
    lg.swap(next);
  }
}

}  // namespace

ComponentDensity component_density(const TexturedMesh& input, const Surface& comp, MapKind map) {
  ComponentDensity d;
  const size_t nf = comp.num_faces();
  d.face.assign(nf, 1.0);
  const std::vector<double> a3 = face_areas(comp);
  if (map == MapKind::kTexel) set_texel_density(input, comp, a3, d);
  if (map == MapKind::kDetail) {
    d.area3 = a3;
    d.detail.resize(nf);
    d.input_density.resize(nf);
    // 15 points x 4 bilinear samples per face: parallel over faces (each writes its own slot).
    tbb::parallel_for(size_t(0), nf, [&](size_t f) {
      const size_t t = comp.input_face[f];
      d.detail[f] = input_detail(input, t);
      d.input_density[f] = a3[f] > 0 ? input_texel_area(input, t) / a3[f] : 0.0;
    });
  }
  for (size_t f = 0; f < nf; ++f) d.texels += d.face[f] * a3[f];
  return d;
}

namespace {

/// allocate_detail but the release of its inputs.
void allocate_detail_densities(const std::vector<Surface>& components, std::vector<ComponentDensity>& density, double budget) {
  double area = 0, max_detail = 0;
  size_t faces = 0;
  for (const ComponentDensity& d : density) {
    for (size_t f = 0; f < d.area3.size(); ++f) area += d.area3[f], max_detail = std::max(max_detail, d.detail[f]);
    faces += d.area3.size();
  }
  if (!(area > 0) || !(max_detail > 0) || !(budget > 0)) return;  // no detail anywhere: the area map
  const double mean = budget / area, floor = kDetailFloor * mean;
  if (!std::isfinite(mean) || !std::isfinite(mean / max_detail) || !(mean / max_detail > 0)) return;  // absurd units: the area map
  const double scale = detail_scale(density, budget, mean, max_detail);
  const double per_face = budget / double(std::max<size_t>(faces, 1));
  const int rounds = int(std::floor(std::min(double(kDetailMaxSmoothing), kDetailSmoothingTexels / per_face)));
  for (size_t c = 0; c < density.size(); ++c) {
    ComponentDensity& d = density[c];
    const size_t nf = d.area3.size();
    std::vector<double> lg(nf);
    for (size_t f = 0; f < nf; ++f) lg[f] = std::log(detail_density(d, f, scale, mean, floor));
    smooth_log_density(components[c], d.area3, rounds, lg);
    d.texels = 0;
    for (size_t f = 0; f < nf; ++f) d.texels += (d.face[f] = std::exp(lg[f])) * d.area3[f];
    std::vector<std::pair<double, double>> vw;
    for (size_t f = 0; f < nf; ++f) vw.push_back({d.face[f], d.area3[f]});
    if (!vw.empty()) d.median = weighted_median(vw);
  }
}

}  // namespace

void allocate_detail(const std::vector<Surface>& components, std::vector<ComponentDensity>& density, double budget) {
  allocate_detail_densities(components, density, budget);
  // Spent: three doubles a face that would otherwise stay through the maps (82 MB at 3.4M faces).
  for (ComponentDensity& d : density) d.area3 = {}, d.detail = {}, d.input_density = {};
}

std::vector<double> texture_shares(std::vector<ComponentDensity>& density, const std::vector<double>& areas) {
  const size_t nc = density.size();
  std::vector<double> shares(nc);
  for (size_t c = 0; c < nc; ++c) shares[c] = density[c].texels;
  double sum_texels = 0, sum_area = 0;
  for (size_t c = 0; c < nc; ++c)
    if (density[c].textured) sum_texels += density[c].texels, sum_area += areas[c];
  const double mean = sum_area > 0 && sum_texels > 0 ? sum_texels / sum_area : 1.0;
  for (size_t c = 0; c < nc; ++c)
    if (!density[c].textured) {
      for (double& x : density[c].face) x *= mean;
      density[c].median *= mean;
      shares[c] = areas[c] * mean;
    }
  return shares;
}

void set_face_targets(const Disk& disk, const ComponentDensity& density, MapKind map, double balance, SquareMapOptions& mo) {
  mo.face_target.clear();
  mo.balance = balance;
  mo.density_flow = map == MapKind::kArea;
  if (map == MapKind::kHarmonic) return;
  if (map != MapKind::kArea) {
    mo.refine_keeps_density = false;
    mo.refine_iterations = kRefineToConvergence;
  }
  const Surface& m = disk.mesh;
  mo.face_target.resize(m.num_faces());
  const std::vector<double> a3 = face_areas(m);
  double real_area = 0;
  size_t real = 0;
  for (size_t f = 0; f < m.num_faces(); ++f)
    if (m.face_parent[f] != kNone) real_area += a3[f], ++real;
  // A hole whose rim's vertex mean lies on the line of a rim edge gets cap faces of zero 3D area; a
  // target of zero area would let the reweighting squeeze them without end and crush their neighbours.
  const double min_scaffold = real > 0 ? kMinScaffoldArea * real_area / double(real) : 0.0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const uint32_t cf = m.face_parent[f];
    const double t = cf == kNone ? kScaffoldDensity * density.median * std::max(a3[f], min_scaffold) : a3[f] * density.face[cf];
    mo.face_target[f] = std::max(t, 1e-300);
  }
}

}  // namespace tightex
