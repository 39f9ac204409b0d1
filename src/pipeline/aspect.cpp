#include "pipeline/aspect.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"
#include "pipeline/budget.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

namespace {

/// Another shape replaces the square only if its estimated error is this fraction of the square's or
/// less: the estimate is a simulation, and a square texture is the simpler one to use.
constexpr double kAspectMinGain = 0.95;

/// The coarse copy whose map tells a large component's texel stretch (choose_on_own_maps): on
/// meshroom_esp32cam and its paged copy, with every map, copies of 2k, 4k and 8k vertices gave a
/// stretch of 1.45-1.86, always on the 2:1 side, and 2k takes 0.14-0.3 s of the 8k copy's 0.42-1.6 s.
constexpr size_t kShapeLookVertices = 2000;

/// Whether a map's texel stretch leaves room for another shape to do better: its texels are longer on
/// the surface along one axis than along the other by more than `limit` (`stretch` < 0: no map).
bool worth_probing_other_shapes(double stretch, double limit = kAspectProbeStretch) { return stretch > limit || stretch < 1 / limit; }

/// The shape chosen on own maps, for a component whose probes would be multilevel: the square's own map
/// on one core; on the other, a coarse copy's map in the square (map_coarse_copy, a fifth of a probe's
/// time) for the texel stretch, then, where the stretch calls for it, the own map of the shape it points
/// to. Both own maps are estimated and the choice made on them by the probes' rule. A multilevel probe
/// cost nearly an own map, and the shape it chose had to be mapped again; and probes could misrank
/// the shapes (meshroom_esp32cam, `--map texel`: its probes estimated 2:1 closer, 36.35 against
/// 35.59 dB, its own maps the square, 41.62 against 41.45). `rect`: the component's rectangle in each
/// shape's texture (none where the shape is not probed); `choice`: the probes' shapes and sizes.
ShapeChoice choose_on_own_maps(const MapContext& ctx, size_t dominant, const CutInputs* shared,
                               const std::vector<std::optional<Rect>>& rect, ShapeChoice choice) {
  const size_t n = std::size(kAspectProbes);
  std::vector<std::optional<Mapped>> own(n);
  std::vector<double> mse(n, -1);
  size_t other = kNone;
  tbb::parallel_invoke([&] { own[0] = map_component(ctx, dominant, *rect[0], shared, CapChoice::kKeep); },
                       [&] {
                         const Mapped look = map_coarse_copy(ctx, dominant, *rect[0], shared, kShapeLookVertices);
                         choice.square_texel_stretch = look.kept.empty() ? texel_stretch_ratio(look) : -1;
                         if (!worth_probing_other_shapes(choice.square_texel_stretch, kShapeLookStretch)) return;
                         other = choice.square_texel_stretch > 1 ? 2 : 1;  // kAspectProbes: 2:1 where texels are long along x
                         if (rect[other]) own[other] = map_component(ctx, dominant, *rect[other], shared, CapChoice::kKeep);
                       });
  if (other == kNone || !own[other]) ctx.progress.advance(double(ctx.components[dominant].num_faces()));  // the map not made
  size_t chosen = 0;
  if (other != kNone && own[other] && own[other]->kept.empty() && own[0]->kept.empty()) {
    tbb::parallel_invoke([&] { mse[0] = estimate_mse(ctx.input, *own[0]); }, [&] { mse[other] = estimate_mse(ctx.input, *own[other]); });
    if (better_map(ctx.options.map, own[other]->map, mse[other], own[0]->map, mse[0], kAspectMinGain)) chosen = other;
  }
  choice.aspect = kAspectProbes[chosen];
  for (size_t i = 0; i < n; ++i) choice.probes[i].full_map_estimated_mse = mse[i];
  choice.dominant_map = std::move(own[chosen]);
  return choice;
}

}  // namespace

double texel_stretch_ratio(const Mapped& m) {
  const Surface& d = m.disk.mesh;
  double along_x = 0, along_y = 0;
  for (uint32_t f = 0; f < d.num_faces(); ++f) {
    if (d.face_parent[f] == kNone) continue;  // scaffolding: no texel of it is baked
    const Tri& t = d.triangles[f];
    const Vec2 scale(m.rect.w, m.rect.h);
    const Vec2 a = (m.uv[t[1]] - m.uv[t[0]]).cwiseProduct(scale), b = (m.uv[t[2]] - m.uv[t[0]]).cwiseProduct(scale);
    const double det = a.x() * b.y() - a.y() * b.x();
    if (!(std::abs(det) > 0)) continue;
    const Vec3 e1 = d.positions[t[1]] - d.positions[t[0]], e2 = d.positions[t[2]] - d.positions[t[0]];
    // [dp/dx dp/dy] = [e1 e2] [a b]^-1
    const Vec3 dp_dx = (e1 * b.y() - e2 * a.y()) / det, dp_dy = (e2 * a.x() - e1 * b.x()) / det;
    along_x += std::abs(det) * dp_dx.squaredNorm();
    along_y += std::abs(det) * dp_dy.squaredNorm();
  }
  return along_y > 0 ? along_x / along_y : 1.0;
}

