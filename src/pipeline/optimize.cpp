// The whole method, stage after stage. Each stage lives in its own folder; this file only wires them
// together, keeps the maps back to the input triangles, and records what each stage did and cost.
#include <sys/resource.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>

#include "bake/bake.hpp"
#include "core/error.hpp"
#include "core/progress.hpp"
#include "cut/seams.hpp"
#include "layout/layout.hpp"
#include "param/param.hpp"
#include "pipeline/aspect.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "report/metrics.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

namespace {

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

class StageClock {
 public:
  explicit StageClock(nlohmann::json& out) : out_(out), last_(std::chrono::steady_clock::now()) {}
  void done(const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    out_.push_back({{"stage", stage}, {"seconds", std::chrono::duration<double>(now - last_).count()}, {"peak_rss_mib", peak_rss_mib()}});
    last_ = now;
  }

 private:
  nlohmann::json& out_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace

namespace {

/// The file name of a path without folder and extension ("a/b.c.png" -> "b.c").
std::string file_stem(std::string s) {
  const size_t slash = s.find_last_of('/');
  if (slash != std::string::npos) s = s.substr(slash + 1);
  const size_t dot = s.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? s : s.substr(0, dot);
}

std::string lower(std::string s) {
  for (char& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

/// A name that is safe as a file stem and an MTL token: letters, digits, '-', '_' and '.' (not first).
std::string file_name_safe(const std::string& s) {
  std::string r;
  for (char ch : s) r += std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || (ch == '.' && !r.empty()) ? ch : '_';
  return r.empty() ? std::string("texture") : r;
}

/// `base`, or base_2, base_3, ... : the first not in `taken` (without case), which it joins.
std::string unique_name(std::set<std::string>& taken, const std::string& base) {
  std::string name = base;
  for (int i = 2; taken.count(lower(name)) != 0; ++i) name = fmt::format("{}_{}", base, i);
  taken.insert(lower(name));
  return name;
}

const char* map_name(MapKind m) {
  return m == MapKind::kHarmonic ? "harmonic" : m == MapKind::kArea ? "area" : m == MapKind::kTexel ? "texel" : "detail";
}

/// Target texel density (texels per unit of 3D area, any common scale) of each face of a component.
struct ComponentDensity {
  std::vector<double> face;  // per component face
  double median = 1.0;       // area-weighted median of face
  double texels = 0.0;       // sum of density x 3D area: the component's share of the texture
  bool textured = true;      // false: no face had a texture of known size (area map used)
  // Detail map only: per face its 3D area, texture detail (input_detail) and input texel density.
  std::vector<double> area3, detail, input_density;
};

/// Scaffolding (hole caps) is not surface: it gets a quarter of the component's median density, so the
/// texels it wastes stay few without squeezing the rim of the hole.
constexpr double kScaffoldDensity = 0.25;
/// A cap face's target is at least that of a cap face of this fraction of the disk's mean surface face
/// area (set_face_targets). Measured on the flat plate with an S-shaped hole (test
/// Pipeline.AHoleCapWithFacesOfZeroAreaDoesNotCrushTheAreaMap) and the bust with six patches missing,
/// before refine_map gave faces without a 3D shape a frame: 1e-3 still squeezed two plate faces to
/// 0.55x the mean density; 1e-1 moved meshroom_esp32cam at --size 1024 41.70 -> 41.59 dB (its caps
/// have small faces); 1e-2 did neither.
constexpr double kMinScaffoldArea = 1e-2;
/// The input's density is followed within a factor of 16 of its median: a triangle the input gave no
/// texels (degenerate UVs) or absurdly many must not take the map to an extreme.
constexpr double kDensityRange = 16.0;
/// Symmetric Dirichlet steps of the texel and detail maps (they stop earlier once a step gains < 0.1%).
constexpr int kRefineToConvergence = 30;

/// The weighted median of (value, weight) pairs (non-empty; sorts them).
double weighted_median(std::vector<std::pair<double, double>>& vw) {
  std::sort(vw.begin(), vw.end());
  double total = 0, acc = 0;
  for (const auto& [v, w] : vw) total += w;
  for (const auto& [v, w] : vw)
    if ((acc += w) >= 0.5 * total) return v;
  return vw.back().first;
}

ComponentDensity component_density(const TexturedMesh& input, const Surface& surface, const Surface& comp, MapKind map) {
  ComponentDensity d;
  const size_t nf = comp.num_faces();
  d.face.assign(nf, 1.0);
  std::vector<double> a3(nf);
  for (size_t f = 0; f < nf; ++f) a3[f] = triangle_area(comp.positions[comp.triangles[f][0]], comp.positions[comp.triangles[f][1]], comp.positions[comp.triangles[f][2]]);
  if (map == MapKind::kTexel) {
    std::vector<std::pair<double, double>> vw;
    for (size_t f = 0; f < nf; ++f) {
      const size_t t = comp.input_face[f];
      d.face[f] = a3[f] > 0 ? input_texel_area(input, t) / a3[f] : 0.0;
      if (d.face[f] > 0 && std::isfinite(d.face[f])) vw.push_back({d.face[f], a3[f]});
    }
    if (vw.empty()) {
      d.textured = false;
      d.face.assign(nf, 1.0);
    } else {
      d.median = weighted_median(vw);
      for (double& x : d.face) x = std::isfinite(x) ? std::clamp(x, d.median / kDensityRange, d.median * kDensityRange) : d.median;
    }
  }
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

/// The detail map's densities (texels per 3D area, in output texels): c x detail, capped at kDetailCap
/// times the input's own density (beyond it a texel adds little the input holds) and at least
/// kDetailFloor of the mean, c chosen by bisection so the surface takes `budget` texels; then smoothed
/// over each face's neighbours (in log space) since a map's density cannot follow every single
/// triangle, and a face of few texels gives a noisy detail figure (15 points). A surface whose texture
/// has no detail at all gets the area map.
/// Chosen by measurement (surface PSNR at the input's budget, mustard / tomato / meshroom_esp32cam;
/// meshroom also at --size 1024): cap 1: 50.90 / 47.21 / 39.34 (1024: 40.26); cap 4: 52.96 / 47.66 /
/// 42.22 (42.38); no cap: 52.87 / 47.65 / 42.27 (41.81). Floor 1/16: 53.10 / 47.70 / 42.01; 1/4:
/// 53.01 / 47.68 / 41.55. Smoothing 1 round: 53.42 / 47.89 / 41.65; 6: 52.67 / 47.48 / 42.04.
/// Density proportional to detail^1.3: 52.86 / 47.59 / 41.48; ^0.8: 53.01 / 47.73 / 42.05.
constexpr double kDetailCap = 4.0, kDetailFloor = 0.125;
/// Smoothing rounds: kDetailSmoothingTexels / (the budget's texels per face), rounded down, at most
/// kDetailMaxSmoothing (so none from 60 texels a face up): faces of a few texels are smoothed over
/// their rings, faces of hundreds of texels keep their own density. Measured (session 10, surface PSNR
/// at the input's budget, rounds 0 / 1 / 2 / 3 / 5 / 8; texels per face in brackets): mustard [694] 53.73 / 53.47 / 53.19 / 52.95 / 52.76 / 52.52,
/// cracker [565] 47.19 / 46.49 / 46.34 / 46.32 / 46.14 / 45.94, tomato [500] 49.27 / 49.16 / 49.05 /
/// 48.96 / 48.84 / 48.70, potted [440] 47.42 / 47.25 / 47.02 / 46.78 / 46.67 / 46.65, fuze [135] 41.93 /
/// 41.95 / 42.08 / 42.06 / 42.02 / 41.99, girl [87] 49.59 / 49.44 / 49.39 / 49.32 / 49.35 / 49.25, bust [89]
/// 57.56 / 57.64 / 57.56 / 57.58 / 57.59 / 57.54, meshroom_esp32cam [18] 41.63 / 41.72 / 41.67 / 43.52 /
/// 42.44 / 42.61 (below 3 rounds its map's estimate picks 2:1, 1-2 dB short of the square at 3).
/// Until session 10 it was 3 rounds everywhere; in session 10 round(50 / texels per face), which gave
/// 1 round between 60 and 100 texels a face. Session 11, rounds 0 / 1 there: the YCB scans at --size
/// 1024 [64] cracker 35.24 / 34.71, potted 37.98 / 37.81, mustard 42.51 / 42.25, tomato 38.57 / 38.36;
/// girl above; bust above (-0.08); and 1 / 2 rounds at 30-33 texels: bust at --size 1024 [33] 55.80 /
/// 55.76.
constexpr double kDetailSmoothingTexels = 60.0;
constexpr int kDetailMaxSmoothing = 6;
void allocate_detail(const std::vector<Surface>& components, std::vector<ComponentDensity>& density, double budget) {
  double area = 0, max_detail = 0;
  for (const ComponentDensity& d : density)
    for (size_t f = 0; f < d.area3.size(); ++f) area += d.area3[f], max_detail = std::max(max_detail, d.detail[f]);
  if (!(area > 0) || !(max_detail > 0) || !(budget > 0)) return;  // no detail anywhere: the area map
  const double mean = budget / area, floor = kDetailFloor * mean;
  if (!std::isfinite(mean) || !std::isfinite(mean / max_detail) || !(mean / max_detail > 0)) return;  // absurd units: the area map
  auto density_at = [&](const ComponentDensity& d, size_t f, double c) {
    const double cap = d.input_density[f] > 0 ? kDetailCap * d.input_density[f] : mean;
    return std::max(floor, std::min(c * d.detail[f], std::max(cap, floor)));
  };
  auto texels = [&](double c) {
    double sum = 0;
    for (const ComponentDensity& d : density)
      for (size_t f = 0; f < d.area3.size(); ++f) sum += d.area3[f] * density_at(d, f, c);
    return sum;
  };
  double lo = 0, hi = mean / max_detail;
  for (int i = 0; i < 200 && texels(hi) < budget && std::isfinite(hi); ++i) hi *= 2;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (texels(mid) < budget ? lo : hi) = mid;
  }
  size_t faces = 0;
  for (const ComponentDensity& d : density) faces += d.area3.size();
  const double per_face = budget / double(std::max<size_t>(faces, 1));
  const int rounds = int(std::floor(std::min(double(kDetailMaxSmoothing), kDetailSmoothingTexels / per_face)));
  for (size_t c = 0; c < density.size(); ++c) {
    ComponentDensity& d = density[c];
    const Surface& comp = components[c];
    const size_t nf = d.area3.size();
    std::vector<double> lg(nf), next(nf);
    for (size_t f = 0; f < nf; ++f) lg[f] = std::log(density_at(d, f, hi));
    for (int round = 0; round < rounds; ++round) {
      for (size_t f = 0; f < nf; ++f) {
        double sw = d.area3[f], sv = d.area3[f] * lg[f];
        for (int k = 0; k < 3; ++k) {
          const uint32_t o = comp.opposite[3 * f + size_t(k)];
          if (o == kNone) continue;
          sw += d.area3[o / 3], sv += d.area3[o / 3] * lg[o / 3];
        }
        next[f] = sw > 0 ? sv / sw : lg[f];
      }
      lg.swap(next);
    }
    d.texels = 0;
    for (size_t f = 0; f < nf; ++f) d.texels += (d.face[f] = std::exp(lg[f])) * d.area3[f];
    std::vector<std::pair<double, double>> vw;
    for (size_t f = 0; f < nf; ++f) vw.push_back({d.face[f], d.area3[f]});
    if (!vw.empty()) d.median = weighted_median(vw);
  }
}

/// The map's per-face targets for a disk cut from component `comp` (nothing for the harmonic map).
void set_face_targets(const Disk& disk, const ComponentDensity& density, const Options& options, SquareMapOptions& mo) {
  mo.face_target.clear();
  mo.balance = options.balance;
  mo.density_flow = options.map == MapKind::kArea;
  if (options.map == MapKind::kHarmonic) return;
  if (options.map != MapKind::kArea) {
    mo.refine_keeps_density = false;
    mo.refine_iterations = kRefineToConvergence;
  }
  const Surface& m = disk.mesh;
  mo.face_target.resize(m.num_faces());
  std::vector<double> a3(m.num_faces());
  double real_area = 0;
  size_t real = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    a3[f] = triangle_area(m.positions[m.triangles[f][0]], m.positions[m.triangles[f][1]], m.positions[m.triangles[f][2]]);
    if (m.face_parent[f] != kNone) real_area += a3[f], ++real;
  }
  // A cap face is asked for at least the texels of a cap face of kMinScaffoldArea x the mean surface
  // face's area. A hole whose rim's vertex mean lies on the line of a rim edge (an S-shaped hole) gets
  // cap faces of zero 3D area, and a target of zero area made the reweighting squeeze them without end
  // (edge weights 1e-9..1e13 within 3 iterations on the bust with six patches missing): four real faces
  // beside the cap were crushed to slivers, then the cap folded and the reweighting stopped.
  const double min_scaffold = real > 0 ? kMinScaffoldArea * real_area / double(real) : 0.0;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const uint32_t cf = m.face_parent[f];
    const double t = cf == kNone ? kScaffoldDensity * density.median * std::max(a3[f], min_scaffold) : a3[f] * density.face[cf];
    mo.face_target[f] = std::max(t, 1e-300);
  }
}

/// One component cut and mapped (plan_charts' step 4), for the rectangle `rect`.
struct Mapped {
  Rect rect;
  Disk disk;
  std::vector<Vec2> uv;
  CutStats cut;
  SquareMapStats map;
  std::string kept;  // non-empty: neither the full method nor the fallback mapped it (Plan::kept)
};

/// The auto aspect's probes, width/height of the texture (the square first: it stays unless another is
/// clearly better). Measured (session 7, detail map at the input's budget, shapes 1/4 .. 3): only
/// ycb_005_tomato_soup_can gains among ../shared/data (0.5: 47.66 -> 49.00 dB); generated vases gain
/// up to 1.2 dB at 2. A can's side unrolls to about 2:1.
constexpr double kAspectProbes[] = {1.0, 0.5, 2.0};
/// Another shape replaces the square only if its estimated error is this fraction of the square's or
/// less (0.2 dB): the estimate is a simulation, and a square texture is the simpler one to use.
constexpr double kAspectMinGain = 0.95;
/// The area map's promise (issue 4): the density of 90% of the surface within a factor 2 of the mean.
constexpr double kAreaSpreadPromise = 1.0;
/// Surface points of the estimate (resampling_mse): the same points for every probe. Scans' errors are
/// heavy-tailed (meshroom_esp32cam: 0.1% of the surface holds 6% of the squared error): 32768 points
/// put its 2:1 map 1 dB above the square, 1M points 0.15 dB (the finished runs: 0.5 dB below).
constexpr size_t kAspectSamples = size_t(1) << 20;
/// Small textures take fewer: 4 per texel, at least this many (a 64^2 texture: 65536 instead of 1M;
/// fuzz_pipeline's tiny meshes ran 172 times in 240 s with 1M).
constexpr size_t kAspectMinSamples = 65536;
/// Beyond this many faces the dominant component is not probed: the square, unless Options::aspect asks
/// for a shape. Each probe is a whole map, and they cost more than the square's: a generated 225k-
/// triangle vase took cut+map 17.5 s square, 95.5 s probed (the square won). Below it the three probes
/// run side by side.
constexpr size_t kAspectProbeMaxFaces = 100000;
/// A longest hole of fewer edges than this is also tried capped (map_component): pepper noise leaves
/// 3..7-edge holes. As a fixed rule, capping below 4 / 8 edges moved 9 / 21 of 36 pepper runs (seeds
/// 7, 11, 13, 17), each way by up to 1 dB; mapped both ways and chosen by the estimate, 18 runs move,
/// +8.3 dB in all, the worst -0.53 (BENCHMARKS.md, "A small longest hole").
constexpr size_t kSmallKeptLoop = 8;
/// How map_component treats the longest hole: kAuto finds out whether it is small (small_longest_hole)
/// and then compares; kCompare maps it both ways and keeps the better (the caller knows it is small);
/// kKeep / kCap as already decided for another shape of the same component.
enum class CapChoice { kAuto, kCompare, kKeep, kCap };

/// The estimate's figure in the report: PSNR of a resampling_mse (< 0: none made).
double estimated_psnr_db(double mse) { return mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : mse == 0 ? 99.0 : -1.0; }

/// Whether map a (estimated error mse_a, resampling_mse; < 0: not mapped) beats map b by the factor
/// `gain` (<= 1: a must be that much better). The area map promises its density first: a map that keeps
/// P5..P95 of log2(area / target) within +-kAreaSpreadPromise beats one that does not, and among maps
/// that all miss, the nearest wins.
bool better_map(MapKind kind, const SquareMapStats& a, double mse_a, const SquareMapStats& b, double mse_b, double gain) {
  if (mse_a < 0) return false;
  if (mse_b < 0) return true;
  if (kind == MapKind::kArea) {
    auto spread = [](const SquareMapStats& m) { return std::max(-m.spread_p5, m.spread_p95); };
    const bool a_keeps = spread(a) <= kAreaSpreadPromise, b_keeps = spread(b) <= kAreaSpreadPromise;
    if (a_keeps != b_keeps) return a_keeps;
    if (!a_keeps) return spread(a) < spread(b);
  }
  return mse_a < mse_b * gain;
}

/// The library's entry check (read_obj guarantees all of this; a mesh built in code may not).
void validate(const TexturedMesh& m) {
  const std::string& f = m.source.empty() ? std::string("mesh") : m.source;
  if (m.triangles.empty()) fail_input("{}: no triangles", f);
  if (m.corner_uv.size() != 3 * m.triangles.size()) fail_input("{}: {} texture coordinates for {} triangles (needs 3 per triangle)", f, m.corner_uv.size(), m.triangles.size());
  if (m.face_material.size() != m.triangles.size()) fail_input("{}: {} face materials for {} triangles", f, m.face_material.size(), m.triangles.size());
  for (size_t v = 0; v < m.positions.size(); ++v)
    if (!m.positions[v].allFinite()) fail_input("{}: vertex {} has a NaN or infinite coordinate", f, v);
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    for (uint32_t v : m.triangles[t])
      if (v >= m.positions.size()) fail_input("{}: triangle {} uses vertex {} (mesh has {})", f, t, v, m.positions.size());
    for (int k = 0; k < 3; ++k)
      if (!m.corner_uv[3 * t + size_t(k)].allFinite()) fail_input("{}: triangle {} has a NaN or infinite texture coordinate", f, t);
    const int32_t mat = m.face_material[t];
    if (mat < -1 || mat >= int32_t(m.materials.size())) fail_input("{}: triangle {} uses material {} (mesh has {})", f, t, mat, m.materials.size());
  }
  for (size_t i = 0; i < m.materials.size(); ++i)
    if (m.materials[i].texture >= int(m.textures.size())) fail_input("{}: material {} uses texture {} (mesh has {})", f, i, m.materials[i].texture, m.textures.size());
}

}  // namespace

Plan plan_charts(const TexturedMesh& input, const Options& options) {
  validate(input);
  auto progress = [&](std::string_view stage, double f) {
    if (options.progress) options.progress(stage, f);
  };
  int size = options.size == 0 ? default_size(input) : options.size;
  if (size < 8 || size > 65536) fail_input("--size {} is out of range (8..65536)", size);
  if (options.aspect != 0 && !(options.aspect >= 1.0 / 16 && options.aspect <= 16))
    fail_input("aspect {} is out of range (0 for auto, or 1/16..16)", options.aspect);
  Plan plan;
  nlohmann::json timings = nlohmann::json::array();
  StageClock clock(timings);

  // 1. Repair (§4.1): weld, drop degenerate and duplicate triangles, slice non-manifold elements.
  progress("repair", 0);
  RepairStats rs;
  const Surface& surface = plan.surface = prepare_surface(input, &rs);
  if (surface.num_faces() == 0)
    fail_input("{}: no triangle with non-zero area ({} zero-area, {} duplicate)", input.source, rs.zero_area_triangles, rs.duplicate_triangles);
  clock.done("repair");

  // 2. Connected components and their areas (the layout needs only the areas).
  progress("components", 0);
  const std::vector<Surface>& components = plan.components = split_components(surface);
  const size_t nc = components.size();
  std::vector<double> areas(nc, 0.0);
  for (size_t c = 0; c < nc; ++c)
    for (const Tri& f : components[c].triangles)
      areas[c] += triangle_area(components[c].positions[f[0]], components[c].positions[f[1]], components[c].positions[f[2]]);
  // Options::default_budget: a texture that cannot hold a 4 x 4 rectangle per component grows (see
  // there). Tested with the components' areas as their shares (the bisection's limits are the count and
  // the smallest shares, rounded up to 4 x 4 alike for every map), before the detail map spends the
  // budget.
  const bool default_budget = options.size == 0 || options.default_budget;
  int size_grown_from = 0;
  if (options.layout == Layout::kAtlas && default_budget) {
    auto holds = [&](int s) {
      try {
        (void)layout_atlas(areas, s, s, 4, false);
        return true;
      } catch (const InputError&) {
        return false;
      }
    };
    if (!holds(size)) {
      size_grown_from = size;
      // Not beyond the default's limit (16M components fit there); past it, the layout's error.
      const int limit = std::max(size, kDefaultSizeMax);
      size = std::min(limit, size_for_texels(double(size) * double(size) + 16.0 * double(nc)));
      while (size < limit && !holds(size)) size = std::min(limit, size_for_texels(1.21 * double(size) * double(size)));
    }
  }
  // Target texel density per component face (area and texel maps); the layout shares the texture out
  // by each component's target texels.
  std::vector<ComponentDensity> density(nc);
  std::vector<double> shares = areas;
  if (options.map != MapKind::kHarmonic) {
    tbb::parallel_for(size_t(0), nc, [&](size_t c) { density[c] = component_density(input, surface, components[c], options.map); });
    if (options.map == MapKind::kDetail) allocate_detail(components, density, double(size) * double(size));
    for (size_t c = 0; c < nc; ++c) shares[c] = density[c].texels;
    // Components without any texture share by area at the overall mean density.
    double sum_texels = 0, sum_area = 0;
    for (size_t c = 0; c < nc; ++c)
      if (density[c].textured) sum_texels += density[c].texels, sum_area += areas[c];
    const double mean = sum_area > 0 && sum_texels > 0 ? sum_texels / sum_area : 1.0;
    for (size_t c = 0; c < nc; ++c)
      if (!density[c].textured) {
        for (double& d : density[c].face) d *= mean;
        density[c].median *= mean;
        shares[c] = areas[c] * mean;
      }
  }

  // 3. Layout: a rectangle of texels per component, in a texture of (about) size x size texels whose
  //    width/height is Options::aspect, or, on auto, the one of kAspectProbes whose map keeps the most of
  //    the texture (below, once the component that dominates the texture has been mapped at each).
  std::vector<Rect>& rects = plan.rects;
  int& num_images = plan.num_images;
  num_images = 1;
  std::vector<std::pair<int, int>>& image_size = plan.image_size;
  // W x H for a shape: W a multiple of 4 near size x sqrt(aspect), H the least multiple of 4 with
  // W x H >= size^2 (never fewer texels than the square).
  auto atlas_size = [&](double aspect) {
    if (aspect == 1.0) return std::pair{size, size};
    const int W = std::max(8, int(std::lround(size * std::sqrt(aspect) / 4)) * 4);
    const long need = (long(size) * long(size) + W - 1) / W;
    return std::pair{W, std::max(8, int((need + 3) / 4 * 4))};
  };
  double aspect = options.aspect > 0 ? options.aspect : 1.0;
  // The area map promises the same texels per unit area on every component; the others may give a
  // fragment that would be squeezed into a strip more than its share (layout_atlas).
  const bool exact_shares = options.map == MapKind::kArea;

  // 4. Cut each component to a disk and map it onto the unit square (§4.2). Where even positive
  //    weights fold (a region crowded below floating-point precision), the disk is slit to that
  //    region and cut again, up to kCrowdingRounds times.
  constexpr int kCrowdingRounds = 3;
  // Holes are capped within kCapBudget of the component's area (smallest first), as long as the caps
  // take at most kMaxCapTexels of its square (the output stays >= 99% used); otherwise with a budget
  // cut down in proportion, down to kFillBudget. An opened hole costs the map far more than its cap's
  // texels: on ../shared/data perturbed as unseen scans come (tools/perturb_obj.py, BENCHMARKS.md
  // "Perturbed scans"), 0.5% of the triangles missing: dancing girl 41.80 -> 48.99 dB, potted meat can
  // 41.48 -> 46.82; six 1% patches missing: meshroom_esp32cam 33.56 -> 40.24, bust 49.44 -> 53.37,
  // tomato can 39.25 -> 42.10 (cracker box -0.76); ../shared/data: the girl 49.03 -> 49.32 (its
  // handles' sides capped), the rest identical. A 5% budget: mixed against 2% (bust +2.1, girl -0.2).
  constexpr double kCapBudget = 0.02, kMaxCapTexels = 0.008;
  progress("cut+map", 0);
  // Progress of the maps, weighted by triangles: each component adds what its map reports (an
  // estimate, SquareMapOptions::progress) and the rest when it is done. The caller hears of it from
  // whichever thread is mapping, one at a time, at most every 0.2 s.
  double all_faces = 0;
  for (const Surface& comp : components) all_faces += double(comp.num_faces());
  bool have_pixels = false;  // the textures' pixels are loaded (the estimates need them)
  for (const Texture& t : input.textures) have_pixels = have_pixels || !t.image.empty();
  // The auto aspect maps the dominant component once per probe (its share of the texels at least half).
  size_t dominant = kNone;
  if (options.aspect == 0 && options.map != MapKind::kHarmonic && options.layout == Layout::kAtlas && nc > 0) {
    const size_t c = size_t(std::max_element(shares.begin(), shares.end()) - shares.begin());
    const double sum = std::accumulate(shares.begin(), shares.end(), 0.0);
    if (have_pixels && density[c].textured && shares[c] >= 0.5 * sum && components[c].num_faces() <= kAspectProbeMaxFaces) dominant = c;
  }
  if (dominant != kNone) all_faces += double(components[dominant].num_faces()) * double(std::size(kAspectProbes) - 1);
  ProgressCounter map_progress(options.progress ? std::function<void(double)>([&](double f) { options.progress("cut+map", f); }) : nullptr,
                               all_faces);
  auto forced_failure = [&](size_t c, const char* what) {
    if (std::find(options.test_fail_components.begin(), options.test_fail_components.end(), c) != options.test_fail_components.end())
      fail_internal("{} failure forced by Options::test_fail_components", what);
  };
  // What the cut needs of component c whatever its rectangle: the input's texture seams (cuts prefer
  // them) and, if it has handles, the handle search (once, whatever the rounds or the shapes probed).
  struct CutInputs {
    std::vector<char> seams;
    std::optional<Denoised> denoised;
  };
  auto cut_inputs = [&](size_t c) {
    CutInputs ci;
    ci.seams = find_texture_seams(input, components[c]);
    if (topology_of(components[c]).genus() > 0) {
      ci.denoised.emplace();
      ci.denoised->surface = remove_handles(components[c], &ci.denoised->handle_loops, ci.seams);
    }
    return ci;
  };
  // The estimate of a map's colour error (resampling_mse) for component c baked into rect.
  auto estimate_mse = [&](size_t c, const Disk& d, const std::vector<Vec2>& uv, const Rect& rect) {
    const size_t texels = size_t(rect.w) * size_t(rect.h);
    return resampling_mse(input, d.mesh, uv, rect.w, rect.h, std::clamp(4 * texels, kAspectMinSamples, kAspectSamples));
  };
  // Whether component c is also mapped with its longest hole capped (map_component): that hole has
  // fewer than kSmallKeptLoop edges and its cap fits the budget; not for the paper's map, which keeps
  // the paper's cut; only where the texture's pixels are known (the estimate needs them), and not
  // beyond kAspectProbeMaxFaces (each try is a whole map, as a probe is). One cut, without a map.
  auto small_longest_hole = [&](size_t c, const CutInputs& ci) {
    if (options.map == MapKind::kHarmonic || options.holes != HoleMode::kFill || !have_pixels || !density[c].textured ||
        components[c].num_faces() > kAspectProbeMaxFaces)
      return false;
    // Holes, or the two sides of a cut handle (the genus-0 surface remove_handles gives back).
    if (topology_of(ci.denoised ? ci.denoised->surface : components[c]).boundary_loops == 0) return false;
    CutStats st;
    try {
      cut_to_disk(components[c],
                  {.holes = options.holes, .fill_budget = kCapBudget, .cap_longest_loop = true,
                   .handles_removed = ci.denoised ? &*ci.denoised : nullptr, .seams = ci.seams},
                  &st);
    } catch (const InternalError&) {
      return false;  // that cut fails here: only the usual one
    }
    return st.longest_loop_capped && st.longest_loop_edges < kSmallKeptLoop;
  };
  // Component c cut and mapped for a texel rectangle of rect's shape; `pre`: cut_inputs(c) if known.
  auto map_component = [&](size_t c, const Rect& rect, Mapped& out, const CutInputs* pre, CapChoice choice) {
    out.rect = rect;
    SquareMapOptions mo;
    mo.rect_width = rect.w;
    mo.rect_height = rect.h;
    mo.texel_extent = std::max(rect.x + rect.w, rect.y + rect.h);
    mo.corners = options.corners;
    const double faces = double(components[c].num_faces());
    double reported = 0;  // fraction of this map already added to the progress
    mo.progress = [&](double f) {
      if (f <= reported) return;
      map_progress.advance((f - reported) * faces);
      reported = f;
    };
    Disk& disk = out.disk;
    std::vector<Vec2>& uv = out.uv;
    CutStats& cut_stats = out.cut;
    SquareMapStats& map_stats = out.map;
    // One cut and map of the full method; `cap_kept`: the longest hole is capped too if it fits
    // (cut_to_disk). Throws InternalError where the map folds.
    auto cut_and_map = [&](const CutInputs& ci, bool cap_kept, SquareMapOptions& mo, Disk& disk, std::vector<Vec2>& uv,
                           CutStats& cut_stats, SquareMapStats& map_stats) {
      for (double budget = kCapBudget;;) {
        std::vector<uint32_t> slit_to;
        for (int round = 0;; ++round) {
          disk = cut_to_disk(components[c],
                             {.holes = options.holes, .fill_budget = budget, .cap_longest_loop = cap_kept, .slit_to = slit_to,
                              .handles_removed = ci.denoised ? &*ci.denoised : nullptr, .seams = ci.seams},
                             &cut_stats);
          if (cap_kept && !cut_stats.longest_loop_capped) return;  // nothing else than the usual cut
          set_face_targets(disk, density[c], options, mo);
          map_stats = SquareMapStats{};
          uv = map_to_square(disk, mo, &map_stats);
          const uint32_t crowded = map_stats.crowded_vertex;
          if (crowded == kNone || round == kCrowdingRounds) break;
          uint32_t target = disk.mesh.vertex_parent[crowded];
          // Crowded at a cap's centre (scaffolding): slit to a real vertex of that cap instead.
          for (size_t f = 0; f < disk.mesh.num_faces() && target == kNone; ++f)
            if (const Tri& t = disk.mesh.triangles[f]; std::find(t.begin(), t.end(), crowded) != t.end())
              for (uint32_t v : t)
                if (disk.mesh.vertex_parent[v] != kNone) target = disk.mesh.vertex_parent[v];
          if (target == kNone) break;  // nothing real near: nothing to slit to
          slit_to.push_back(target);
        }
        // The caps' share of the square: a cap spans its hole's rim, so it takes about its area at the
        // rim's density, whatever its target. Over kMaxCapTexels, cut again with a budget cut down in
        // proportion, down to kFillBudget (which is kept whatever the share).
        if (cut_stats.holes_filled == 0 || budget <= kFillBudget) break;
        double caps = 0;
        for (uint32_t f = 0; f < disk.mesh.num_faces(); ++f)
          if (disk.mesh.face_parent[f] == kNone) {
            const Tri& t = disk.mesh.triangles[f];
            caps += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
          }
        if (!(caps > kMaxCapTexels)) break;
        budget = std::max(kFillBudget, std::min(budget, cut_stats.filled_area) * 0.95 * kMaxCapTexels / caps);
      }
      // The paper's map can crowd a region (a protrusion beside the boundary) below what the output's
      // texture coordinates hold, where no slit helps: written, such triangles would fold. That
      // component gets the area map on the same disk instead (fold-free by construction), and the
      // report says so (meshroom_esp32cam with six 1% patches missing: 22 to 46 triangles below 1e-9
      // texels after each of 3 slits).
      if (map_stats.flipped > 0 && options.map == MapKind::kHarmonic) {
        const size_t collapsed = map_stats.flipped;
        Options area = options;
        area.map = MapKind::kArea;
        set_face_targets(disk, component_density(input, surface, components[c], MapKind::kArea), area, mo);
        map_stats = SquareMapStats{};
        uv = map_to_square(disk, mo, &map_stats);
        cut_stats.fallback_reason = fmt::format("the harmonic map collapses {} triangles below the output's precision: the area map instead", collapsed);
      }
      // The map promises no fold; one that folds anyway is a failure of the full method.
      if (map_stats.flipped > 0) fail_internal("the map folds {} triangles", map_stats.flipped);
    };
    try {
      forced_failure(c, "full method");
      const CutInputs own = pre ? CutInputs{} : cut_inputs(c);
      const CutInputs& ci = pre ? *pre : own;
      // A small longest hole (pepper noise: a missing triangle or two where the scan is otherwise
      // closed) is a poor boundary: a 3-edge loop cannot hold the square's four corners, the map
      // crowds there and the disk gets slit. Capping it too (the path cut) is better there, but not
      // everywhere (BENCHMARKS.md, "A small longest hole"): both are mapped, side by side, and the
      // estimate of the colour error (resampling_mse, as the aspect probes) decides.
      if (choice == CapChoice::kAuto) choice = small_longest_hole(c, ci) ? CapChoice::kCompare : CapChoice::kKeep;
      if (choice == CapChoice::kKeep) {
        cut_and_map(ci, false, mo, disk, uv, cut_stats, map_stats);
      } else if (choice == CapChoice::kCap) {
        bool capped = false;
        try {
          cut_and_map(ci, true, mo, disk, uv, cut_stats, map_stats);
          capped = cut_stats.longest_loop_capped;
        } catch (const InternalError&) {
        }
        if (!capped) cut_and_map(ci, false, mo, disk, uv, cut_stats, map_stats);  // the usual cut, as any other
      } else {
        Mapped alt;
        SquareMapOptions alt_mo = mo;
        alt_mo.progress = nullptr;  // the kept cut's map reports for both
        bool mapped = false;
        tbb::parallel_invoke([&] { cut_and_map(ci, false, mo, disk, uv, cut_stats, map_stats); },
                             [&] {
                               try {
                                 cut_and_map(ci, true, alt_mo, alt.disk, alt.uv, alt.cut, alt.map);
                                 mapped = alt.cut.longest_loop_capped;
                               } catch (const InternalError&) {
                               }
                             });
        if (mapped) {
          const double kept = estimate_mse(c, disk, uv, rect), capped = estimate_mse(c, alt.disk, alt.uv, rect);
          cut_stats.compared_mse = {kept, capped};
          if (better_map(options.map, alt.map, capped, map_stats, kept, 1.0)) {
            alt.cut.compared_mse = cut_stats.compared_mse;
            disk = std::move(alt.disk), uv = std::move(alt.uv), cut_stats = std::move(alt.cut), map_stats = alt.map;
          }
        }
      }
    } catch (const InternalError& e) {
      // A component the full method cannot handle still gets one chart: the plain cut graph and the
      // fold-free map. The report says so; the run goes on.
      cut_stats = CutStats{};
      try {
        forced_failure(c, "plain fallback");
        disk = cut_to_disk(components[c], {.holes = options.holes, .method = CutMethod::kPlain}, &cut_stats);
        cut_stats.fallback_reason = e.what();
        set_face_targets(disk, density[c], options, mo);
        map_stats = SquareMapStats{};
        uv = map_to_square(disk, mo, &map_stats);
        if (map_stats.flipped > 0) fail_internal("the plain fallback's map folds {} triangles", map_stats.flipped);
      } catch (const InternalError& last) {
        // The last resort: the component keeps its input texture coordinates and material(s), so none
        // of its triangles is lost (bake_plan). The report and the CLI say so.
        cut_stats = CutStats{};
        cut_stats.before = topology_of(components[c]);
        cut_stats.fallback_reason = e.what();
        out.kept = fmt::format("{}; then {}", e.what(), last.what());
        disk = Disk{};
        uv.clear();
      }
    }
    map_progress.advance((1 - reported) * faces);
  };

  // The auto aspect: the dominant component mapped into its rectangle of each probe's texture, each map
  // baked and compared with the input (resampling_mse), the best kept (the square unless another is
  // clearly better).
  std::vector<Mapped> probe(std::size(kAspectProbes));
  nlohmann::json probes_report = nlohmann::json::array();
  size_t chosen = kNone;
  if (dominant != kNone) {
    // The probes share the dominant component's seams and handle search (if that throws, each probe
    // meets it again and falls back as any component would).
    std::optional<CutInputs> shared;
    try {
      shared = cut_inputs(dominant);
    } catch (const InternalError&) {
    }
    std::vector<double> mse(probe.size(), -1);
    std::vector<Rect> probe_rect(probe.size());
    auto run_probe = [&](size_t i, CapChoice choice) {
      const auto [W, H] = atlas_size(kAspectProbes[i]);
      if (std::max(W, H) > std::max(size, kDefaultSizeMax)) return;  // not beyond the size limit for a shape
      if (kAspectProbes[i] != 1.0 && W == H) return;  // too small a texture to take another shape
      try {
        probe_rect[i] = layout_atlas(shares, W, H, 4, exact_shares)[dominant];
      } catch (const InputError&) {
        return;  // this shape cannot hold every component: not probed
      }
      map_component(dominant, probe_rect[i], probe[i], shared ? &*shared : nullptr, choice);
      if (!probe[i].kept.empty()) return;
      mse[i] = estimate_mse(dominant, probe[i].disk, probe[i].uv, probe_rect[i]);
    };
    if (shared && small_longest_hole(dominant, *shared)) {
      // Both cuts are mapped for the square (side by side), and the other shapes take its choice:
      // four maps instead of six, in about the time of the three probes on two cores.
      run_probe(0, CapChoice::kCompare);
      CapChoice decided = CapChoice::kKeep;
      if (!probe[0].cut.compared_mse.empty() && probe[0].cut.longest_loop_capped) decided = CapChoice::kCap;
      tbb::parallel_for(size_t(1), probe.size(), [&](size_t i) {
        run_probe(i, decided);
        probe[i].cut.compared_mse = probe[0].cut.compared_mse;  // the report's estimates: the square's
      });
    } else {
      tbb::parallel_for(size_t(0), probe.size(), [&](size_t i) { run_probe(i, CapChoice::kKeep); });
    }
    chosen = 0;  // kAspectProbes[0] is the square
    // The area map's density promise first (better_map; the dancing girl with six patches missing,
    // seed 11: the 1:2 probe was estimated 0.8 dB above the square but its density missed, -1.39
    // against -1.01), then the estimate, where another shape must beat the square by kAspectMinGain.
    for (size_t i = 1; i < probe.size(); ++i)
      if (better_map(options.map, probe[i].map, mse[i], probe[chosen].map, mse[chosen], chosen == 0 ? kAspectMinGain : 1.0)) chosen = i;
    aspect = kAspectProbes[chosen];
    for (size_t i = 0; i < probe.size(); ++i) {
      const auto [W, H] = atlas_size(kAspectProbes[i]);
      probes_report.push_back({{"aspect", kAspectProbes[i]}, {"width", W}, {"height", H},
                               {"estimated_psnr_db", estimated_psnr_db(mse[i])}});
    }
  }
  if (options.layout == Layout::kAtlas) {
    const auto [W, H] = atlas_size(aspect);
    rects = layout_atlas(shares, W, H, 4, exact_shares);
    image_size.push_back({W, H});
  } else {
    // --size is the largest component's side (the paper's layout). The default budget is the input's
    // used texels for all the textures together: the largest's side shrinks by the square root of its
    // share (30000 small components each got the whole budget: 30000 textures of 480^2, 9.4 GB at the
    // bake and 5 minutes, where their atlas took 0.3 GB and 6 s).
    int side = size;
    if (default_budget) {
      const double sum = std::accumulate(shares.begin(), shares.end(), 0.0), largest = *std::max_element(shares.begin(), shares.end());
      if (sum > 0 && largest > 0) side = std::max(4, int(std::lround(double(size) * std::sqrt(largest / sum))));
    }
    rects = layout_per_component(shares, side, 4, aspect);
    num_images = int(nc);
    for (const Rect& r : rects) image_size.push_back({r.w, r.h});
  }

  std::vector<Disk>& disks = plan.disks;
  disks.resize(nc);
  std::vector<CutStats> cut_stats(nc);
  std::vector<std::vector<Vec2>>& uv = plan.uv;
  uv.resize(nc);
  std::vector<SquareMapStats> map_stats(nc);
  std::vector<std::string>& kept = plan.kept;
  kept.assign(nc, std::string());
  tbb::parallel_for(size_t(0), nc, [&](size_t c) {
    Mapped m;
    if (c == dominant && rects[c].w == probe[chosen].rect.w && rects[c].h == probe[chosen].rect.h) m = std::move(probe[chosen]);
    else map_component(c, rects[c], m, nullptr, CapChoice::kAuto);
    disks[c] = std::move(m.disk);
    uv[c] = std::move(m.uv);
    cut_stats[c] = std::move(m.cut);
    map_stats[c] = std::move(m.map);
    kept[c] = std::move(m.kept);
  });
  clock.done("cut+map");

  // What was done so far, for the report.
  nlohmann::json& rep = plan.report;
  rep["input"] = {{"file", input.source}, {"vertices", input.num_vertices()}, {"triangles", input.num_triangles()},
                  {"materials", input.materials.size()}, {"textures", input.textures.size()}};
  rep["options"] = {{"size", size}, {"size_grown_from", size_grown_from > 0 ? nlohmann::json(size_grown_from) : nlohmann::json(nullptr)}, {"layout", options.layout == Layout::kAtlas ? "atlas" : "per-component"},
                    {"holes", options.holes == HoleMode::kFill ? "fill" : "cut"}, {"map", map_name(options.map)},
                    {"balance", options.balance}, {"fit", options.fit}, {"fine_fit", options.fit && options.fine_fit},
                    {"corners", options.corners == CornerRule::kTurningAngle ? "turning" : "arcs"},
                    {"aspect", options.aspect > 0 ? nlohmann::json(options.aspect) : nlohmann::json("auto")}};
  // The texture's shape: what was asked, what it is, and (auto) what each probe was estimated to give.
  rep["aspect"] = {{"requested", options.aspect > 0 ? nlohmann::json(options.aspect) : nlohmann::json("auto")},
                   {"chosen", aspect},
                   {"probed_component", dominant == kNone ? nlohmann::json(nullptr) : nlohmann::json(dominant)},
                   {"probes", probes_report}};
  rep["preparation"] = {{"input_vertices", rs.input_vertices},       {"welded_vertices", rs.welded_vertices},
                        {"zero_area_dropped", rs.zero_area_triangles}, {"duplicates_dropped", rs.duplicate_triangles},
                        {"non_manifold_edges_sliced", rs.non_manifold_edges}, {"inconsistent_edges_sliced", rs.inconsistent_edges}, {"reoriented_triangles", rs.reoriented_triangles},
                        {"vertices_sliced", rs.sliced_vertices}, {"slits_closed", rs.slits_closed},      {"components", nc}};
  // One entry per component, in plan order, up to kReportComponents of them: the largest by triangles,
  // and besides them every one that fell back or kept its UVs (up to as many again). A tile of 30000
  // buildings gave a 40 MB report (1.4 KB a component) and 200 MB of copies of it at the peak; the
  // totals over all components are in "preparation".
  constexpr size_t kReportComponents = 256;
  std::vector<char> listed(nc, 0);
  {
    std::vector<size_t> order(nc);
    std::iota(order.begin(), order.end(), size_t(0));
    auto larger = [&](size_t a, size_t b) { return components[a].num_faces() != components[b].num_faces() ? components[a].num_faces() > components[b].num_faces() : a < b; };
    const size_t top = std::min(nc, kReportComponents);
    std::partial_sort(order.begin(), order.begin() + std::ptrdiff_t(top), order.end(), larger);
    for (size_t k = 0; k < top; ++k) listed[order[k]] = 1;
    size_t troubled = 0;
    for (size_t c = 0; c < nc && troubled < kReportComponents; ++c)
      if (!listed[c] && (!cut_stats[c].fallback_reason.empty() || !kept[c].empty())) listed[c] = 1, ++troubled;
  }
  nlohmann::json comps = nlohmann::json::array();
  size_t holes_filled = 0, holes_cut = 0, fallbacks = 0, longest_capped = 0;
  // Estimated PSNR of the two cuts tried ([the longest hole kept as the boundary, capped too]).
  auto compared_db = [](const std::vector<double>& mse) {
    nlohmann::json db = nlohmann::json::array();
    for (double m : mse) db.push_back(estimated_psnr_db(m));
    return mse.empty() ? nlohmann::json(nullptr) : db;
  };
  for (size_t c = 0; c < nc; ++c) {
    const CutStats& cs = cut_stats[c];
    holes_filled += cs.holes_filled;
    longest_capped += cs.longest_loop_capped;
    holes_cut += cs.holes_cut;
    fallbacks += !cs.fallback_reason.empty();
    if (!listed[c]) continue;
    comps.push_back({{"index", c},
                     {"triangles", components[c].num_faces()},
                     {"area", areas[c]},
                     {"euler", cs.before.euler()},
                     {"boundary_loops", cs.before.boundary_loops},
                     {"genus", cs.before.genus()},
                     {"holes_filled", cs.holes_filled},
                     {"holes_cut", cs.holes_cut},
                     {"cut", cs.method},
                     {"longest_hole_edges", cs.longest_loop_edges},
                     {"longest_hole_capped", cs.longest_loop_capped},
                     {"longest_hole_kept_capped_estimated_psnr_db", compared_db(cs.compared_mse)},
                     {"slits", cs.slits},
                     {"fallback", cs.fallback_reason},
                     {"cap_budget", cs.fill_budget},
                     {"kept_original_uvs", !kept[c].empty()},
                     {"kept_reason", kept[c]},
                     {"handle_loops", cs.handle_loops},
                     {"cut_edges", cs.cut_edges},
                     {"cut_length", cs.cut_length},
                     {"seam_length", cs.seam_length},
                     {"seam_on_input_seams", cs.seam_on_input_seams},
                     {"weights", map_stats[c].weights},
                     {"negative_cotangent_weights", map_stats[c].negative_weights},
                     {"bumped_boundary_vertices", map_stats[c].bumped_vertices},
                     {"flipped_in_map", map_stats[c].flipped},
                     {"folds_per_weighting", map_stats[c].folds_per_attempt},
                     {"density_iterations", map_stats[c].iterations},
                     {"density_stopped", map_stats[c].stopped},
                     {"density_correction_rounds", map_stats[c].correction_rounds},
                     {"density_error_log2_before", {map_stats[c].spread_before_p5, map_stats[c].spread_before_p95}},
                     {"density_error_log2", {map_stats[c].spread_p5, map_stats[c].spread_p95}},
                     {"refine_iterations", map_stats[c].refine_iterations},
                     {"flow_steps", map_stats[c].flow_steps},
                     {"flow_lead_steps", map_stats[c].flow_lead_steps},
                     {"flow_shape_steps", map_stats[c].flow_shape_steps},
                     {"flow_stopped", map_stats[c].flow_stopped},
                     {"refine_energy", {map_stats[c].refine_energy_before, map_stats[c].refine_energy}},
                     {"refine_stopped", map_stats[c].refine_stopped},
                     {"rect", {{"image", rects[c].image}, {"x", rects[c].x}, {"y", rects[c].y}, {"w", rects[c].w}, {"h", rects[c].h}}}});
  }
  rep["preparation"]["holes_filled"] = holes_filled;
  rep["preparation"]["holes_cut"] = holes_cut;
  rep["preparation"]["components_with_fallback"] = fallbacks;
  rep["preparation"]["components_longest_hole_capped"] = longest_capped;
  rep["preparation"]["components_listed"] = comps.size();
  rep["preparation"]["components_kept_original_uvs"] = size_t(std::count_if(kept.begin(), kept.end(), [](const std::string& k) { return !k.empty(); }));
  rep["components"] = comps;
  rep["timings"] = timings;
  return plan;
}

Result bake_plan(const Plan& plan, const TexturedMesh& input, const Options& options) {
  auto progress = [&](std::string_view stage, double f) {
    if (options.progress) options.progress(stage, f);
  };
  Result result;
  result.report = plan.report;
  nlohmann::json& rep = result.report;
  nlohmann::json& timings = rep["timings"];
  StageClock clock(timings);
  const Surface& surface = plan.surface;
  const std::vector<Surface>& components = plan.components;
  const std::vector<Disk>& disks = plan.disks;
  const std::vector<Rect>& rects = plan.rects;
  const std::vector<std::vector<Vec2>>& uv = plan.uv;
  const std::vector<std::pair<int, int>>& image_size = plan.image_size;
  const int num_images = plan.num_images;
  const size_t nc = components.size();
  // 5. Output model: the input's positions and triangles (same corners, same winding), new UVs.
  //    Components the plan could not map (Plan::kept) keep their input UVs and materials (below).
  const std::vector<std::string> no_kept;
  const std::vector<std::string>& kept = plan.kept.empty() ? no_kept : plan.kept;
  auto is_kept = [&](size_t c) { return c < kept.size() && !kept[c].empty(); };
  // The new images that some mapped component uses, renumbered densely (all of them unless a
  // component was kept: then a per-component image of its own would stay empty and is not written).
  std::vector<int> image_index(size_t(num_images), -1);
  for (size_t c = 0; c < nc; ++c)
    if (!is_kept(c)) image_index[size_t(rects[c].image)] = 0;
  int new_images = 0;
  for (int& i : image_index)
    if (i == 0) i = new_images++;
  std::vector<Rect> mapped_rects;
  for (size_t c = 0; c < nc; ++c)
    if (!is_kept(c)) {
      mapped_rects.push_back(rects[c]);
      mapped_rects.back().image = image_index[size_t(rects[c].image)];
    }
  TexturedMesh& out = result.output;
  out.source = input.source;
  out.positions = input.positions;
  const bool normals = !input.corner_normal.empty();
  std::vector<BakeTriangle> bake_tris;
  bake_tris.reserve(input.num_triangles());
  for (size_t c = 0; c < nc; ++c) {
    if (is_kept(c)) continue;
    const Rect& r = rects[c];
    const auto [W, H] = image_size[size_t(r.image)];
    const int image = image_index[size_t(r.image)];
    const Disk& d = disks[c];
    for (uint32_t f = 0; f < d.mesh.num_faces(); ++f) {
      const uint32_t t = d.mesh.input_face[f];
      if (t == kNone) continue;  // scaffolding
      BakeTriangle bt = bake_triangle(input, d.mesh, f, uv[c], r);
      bt.image = uint32_t(image);
      const uint8_t* ik = &d.mesh.input_corner[3 * size_t(f)];
      const Tri& it = input.triangles[t];
      out.triangles.push_back(Tri{it[ik[0]], it[ik[1]], it[ik[2]]});  // wound as the repaired surface
      for (int k = 0; k < 3; ++k) {
        const Vec2& px = bt.target_px[size_t(k)];
        out.corner_uv.push_back(Vec2(px.x() / W, 1.0 - px.y() / H));
        if (normals) out.corner_normal.push_back(input.corner_normal[3 * t + ik[k]]);
      }
      out.face_material.push_back(int32_t(image));
      bake_tris.push_back(bt);
    }
  }
  const std::string stem = file_stem(input.source);
  std::set<std::string> names;  // file stems and material names taken, compared without case
  for (int i = 0; i < new_images; ++i) {
    Texture tex;
    tex.path = new_images == 1 ? stem + "_tightex" : fmt::format("{}_tightex_{}", stem, i);
    int src = 0;
    while (image_index[size_t(src)] != i) ++src;
    tex.image = Image(image_size[size_t(src)].first, image_size[size_t(src)].second, Rgba8{0, 0, 0, 255});
    names.insert(lower(tex.path));
    out.textures.push_back(std::move(tex));
    Material m;
    m.name = new_images == 1 ? "tightex" : fmt::format("tightex_{}", i);
    m.texture = i;
    names.insert(lower(m.name));
    out.materials.push_back(m);
  }
  // The kept components' triangles, after the mapped ones: input corners and texture coordinates as
  // they were, each input material they use copied once (first use first, so the order is fixed), its
  // texture copied under the input file's own stem, both renamed only where a name is taken.
  std::vector<int32_t> kept_material(input.materials.size() + 1, -1);  // input material + 1 -> output
  std::vector<int> kept_texture(input.textures.size(), -1);
  for (size_t c = 0; c < nc; ++c) {
    if (!is_kept(c)) continue;
    const Surface& comp = components[c];
    for (uint32_t cf = 0; cf < comp.num_faces(); ++cf) {
      const uint32_t t = comp.input_face[cf];
      const int32_t in_mat = input.face_material[t];
      int32_t& om = kept_material[size_t(in_mat + 1)];
      if (om < 0) {
        Material m;  // no input material: white, as measure() and a renderer take it
        if (in_mat >= 0) m = input.materials[size_t(in_mat)];
        m.texture = -1;
        m.name = unique_name(names, "kept_" + file_name_safe(in_mat >= 0 ? input.materials[size_t(in_mat)].name : "none"));
        if (in_mat >= 0 && input.materials[size_t(in_mat)].texture >= 0) {
          const int in_tex = input.materials[size_t(in_mat)].texture;
          int& ot = kept_texture[size_t(in_tex)];
          if (ot < 0 && !input.textures[size_t(in_tex)].image.empty()) {
            Texture tex;
            // "kept_" keeps the copy from ever taking an input texture's own file name.
            tex.path = unique_name(names, "kept_" + file_name_safe(file_stem(input.textures[size_t(in_tex)].path)));
            tex.image = input.textures[size_t(in_tex)].image;
            ot = int(out.textures.size());
            out.textures.push_back(std::move(tex));
          }
          m.texture = ot;
        }
        om = int32_t(out.materials.size());
        out.materials.push_back(std::move(m));
      }
      const uint8_t* ic = &comp.input_corner[3 * size_t(cf)];
      const Tri& it = input.triangles[t];
      out.triangles.push_back(Tri{it[ic[0]], it[ic[1]], it[ic[2]]});
      for (int k = 0; k < 3; ++k) {
        const size_t ik = ic[k];
        out.corner_uv.push_back(input.corner_uv[3 * t + ik]);
        if (normals) out.corner_normal.push_back(input.corner_normal[3 * t + ik]);
      }
      out.face_material.push_back(om);
    }
  }

  // 6. Bake the new texture (§4.3).
  progress("bake", 0);
  std::vector<Image> images;
  for (int i = 0; i < new_images; ++i) images.push_back(std::move(out.textures[size_t(i)].image));
  BakeStats bs;
  BakeOptions bo;
  bo.fit = options.fit;
  if (options.fine_fit) bo.fit_samples = kFineFitSamples, bo.fit_lambda = kFineFitLambda;
  if (options.progress) bo.progress = [&](double f) { options.progress("bake", f); };
  bake_texture(input, bake_tris, mapped_rects, images, &bs, bo);
  for (size_t i = 0; i < images.size(); ++i) out.textures[i].image = std::move(images[i]);
  clock.done("bake");

  // 7. Report.
  if (options.measure) {
    progress("measure", 0);
    rep["metrics"] = to_json(measure(input, out));
    clock.done("measure");
  }

  rep["bake"] = {{"texels_filled", bs.texels_filled}, {"texels_dilated", bs.texels_dilated},
                 {"texels_footprint_filtered", bs.texels_footprint_filtered}, {"tiles_fitted", bs.tiles_fitted}, {"tiles", bs.tiles}};
  rep["timings"] = timings;
  rep["peak_rss_mib"] = peak_rss_mib();
  progress("done", 1);
  return result;
}

int size_for_texels(double texels) {
  const double side = std::ceil(std::sqrt(std::max(texels, 0.0)) / 4.0) * 4.0;
  return int(std::clamp(side, 64.0, 65536.0));
}

double input_used_texels(const TexturedMesh& input) { return measure_texture_space(input).used_texels; }

int default_size(const TexturedMesh& input, int max_side) {
  double texels = std::ceil(input_used_texels(input) / 4.0) * 4.0;
  if (!(texels > 0)) texels = 1024.0 * 1024.0;  // no texture of known size: a 1K map
  return std::min(size_for_texels(texels), max_side);
}

Result optimize(const TexturedMesh& input, const Options& options) { return bake_plan(plan_charts(input, options), input, options); }

}  // namespace tightex
