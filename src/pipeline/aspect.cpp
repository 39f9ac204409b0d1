#include "pipeline/aspect.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "core/error.hpp"
#include "pipeline/budget.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

namespace {

/// Another shape replaces the square only if its estimated error is this fraction of the square's or
/// less: the estimate is a simulation, and a square texture is the simpler one to use.
constexpr double kAspectMinGain = 0.95;

/// The probes share the dominant component's seams and handle search. Where that search meets a bug
/// (InternalError), none is shared: each probe then meets it again inside map_component, which reports
/// it as that map's fallback.
std::optional<CutInputs> shared_cut_inputs(const MapContext& ctx, size_t c) {
  try {
    return cut_inputs(ctx.input, ctx.components[c]);
  } catch (const InternalError&) {
    return std::nullopt;
  }
}

}  // namespace

size_t aspect_probe_component(const MapContext& ctx, const std::vector<double>& shares) {
  const Options& o = ctx.options;
  if (o.aspect != 0 || o.map == MapKind::kHarmonic || o.layout != Layout::kAtlas || shares.empty()) return kNone;
  const size_t c = size_t(std::max_element(shares.begin(), shares.end()) - shares.begin());
  const double sum = std::accumulate(shares.begin(), shares.end(), 0.0);
  if (ctx.have_pixels && ctx.density[c].textured && shares[c] >= 0.5 * sum && ctx.components[c].num_faces() <= kProbeMaxFaces) return c;
  return kNone;
}

ShapeChoice choose_aspect(const MapContext& ctx, size_t dominant, const std::vector<double>& shares, int size, AtlasShares mode) {
  const size_t n = std::size(kAspectProbes);
  std::vector<std::optional<Mapped>> probe(n);
  std::vector<double> mse(n, -1);
  std::vector<Rect> rect(n);
  const std::optional<CutInputs> shared = shared_cut_inputs(ctx, dominant);
  auto run_probe = [&](size_t i, CapChoice choice) {
    const auto [W, H] = atlas_size(size, kAspectProbes[i]);
    if (std::max(W, H) > std::max(size, kDefaultSizeMax)) return;  // not beyond the size limit for a shape
    if (kAspectProbes[i] != 1.0 && W == H) return;                 // too small a texture to take another shape
    const auto rects = try_layout_atlas(shares, W, H, 4, mode);
    if (!rects) return;  // this shape cannot hold every component: not probed
    rect[i] = (*rects)[dominant];
    probe[i] = map_component(ctx, dominant, rect[i], shared ? &*shared : nullptr, choice, true);
    if (probe[i]->kept.empty()) mse[i] = estimate_mse(ctx.input, *probe[i]);
  };
  if (shared && small_longest_hole(ctx, dominant, *shared)) {
    // Both cuts are mapped for the square (side by side), and the other shapes take its choice.
    run_probe(0, CapChoice::kCompare);
    const CutStats square = probe[0] ? probe[0]->cut : CutStats{};
    const CapChoice decided = !square.compared_mse.empty() && square.longest_loop_capped ? CapChoice::kCap : CapChoice::kKeep;
    tbb::parallel_for(size_t(1), n, [&](size_t i) {
      run_probe(i, decided);
      if (probe[i]) probe[i]->cut.compared_mse = square.compared_mse;  // the report's estimates: the square's
    });
  } else {
    tbb::parallel_for(size_t(0), n, [&](size_t i) { run_probe(i, CapChoice::kKeep); });
  }
  // The area map's density promise first, then the estimate, where another shape must beat the square
  // by kAspectMinGain.
  const SquareMapStats none{};
  auto stats = [&](size_t i) -> const SquareMapStats& { return probe[i] ? probe[i]->map : none; };
  size_t chosen = 0;
  for (size_t i = 1; i < n; ++i)
    if (better_map(ctx.options.map, stats(i), mse[i], stats(chosen), mse[chosen], chosen == 0 ? kAspectMinGain : 1.0)) chosen = i;
  ShapeChoice choice;
  choice.aspect = kAspectProbes[chosen];
  for (size_t i = 0; i < n; ++i) {
    const auto [W, H] = atlas_size(size, kAspectProbes[i]);
    choice.probes.push_back({kAspectProbes[i], W, H, mse[i]});
  }
  choice.dominant_map = std::move(probe[chosen]);
  if (choice.dominant_map && choice.dominant_map->map.coarse_vertices > 0) {
    // A probe's multilevel map chose the shape; the component gets its own map for it, with the cut the
    // probe kept (the estimates of a small hole's two cuts stay in the report).
    const CutStats& cut = choice.dominant_map->cut;
    const CapChoice kept = cut.longest_loop_capped && !cut.compared_mse.empty() ? CapChoice::kCap : CapChoice::kKeep;
    const std::vector<double> compared = cut.compared_mse;
    choice.dominant_map = map_component(ctx, dominant, rect[chosen], shared ? &*shared : nullptr, kept);
    if (choice.dominant_map->cut.compared_mse.empty()) choice.dominant_map->cut.compared_mse = compared;
  }
  return choice;
}

}  // namespace tightex