size_t aspect_probe_component(const MapContext& ctx, const std::vector<double>& shares) {
  const Options& o = ctx.options;
  if (o.aspect != 0 || o.map == MapKind::kHarmonic || o.layout != Layout::kAtlas || shares.empty()) return kNone;
  const size_t c = size_t(std::max_element(shares.begin(), shares.end()) - shares.begin());
  const double sum = std::accumulate(shares.begin(), shares.end(), 0.0);
  if (ctx.have_pixels && ctx.density[c].textured && shares[c] >= 0.5 * sum && ctx.components[c].num_faces() <= kProbeMaxFaces) return c;
  return kNone;
}

ShapeChoice choose_aspect(const MapContext& ctx, size_t dominant, const CutInputs* shared, const std::vector<double>& shares, int size,
                          AtlasShares mode) {
  const size_t n = std::size(kAspectProbes);
  std::vector<std::optional<Mapped>> probe(n);
  std::vector<double> mse(n, -1);
  // The component's rectangle in each shape's texture; none where the shape is not probed.
  std::vector<std::optional<Rect>> rect(n);
  for (size_t i = 0; i < n; ++i) {
    const auto [W, H] = atlas_size(size, kAspectProbes[i]);
    if (std::max(W, H) > std::max(size, kDefaultSizeMax)) continue;  // not beyond the size limit for a shape
    if (kAspectProbes[i] != 1.0 && W == H) continue;                 // too small a texture to take another shape
    const auto rects = try_layout_atlas(shares, W, H, 4, mode);
    if (rects) rect[i] = (*rects)[dominant];  // else this shape cannot hold every component
  }
  ShapeChoice choice;
  for (size_t i = 0; i < n; ++i) {
    const auto [W, H] = atlas_size(size, kAspectProbes[i]);
    choice.probes.push_back({kAspectProbes[i], W, H, -1});
  }
  // A component whose probes would be multilevel is chosen on own maps, unless its longest hole is
  // small: then its two cuts are compared on the square's probe, as below.
  const bool compare_cuts = shared && small_longest_hole(ctx, dominant, *shared);
  if (!compare_cuts && rect[0] && probes_would_be_multilevel(ctx.components[dominant].num_faces()))
    return choose_on_own_maps(ctx, dominant, shared, rect, std::move(choice));
  auto run_probe = [&](size_t i, CapChoice cap) {
    if (rect[i]) probe[i] = map_component(ctx, dominant, *rect[i], shared, cap, true);
  };
  // The square first: where the longest hole is small both its cuts are mapped (side by side), and the
  // other shape takes its choice. Then, where the square's texels are stretched, the shape they point
  // to, beside the square's estimate (the square alone needs none).
  const double faces = double(ctx.components[dominant].num_faces());
  double stretch = -1;
  auto probe_shapes = [&] {
    run_probe(0, compare_cuts ? CapChoice::kCompare : CapChoice::kKeep);
    const CutStats square = probe[0] ? probe[0]->cut : CutStats{};
    const CapChoice decided = !square.compared_mse.empty() && square.longest_loop_capped ? CapChoice::kCap : CapChoice::kKeep;
    stretch = probe[0] && probe[0]->kept.empty() ? texel_stretch_ratio(*probe[0]) : -1;
    if (!worth_probing_other_shapes(stretch)) {
      ctx.progress.advance(faces * double(n - 1));  // the maps not made
      return;
    }
    const size_t other = stretch > 1 ? 2 : 1;  // kAspectProbes: 2:1 where texels are long along x, else 1:2
    tbb::parallel_invoke(
        [&] {
          run_probe(other, decided);
          if (probe[other] && compare_cuts) probe[other]->cut.compared_mse = square.compared_mse;  // the report's: the square's
          if (probe[other] && probe[other]->kept.empty()) mse[other] = estimate_mse(ctx.input, *probe[other]);
        },
        [&] { mse[0] = estimate_mse(ctx.input, *probe[0]); });
    ctx.progress.advance(faces * double(n - 2));  // the shape the texels do not point to
  };
  probe_shapes();
  // The area map's density promise first, then the estimate, where another shape must beat the square
  // by kAspectMinGain.
  const SquareMapStats none{};
  auto stats = [&](size_t i) -> const SquareMapStats& { return probe[i] ? probe[i]->map : none; };
  size_t chosen = 0;
  for (size_t i = 1; i < n; ++i)
    if (better_map(ctx.options.map, stats(i), mse[i], stats(chosen), mse[chosen], chosen == 0 ? kAspectMinGain : 1.0)) chosen = i;
  choice.aspect = kAspectProbes[chosen];
  choice.square_texel_stretch = stretch;
  for (size_t i = 0; i < n; ++i) choice.probes[i].estimated_mse = mse[i];
  choice.dominant_map = std::move(probe[chosen]);
  if (choice.dominant_map && choice.dominant_map->map.coarse_vertices > 0) {
    // A probe's multilevel map chose the shape; the component gets its own map for it, with the cut the
    // probe kept (the estimates of a small hole's two cuts stay in the report).
    const CutStats& cut = choice.dominant_map->cut;
    const CapChoice kept = cut.longest_loop_capped && !cut.compared_mse.empty() ? CapChoice::kCap : CapChoice::kKeep;
    const std::vector<double> compared = cut.compared_mse;
    choice.dominant_map = map_component(ctx, dominant, *rect[chosen], shared, kept);
    if (choice.dominant_map->cut.compared_mse.empty()) choice.dominant_map->cut.compared_mse = compared;
  }
  return choice;
}

}  // namespace tightex
