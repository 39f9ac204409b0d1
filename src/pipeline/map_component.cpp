#include "pipeline/map_component.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>

#include "bake/resampling_error.hpp"
#include "core/error.hpp"
#include "param/multilevel.hpp"

namespace tightex {

namespace {

/// Where the map crowds a region below floating-point precision, the disk is slit to that region and
/// cut again, up to this many times.
constexpr int kCrowdingRounds = 3;
/// Holes are capped within kCapBudget of the component's area (smallest first), as long as the caps take
/// at most kMaxCapTexels of its square (the output stays >= 99% used); otherwise with a budget cut down
/// in proportion, down to kFillBudget. Chosen by measurement (docs/decisions.md).
constexpr double kCapBudget = 0.02, kMaxCapTexels = 0.008;
/// A longest hole of fewer edges than this is also tried capped (docs/decisions.md).
constexpr size_t kSmallKeptLoop = 8;
/// The area map's promise: the density of 90% of the surface within a factor 2 of the mean.
constexpr double kAreaSpreadPromise = 1.0;
/// Surface points of the estimate: 4 per texel, between these bounds (docs/decisions.md).
constexpr size_t kEstimateMaxSamples = size_t(1) << 20, kEstimateMinSamples = 65536;

bool forced_to_fail(const MapContext& ctx, size_t c) {
  const auto& f = ctx.hooks.fail_components;
  return std::find(f.begin(), f.end(), c) != f.end();
}

/// Runs one attempt at a component. The stages throw InternalError only on a broken invariant; at
/// this boundary such a bug becomes the component's failure, reported as its fallback or kept reason,
/// so that one component's bug costs that component's chart, not the model.
template <typename Attempt>
std::string run_attempt(Attempt&& attempt) {
  try {
    return attempt();
  } catch (const InternalError& e) {
    return e.what();
  }
}

SquareMapOptions map_options(const MapContext& ctx, size_t c, const Rect& rect) {
  SquareMapOptions mo;
  mo.rect_width = rect.w;
  mo.rect_height = rect.h;
  mo.texel_extent = std::max(rect.x + rect.w, rect.y + rect.h);
  mo.corners = c < ctx.split_piece.size() && ctx.split_piece[c] ? CornerRule::kTurningAngle : ctx.options.corners;
  return mo;
}

/// The full method's cut: the run's hole mode, the cap budget, the handles removed once, the seams.
CutOptions full_cut_options(const MapContext& ctx, const CutInputs& ci, double fill_budget) {
  CutOptions co;
  co.holes = ctx.options.holes;
  co.fill_budget = fill_budget;
  co.handles_removed = ci.denoised ? &*ci.denoised : nullptr;
  co.seams = ci.seams;
  return co;
}

/// A real vertex of the component to slit to where the map crowded `crowded` (a cap's centre, which is
/// scaffolding, gives a real vertex of that cap); kNone: nothing real near.
uint32_t slit_target(const Disk& disk, uint32_t crowded) {
  uint32_t target = disk.mesh.vertex_parent[crowded];
  for (size_t f = 0; f < disk.mesh.num_faces() && target == kNone; ++f)
    if (const Tri& t = disk.mesh.triangles[f]; std::find(t.begin(), t.end(), crowded) != t.end())
      for (uint32_t v : t)
        if (disk.mesh.vertex_parent[v] != kNone) target = disk.mesh.vertex_parent[v];
  return target;
}

/// The caps' share of the unit square in a map.
double cap_share(const Disk& disk, const std::vector<Vec2>& uv) {
  double caps = 0;
  for (uint32_t f = 0; f < disk.mesh.num_faces(); ++f)
    if (disk.mesh.face_parent[f] == kNone) {
      const Tri& t = disk.mesh.triangles[f];
      caps += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
    }
  return caps;
}

/// Cuts component c with the cap budget `budget` and maps it; where the map crowds a region, slits to
/// it and cuts again (kCrowdingRounds). Returns false where `cap_kept` was asked but the longest loop
/// could not be capped (only the usual cut is to be made: not mapped).
bool cut_and_map_with_slits(const MapContext& ctx, size_t c, const CutInputs& ci, bool cap_kept, double budget, SquareMapOptions& mo,
                            Mapped& out) {
  std::vector<uint32_t> slit_to;
  for (int round = 0;; ++round) {
    CutOptions co = full_cut_options(ctx, ci, budget);
    co.slit_to = slit_to;
    if (cap_kept) {
      std::optional<Disk> capped = cut_to_disk_capped(ctx.components[c], co, &out.cut);
      if (!capped) {
        out.cut.longest_loop_capped = false;
        return false;
      }
      out.disk = std::move(*capped);
    } else {
      out.disk = cut_to_disk(ctx.components[c], co, &out.cut);
    }
    set_face_targets(out.disk, ctx.density[c], ctx.options.map, ctx.options.balance, mo);
    out.map = SquareMapStats{};
    out.uv = map_to_square(out.disk, mo, &out.map);
    const uint32_t crowded = out.map.crowded_vertex;
    if (crowded == kNone || round == kCrowdingRounds) return true;
    const uint32_t target = slit_target(out.disk, crowded);
    if (target == kNone) return true;
    slit_to.push_back(target);
  }
}

/// One cut and map of the full method. Returns "" when mapped, else why not (the map folds). Where
/// `cap_kept` and the longest loop could not be capped, returns "" with out.cut.longest_loop_capped
/// false and nothing mapped.
std::string cut_and_map(const MapContext& ctx, size_t c, const CutInputs& ci, bool cap_kept, SquareMapOptions& mo, Mapped& out) {
  // Caps take about their area at the rim's density, whatever their target: over kMaxCapTexels of the
  // square, cut again with a budget cut down in proportion, down to kFillBudget (kept whatever the share).
  for (double budget = kCapBudget;;) {
    if (!cut_and_map_with_slits(ctx, c, ci, cap_kept, budget, mo, out)) return "";
    if (out.cut.holes_filled == 0 || budget <= kFillBudget) break;
    const double caps = cap_share(out.disk, out.uv);
    if (!(caps > kMaxCapTexels)) break;
    budget = std::max(kFillBudget, std::min(budget, out.cut.filled_area) * 0.95 * kMaxCapTexels / caps);
  }
  // The paper's map can crowd a region below what the output's texture coordinates hold, where no slit
  // helps: such triangles would fold when written. That component gets the area map on the same disk
  // (fold-free by construction), and the report says so.
  if (out.map.flipped > 0 && ctx.options.map == MapKind::kHarmonic) {
    const size_t collapsed = out.map.flipped;
    set_face_targets(out.disk, component_density(ctx.input, ctx.components[c], MapKind::kArea), MapKind::kArea, ctx.options.balance, mo);
    out.map = SquareMapStats{};
    out.uv = map_to_square(out.disk, mo, &out.map);
    out.cut.fallback_reason =
        fmt::format("the harmonic map collapses {} triangles below the output's precision: the area map instead", collapsed);
  }
  if (out.map.flipped > 0) return fmt::format("the map folds {} triangles", out.map.flipped);
  return "";
}

/// Both cuts of a small longest hole mapped side by side (kept as the boundary, and capped); the
/// estimate decides. Returns the kept cut's failure ("" when mapped).
std::string map_both_cuts(const MapContext& ctx, size_t c, const CutInputs& ci, SquareMapOptions& mo, Mapped& out) {
  Mapped alt;
  alt.rect = out.rect;
  SquareMapOptions alt_mo = mo;
  alt_mo.progress = nullptr;  // the kept cut's map reports for both
  std::string failure, alt_failure;
  tbb::parallel_invoke([&] { failure = run_attempt([&] { return cut_and_map(ctx, c, ci, false, mo, out); }); },
                       [&] { alt_failure = run_attempt([&] { return cut_and_map(ctx, c, ci, true, alt_mo, alt); }); });
  if (!failure.empty() || !alt_failure.empty() || !alt.cut.longest_loop_capped) return failure;
  const double kept = estimate_mse(ctx.input, out), capped = estimate_mse(ctx.input, alt);
  out.cut.compared_mse = {kept, capped};
  if (better_map(ctx.options.map, alt.map, capped, out.map, kept, 1.0)) {
    alt.cut.compared_mse = out.cut.compared_mse;
    out.disk = std::move(alt.disk), out.uv = std::move(alt.uv), out.cut = std::move(alt.cut), out.map = alt.map;
  }
  return "";
}

/// The full method: handles, holes (the longest one both ways where it is small), cut, map.
std::string map_full(const MapContext& ctx, size_t c, const CutInputs* pre, CapChoice choice, SquareMapOptions& mo, Mapped& out) {
  if (forced_to_fail(ctx, c)) return "full method failure forced by a test hook";
  const CutInputs own = pre ? CutInputs{} : cut_inputs(ctx.input, ctx.components[c]);
  const CutInputs& ci = pre ? *pre : own;
  // A small longest hole (pepper noise) is a poor boundary: a 3-edge loop cannot hold the square's
  // four corners. Capping it too is better there, but not everywhere: both are mapped, and the
  // estimate of the colour error decides.
  if (choice == CapChoice::kAuto) choice = small_longest_hole(ctx, c, ci) ? CapChoice::kCompare : CapChoice::kKeep;
  switch (choice) {
    case CapChoice::kCompare:
      return map_both_cuts(ctx, c, ci, mo, out);
    case CapChoice::kCap: {
      const std::string capped = cut_and_map(ctx, c, ci, true, mo, out);
      if (capped.empty() && out.cut.longest_loop_capped) return "";
      return cut_and_map(ctx, c, ci, false, mo, out);  // the usual cut, as any other component
    }
    case CapChoice::kAuto:
    case CapChoice::kKeep:
      break;
  }
  return cut_and_map(ctx, c, ci, false, mo, out);
}

/// The plain fallback: the plain cut graph (no handle search, caps or slits) and the fold-free map.
std::string map_plain(const MapContext& ctx, size_t c, SquareMapOptions& mo, Mapped& out) {
  if (forced_to_fail(ctx, c)) return "plain fallback failure forced by a test hook";
  CutOptions co;
  co.holes = ctx.options.holes;
  co.method = CutMethod::kPlain;
  out.disk = cut_to_disk(ctx.components[c], co, &out.cut);
  set_face_targets(out.disk, ctx.density[c], ctx.options.map, ctx.options.balance, mo);
  out.map = SquareMapStats{};
  out.uv = map_to_square(out.disk, mo, &out.map);
  if (out.map.flipped > 0) return fmt::format("the plain fallback's map folds {} triangles", out.map.flipped);
  return "";
}

}  // namespace

CutInputs cut_inputs(const TexturedMesh& input, const Surface& component) {
  CutInputs ci;
  ci.seams = find_texture_seams(input, component);
  if (topology_of(component).genus() > 0) {
    ci.denoised.emplace();
    ci.denoised->surface = remove_handles(component, &ci.denoised->handle_loops, ci.seams);
  }
  return ci;
}

bool small_longest_hole(const MapContext& ctx, size_t c, const CutInputs& ci) {
  const Options& o = ctx.options;
  if (o.map == MapKind::kHarmonic || o.holes != HoleMode::kFill || !ctx.have_pixels || !ctx.density[c].textured ||
      ctx.components[c].num_faces() > kProbeMaxFaces)
    return false;
  // Holes, or the two sides of a cut handle (the genus-0 surface remove_handles gives back).
  if (topology_of(ci.denoised ? ci.denoised->surface : ctx.components[c]).boundary_loops == 0) return false;
  CutStats st;
  return cut_to_disk_capped(ctx.components[c], full_cut_options(ctx, ci, kCapBudget), &st) && st.longest_loop_edges < kSmallKeptLoop;
}

Mapped kept_with_input_uvs(const MapContext& ctx, size_t c, const Rect& rect, std::string why) {
  Mapped out;
  out.rect = rect;
  out.cut.before = topology_of(ctx.components[c]);
  out.kept = std::move(why);
  ctx.progress.advance(double(ctx.components[c].num_faces()));
  return out;
}

Mapped map_component(const MapContext& ctx, size_t c, const Rect& rect, const CutInputs* pre, CapChoice choice, bool probe) {
  Mapped out;
  out.rect = rect;
  SquareMapOptions mo = map_options(ctx, c, rect);
  if (probe) mo.multilevel_from = std::min(mo.multilevel_from, kProbeMultilevelFrom), mo.coarse_vertices = kProbeCoarseVertices;
  const double faces = double(ctx.components[c].num_faces());
  double reported = 0;  // fraction of this map already added to the progress
  mo.progress = [&](double f) {
    if (f <= reported) return;
    ctx.progress.advance((f - reported) * faces);
    reported = f;
  };
  const std::string failure = run_attempt([&] { return map_full(ctx, c, pre, choice, mo, out); });
  if (!failure.empty()) {
    // A component the full method cannot handle still gets one chart: the plain cut graph and the
    // fold-free map. The report says so; the run goes on.
    out.cut = CutStats{};
    const std::string last = run_attempt([&] { return map_plain(ctx, c, mo, out); });
    out.cut.fallback_reason = failure;
    if (!last.empty()) {
      // The last resort: the component keeps its input texture coordinates and material(s), so none of
      // its triangles is lost (bake_plan). The report and the CLI say so.
      out.cut = CutStats{};
      out.cut.before = topology_of(ctx.components[c]);
      out.cut.fallback_reason = failure;
      out.kept = fmt::format("{}; then {}", failure, last);
      out.disk = Disk{};
      out.uv.clear();
    }
  }
  ctx.progress.advance((1 - reported) * faces);
  return out;
}

Mapped map_coarse_copy(const MapContext& ctx, size_t c, const Rect& rect, const CutInputs* pre, size_t vertices) {
  Mapped out;
  out.rect = rect;
  out.kept = run_attempt([&] {
    const CutInputs own = pre ? CutInputs{} : cut_inputs(ctx.input, ctx.components[c]);
    const CutInputs& ci = pre ? *pre : own;
    const Disk disk = cut_to_disk(ctx.components[c], full_cut_options(ctx, ci, kCapBudget), &out.cut);
    SquareMapOptions mo = map_options(ctx, c, rect);
    set_face_targets(disk, ctx.density[c], ctx.options.map, ctx.options.balance, mo);
    CoarseDisk coarse = coarsen_disk(disk, mo.face_target, vertices);
    const SquareMapOptions coarse_mo = coarse_options(mo, coarse);  // as multilevel_map maps its copy
    out.disk = std::move(coarse.disk);
    out.uv = map_to_square(out.disk, coarse_mo, &out.map);
    return out.map.flipped > 0 ? fmt::format("the coarse copy's map folds {} triangles", out.map.flipped) : std::string();
  });
  return out;
}

double estimate_mse(const TexturedMesh& input, const Mapped& m) {
  const size_t texels = size_t(m.rect.w) * size_t(m.rect.h);
  return resampling_mse(input, m.disk.mesh, m.uv, m.rect.w, m.rect.h, std::clamp(4 * texels, kEstimateMinSamples, kEstimateMaxSamples));
}

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

}  // namespace tightex
