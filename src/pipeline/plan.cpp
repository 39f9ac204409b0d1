// plan_charts: the geometric half of the method, stage after stage (paper §4.1, §4.2, then the layout).
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include "core/error.hpp"
#include "core/memory_model.hpp"
#include "core/progress.hpp"
#include "core/resources.hpp"
#include "layout/chart_orientation.hpp"
#include "layout/float_coordinates.hpp"
#include "pipeline/aspect.hpp"
#include "pipeline/budget.hpp"
#include "pipeline/plan_report.hpp"
#include "pipeline/plan_state.hpp"
#include "pipeline/stage_clock.hpp"
#include "pipeline/tight_input.hpp"
#include "pipeline/validate.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"

namespace tightex {

namespace {

/// The share of a page that one component may take before it is split for pages: room for the
/// page's other components and for rounding the rectangles.
constexpr double kPageFill = 0.8;

/// The fewest triangles a piece of a component split for pages has on average (split_oversized_components).
constexpr size_t kMinPieceFaces = 64;

/// The largest texture side a run makes without allow_large_textures: 1 GiB of RGBA.
constexpr int kLargeSide = 16384;

/// Checks the budget's side and the aspect.
void check_budget(const TextureBudget& budget, const Options& options) {
  if (budget.side < 8 || budget.side > 65536) fail_input("--size {} is out of range (8..65536)", budget.side);
  if (budget.side > kLargeSide && !options.allow_large_textures)
    fail_input("--size {} is above {} ({:.1f} GiB of RGBA texture); add --force (allow_large_textures) to allow it", budget.side,
               kLargeSide, double(budget.side) * budget.side * 4 / double(1 << 30));
  const double aspect = effective_aspect(options);
  if (aspect != 0 && !(aspect >= 1.0 / 16 && aspect <= 16))
    fail_input("aspect {} is out of range (0 or {} for auto, or 1/16..16)", options.aspect, kAspectAuto);
}

std::vector<double> component_areas(const std::vector<Surface>& components) {
  std::vector<double> areas(components.size(), 0.0);
  for (size_t c = 0; c < components.size(); ++c)
    for (const Tri& f : components[c].triangles) areas[c] += triangle_area(components[c].positions, f);
  return areas;
}

/// Each component's target density (for every map but the harmonic one) and its share of the texture.
std::vector<double> plan_density(const TexturedMesh& input, const Options& options, const std::vector<Surface>& components,
                                 const std::vector<double>& areas, int size, std::vector<ComponentDensity>& density) {
  density.assign(components.size(), ComponentDensity{});
  if (options.map == MapKind::kHarmonic) return areas;
  tbb::parallel_for(size_t(0), components.size(), [&](size_t c) { density[c] = component_density(input, components[c], options.map); });
  if (options.map == MapKind::kDetail) allocate_detail(components, density, double(size) * double(size));
  return texture_shares(density, areas);
}

/// Triangles the maps will take (the probed component once per probe), for the progress.
double faces_to_map(const std::vector<Surface>& components, size_t probed) {
  double faces = 0;
  for (const Surface& comp : components) faces += double(comp.num_faces());
  if (probed == kNone) return faces;
  // The other shapes' probes; where they would be multilevel, the one other shape's own map.
  const size_t faces_probed = components[probed].num_faces();
  const size_t others = probes_would_be_multilevel(faces_probed) ? 1 : std::size(kAspectProbes) - 1;
  return faces + double(faces_probed) * double(others);
}

bool have_pixels(const TexturedMesh& input) {
  for (const Texture& t : input.textures)
    if (!t.image.empty()) return true;
  return false;
}

/// How many pieces component `c` becomes: enough that each holds at most Options::max_piece_faces
/// triangles and, in the atlas, at most kPageFill of a page (Options::max_page_side) of the size^2
/// budget; 1: it stays whole. `texels`: its share of the budget.
int pieces_needed(const Options& options, const Surface& component, double texels) {
  double parts = 1;
  if (options.layout == Layout::kAtlas && options.max_page_side > 0)
    parts = std::ceil(texels / (kPageFill * double(options.max_page_side) * double(options.max_page_side)));
  if (options.max_piece_faces > 0) parts = std::max(parts, std::ceil(double(component.num_faces()) / double(options.max_piece_faces)));
  // Not below kMinPieceFaces triangles a piece: a piece of a few triangles cannot fill its square
  // (one triangle covers half of it); such a piece keeps a capped page instead (assign_pages).
  const size_t most = std::max<size_t>(1, component.num_faces() / kMinPieceFaces);
  return int(std::min(double(most), parts));
}

/// Splits every component that is more than a page holds or has more than Options::max_piece_faces
/// triangles (pieces_needed) into pieces (split_into_parts, by area), and marks the pieces in `piece`
/// (per component, kept aligned). Returns whether any was.
bool split_oversized_components(const Options& options, int size, const std::vector<double>& shares, std::vector<Surface>& components,
                                std::vector<char>& piece, Pages& pages) {
  const double budget = double(size) * double(size), total = std::accumulate(shares.begin(), shares.end(), 0.0);
  if (!(total > 0)) return false;
  piece.resize(components.size(), 0);
  std::vector<Surface> split;
  std::vector<char> split_piece;
  bool any = false;
  for (size_t c = 0; c < components.size(); ++c) {
    const int parts = pieces_needed(options, components[c], shares[c] / total * budget);
    if (parts < 2) {
      split.push_back(std::move(components[c])), split_piece.push_back(piece[c]);
      continue;
    }
    std::vector<Surface> pieces = split_into_parts(components[c], parts);
    ++pages.components_split, pages.pieces += pieces.size() - 1, any = true;
    for (Surface& p : pieces) split.push_back(std::move(p)), split_piece.push_back(1);
  }
  components = std::move(split);
  piece = std::move(split_piece);
  return any;
}

/// Groups of components, one per page: the fewest pages, from ceil(W x H / max^2) up, where each
/// page's share of the W x H budget (largest component first, each to the page with the least so far)
/// fits a max x max page in the atlas's shape and the atlas layout holds its components; per page, its
/// components and its size.
struct PageAssignment {
  std::vector<std::vector<size_t>> components;
  std::vector<std::pair<int, int>> size;
};
PageAssignment assign_pages(const std::vector<double>& shares, int W, int H, double aspect, int max_side, AtlasShares mode) {
  const double total = std::max(std::accumulate(shares.begin(), shares.end(), 0.0), 1e-300);
  std::vector<size_t> order(shares.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return shares[a] > shares[b]; });
  const double max_texels = double(max_side) * double(max_side);
  // At most a page a component: beyond that a page would be empty.
  for (size_t pages = std::min(shares.size(), size_t(std::ceil(double(W) * double(H) / max_texels)));; ++pages) {
    PageAssignment a;
    a.components.resize(pages);
    std::vector<double> load(pages, 0.0);
    for (size_t c : order) {
      const size_t p = size_t(std::min_element(load.begin(), load.end()) - load.begin());
      a.components[p].push_back(c), load[p] += shares[c];
    }
    bool fits = true;
    for (size_t p = 0; p < pages && fits; ++p) {
      const double texels = load[p] / total * double(W) * double(H);
      auto [w, h] = atlas_size(std::max(8, int(std::ceil(std::sqrt(texels) / 4)) * 4), aspect);
      if (pages >= shares.size()) w = std::min(w, max_side), h = std::min(h, max_side);  // a page a component: capped
      std::vector<double> page_shares;
      for (size_t c : a.components[p]) page_shares.push_back(shares[c]);
      fits = w <= max_side && h <= max_side && try_layout_atlas(page_shares, w, h, 4, mode).has_value();
      a.size.push_back({w, h});
    }
    if (fits || pages >= shares.size()) return a;
  }
}

/// The atlas on several pages (assign_pages), each laid out by layout_atlas.
void lay_out_pages(const std::vector<double>& shares, int W, int H, double aspect, int max_side, AtlasShares mode, Plan::State& plan) {
  const PageAssignment a = assign_pages(shares, W, H, aspect, max_side, mode);
  plan.rects.assign(shares.size(), Rect{});
  for (size_t p = 0; p < a.components.size(); ++p) {
    std::vector<double> page_shares;
    for (size_t c : a.components[p]) page_shares.push_back(shares[c]);
    const std::vector<Rect> rects = layout_atlas(page_shares, a.size[p].first, a.size[p].second, 4, mode);
    for (size_t i = 0; i < rects.size(); ++i) {
      plan.rects[a.components[p][i]] = rects[i];
      plan.rects[a.components[p][i]].image = int(p);
    }
    plan.image_size.push_back(a.size[p]);
  }
}

/// The rectangles and texture sizes: one atlas of the chosen shape (on several pages where it is wider
/// or taller than Options::max_page_side), or a texture per component.
void lay_out(const Options& options, const std::vector<double>& shares, int size, double aspect, Plan::State& plan) {
  const bool default_budget = plan.budget.is_default;
  if (options.layout == Layout::kAtlas) {
    const auto [W, H] = atlas_size(size, aspect);
    const AtlasShares mode = options.map == MapKind::kArea ? AtlasShares::kExact : AtlasShares::kLeastError;
    const int max_side = options.max_page_side;
    if (max_side > 0 && (W > max_side || H > max_side)) {
      lay_out_pages(shares, W, H, aspect, max_side, mode, plan);
      std::string& reason = plan.report.pages.reason;
      reason = fmt::format("the budget's {} x {} texture is larger than --max-size {} allows a page", W, H, max_side);
      double written = 0;
      for (const auto& [w, h] : plan.image_size) written += double(w) * double(h);
      if (written < 0.95 * double(W) * double(H))
        reason += fmt::format("; the pages hold {:.0f} of its {} texels: a component is not split into pieces of fewer than {} triangles",
                              written, long(W) * long(H), kMinPieceFaces);
    } else {
      plan.rects = layout_atlas(shares, W, H, 4, mode);
      plan.image_size.push_back({W, H});
    }
    plan.report.pages.count = plan.image_size.size();
    return;
  }
  const int side = default_budget ? per_component_side(shares, size) : size;
  plan.rects = layout_per_component(shares, side, 4, aspect);
  for (const Rect& r : plan.rects) plan.image_size.push_back({r.w, r.h});
}

/// Every component cut and mapped into its rectangle (the probed one reuses its chosen probe's map),
/// each from its prepared cut inputs, released once it is mapped; each one's cut and map statistics
/// for the report. The large maps one after another where the memory limit does not leave room for
/// all of them at once (large_maps_at_once), the smaller ones beside them: returns how many went one
/// after another (0: all at once).
size_t map_components(const MapContext& ctx, std::optional<Mapped>& probed, size_t probed_component,
                      std::vector<std::optional<CutInputs>>& cut_inputs, const std::string& keep_all, Plan::State& plan,
                      std::vector<CutStats>& cuts, std::vector<SquareMapStats>& maps) {
  const size_t nc = plan.components.size();
  plan.disks.resize(nc);
  plan.uv.resize(nc);
  plan.kept.assign(nc, std::string());
  cuts.resize(nc);
  maps.resize(nc);
  auto map_one = [&](size_t c) {
    const Rect& rect = plan.rects[c];
    Mapped m = !keep_all.empty() ? kept_with_input_uvs(ctx, c, rect, keep_all)
               : c == probed_component && probed && rect.w == probed->rect.w && rect.h == probed->rect.h
                   ? std::move(*probed)
                   : map_component(ctx, c, rect, cut_inputs[c] ? &*cut_inputs[c] : nullptr, CapChoice::kAuto);
    cut_inputs[c].reset();
    if (m.kept.empty()) {
      // Upright in its rectangle: the input's print keeps its direction where a quarter turn can give it.
      orient_chart(ctx.input, m.disk.mesh, rect, m.uv);
      const auto [width, height] = plan.image_size[size_t(rect.image)];
      const FloatGuard guard = keep_orientation_in_float(m.disk.mesh, rect, width, height, m.uv);
      m.map.float_moved = guard.moved, m.map.float_unfixed = guard.unfixed;
    }
    plan.disks[c] = std::move(m.disk);
    plan.uv[c] = std::move(m.uv);
    cuts[c] = std::move(m.cut);
    maps[c] = m.map;
    plan.kept[c] = std::move(m.kept);
  };
  std::vector<size_t> large, small;
  double large_faces = 0;
  for (size_t c = 0; c < nc; ++c) {
    const bool is_large = plan.components[c].num_faces() >= kLargeMapFaces;
    (is_large ? large : small).push_back(c);
    if (is_large) large_faces += double(plan.components[c].num_faces());
  }
  if (large.size() < 2 || large_maps_at_once(large_faces, peak_rss_mib(), memory_limit_mib(ctx.options.max_memory_mib))) {
    tbb::parallel_for(size_t(0), nc, map_one);
    return 0;
  }
  tbb::parallel_invoke(
      [&] {
        for (size_t c : large) map_one(c);
      },
      [&] { tbb::parallel_for(size_t(0), small.size(), [&](size_t i) { map_one(small[i]); }); });
  return large.size();
}

OptionsUsed options_used(const Options& o, int size) {
  return {size, 0, o.layout, o.holes, o.map, o.balance, o.fit, o.fit && o.fine_fit, o.corners, o.aspect, o.material_map_budget_db};
}

}  // namespace

uint64_t input_fingerprint(const TexturedMesh& input) {
  // FNV-1a's step on 8-byte words (then the bytes left), with a shift that brings the high bits down:
  // each step is a bijection of h, so any one word that differs changes the result. A word at a time
  // is about 8 times as fast as FNV's byte at a time (a multiply's latency each): 0.09 s at 850k
  // triangles, where the CLI checks it three times.
  uint64_t h = 1469598103934665603ull;
  auto step = [&](uint64_t w) {
    h = (h ^ w) * 1099511628211ull;
    h ^= h >> 29;
  };
  auto mix = [&](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (uint64_t w; i + 8 <= bytes; i += 8) std::memcpy(&w, p + i, 8), step(w);
    for (; i < bytes; ++i) step(p[i]);
  };
  const size_t counts[2] = {input.num_vertices(), input.num_triangles()};
  mix(counts, sizeof counts);
  mix(input.triangles.data(), input.triangles.size() * sizeof(Tri));
  mix(input.corner_uv.data(), input.corner_uv.size() * sizeof(Vec2));
  mix(input.face_material.data(), input.face_material.size() * sizeof(int32_t));
  return h;
}

std::vector<char> untextured_triangles(const TexturedMesh& geometry, std::vector<uint32_t>& list) {
  std::vector<char> untextured(geometry.num_triangles(), 0);
  list.clear();
  for (uint32_t t = 0; t < geometry.num_triangles(); ++t) {
    const int32_t m = geometry.face_material[t];
    if (m >= 0 && geometry.materials[size_t(m)].texture >= 0) continue;
    untextured[t] = 1;
    list.push_back(t);
  }
  if (list.size() == geometry.num_triangles())
    fail_input("{}: nothing to bake: none of its {} triangles has a texture or vertex colours", geometry.source, list.size());
  return untextured;
}

void scale_to_world_area(const TexturedMesh& geometry, std::vector<Surface>& components) {
  if (geometry.source_mesh_area_scale.empty() || geometry.source_mesh.empty()) return;
  // One scale for every component changes no share: the components stay as they are.
  const double first = geometry.source_mesh_area_scale[geometry.source_mesh[components.front().input_face[0]]];
  if (std::all_of(components.begin(), components.end(),
                  [&](const Surface& comp) { return geometry.source_mesh_area_scale[geometry.source_mesh[comp.input_face[0]]] == first; }))
    return;
  for (Surface& comp : components) {
    const double area_scale = geometry.source_mesh_area_scale[geometry.source_mesh[comp.input_face[0]]];
    if (area_scale == 1.0 || !(area_scale > 0)) continue;
    const double scale = std::sqrt(area_scale);
    for (Vec3& p : comp.positions) p *= scale;
  }
}

std::vector<std::optional<CutInputs>> prepare_cut_inputs(const TexturedMesh& input, const std::vector<Surface>& components) {
  std::vector<std::optional<CutInputs>> out(components.size());
  tbb::parallel_for(size_t(0), components.size(), [&](size_t c) {
    try {
      out[c] = cut_inputs(input, components[c]);
    } catch (const InternalError&) {
      out[c].reset();
    }
  });
  return out;
}

std::unique_ptr<PreparedMesh::State> prepare_state(const TexturedMesh& geometry, const Options& options) {
  validate_mesh(geometry);
  const TextureBudget budget = texture_budget(geometry, options);  // the options checked before the work
  const StageProgress progress(options.progress);
  auto prepared = std::make_unique<PreparedMesh::State>();
  prepared->input_fingerprint = input_fingerprint(geometry);
  StageClock clock(prepared->timings);

  // 1. Preparation (§4.1): weld, drop degenerate and duplicate triangles, orient, slice non-manifold
  //    elements.
  progress("repair", 0);
  const RepairStats& rs = prepared->repair;
  const std::vector<char> untextured = untextured_triangles(geometry, prepared->set_aside.untextured);
  if (!options.keep_untextured) prepared->set_aside.untextured.clear();  // baked with the rest
  const Surface surface = prepare_surface(geometry, &prepared->repair, &prepared->set_aside.repeats,
                                          prepared->set_aside.untextured.empty() ? nullptr : &untextured);
  if (surface.num_faces() == 0)
    fail_input("{}: no triangle with non-zero area ({} zero-area, {} duplicate)", geometry.source, rs.zero_area_triangles,
               rs.repeated_triangles);
  clock.done("repair");

  // 2. Connected components, each one's texture seams (the cut prefers them) and handles removed.
  progress("components", 0);
  prepared->components = split_components(surface);
  scale_to_world_area(geometry, prepared->components);
  // An input that is already tight is kept, not cut (a plan with another budget cuts each component
  // when it maps it).
  prepared->tight_utilization = tight_utilization(geometry, prepared->components);
  if (keep_tight_reason(prepared->tight_utilization, options, budget).empty())
    prepared->cut_inputs = prepare_cut_inputs(geometry, prepared->components);
  else
    prepared->cut_inputs.assign(prepared->components.size(), std::nullopt);
  clock.done("seams+handles");
  return prepared;
}

PreparedMesh::PreparedMesh() = default;
PreparedMesh::PreparedMesh(std::unique_ptr<State> state) : state_(std::move(state)) {}
PreparedMesh::PreparedMesh(PreparedMesh&&) noexcept = default;
PreparedMesh& PreparedMesh::operator=(PreparedMesh&&) noexcept = default;
PreparedMesh::~PreparedMesh() = default;
std::unique_ptr<PreparedMesh::State> PreparedMesh::take() { return std::move(state_); }

PreparedMesh prepare_mesh(const TexturedMesh& geometry, const Options& options) { return PreparedMesh(prepare_state(geometry, options)); }

namespace {

/// The rest of plan_charts after the preparation.
Plan plan_prepared(const TexturedMesh& input, const Options& given, const TextureBudget& budget, const PlanHooks& hooks,
                   std::unique_ptr<PreparedMesh::State> prepared) {
  Options options = given;  // the aspect as the run makes it: a square for a size (effective_aspect)
  options.aspect = effective_aspect(given);
  check_budget(budget, options);
  const StageProgress progress(options.progress);
  auto plan = std::make_unique<Plan::State>();
  plan->budget = budget;
  ReportData& rep = plan->report;
  rep.options = options_used(options, budget.side);
  int& size = rep.options.size;
  plan->input_fingerprint = prepared->input_fingerprint;
  rep.preparation.repair = prepared->repair;
  rep.preparation.untextured_kept = prepared->set_aside.untextured.size();
  plan->set_aside = std::move(prepared->set_aside);
  rep.timings = std::move(prepared->timings);
  StageClock clock(rep.timings);

  // 2. The components (prepared), the budget they need, and where the texels go on them.
  plan->components = std::move(prepared->components);
  std::vector<std::optional<CutInputs>> cut_inputs = std::move(prepared->cut_inputs);
  // An input that is one chart per component filling its texture already is kept as it came.
  const std::string keep_all = have_pixels(input) ? keep_tight_reason(prepared->tight_utilization, options, budget) : "";
  rep.preparation.already_tight = !keep_all.empty();
  prepared.reset();
  std::vector<double> areas = component_areas(plan->components);
  if (options.layout == Layout::kAtlas && budget.is_default) {
    const int side = atlas_side_holding(areas, size);
    if (side != size) rep.options.size_grown_from = size, size = side;
  }
  std::vector<ComponentDensity> density(plan->components.size());
  std::vector<double> shares = keep_all.empty() ? plan_density(input, options, plan->components, areas, size, density) : areas;
  rep.pages.max_side = options.layout == Layout::kAtlas ? options.max_page_side : 0;
  rep.pages.max_piece_faces = options.max_piece_faces;
  // Pieces split by area can still hold more than a page, or more triangles than a piece may, where the
  // density or the triangles' size is uneven: split again.
  std::vector<char> split_piece;
  for (int round = 0;
       keep_all.empty() && round < 3 && split_oversized_components(options, size, shares, plan->components, split_piece, rep.pages);
       ++round) {
    areas = component_areas(plan->components);
    shares = plan_density(input, options, plan->components, areas, size, density);
  }
  if (rep.pages.components_split > 0) cut_inputs = prepare_cut_inputs(input, plan->components);  // the pieces' own

  // 3. The texture's shape (auto: probed on the component that dominates the texture), then 4. each
  //    component cut to a disk and mapped onto its rectangle (§4.2).
  progress("cut+map", 0);
  ProgressCounter map_progress(progress.of_stage("cut+map"), 0);
  const MapContext ctx{input, options, plan->components, density, map_progress, have_pixels(input), hooks, split_piece};
  rep.aspect.requested = options.aspect;
  rep.aspect.probed_component = keep_all.empty() ? aspect_probe_component(ctx, shares) : kNone;
  map_progress.set_total(faces_to_map(plan->components, rep.aspect.probed_component));
  rep.aspect.chosen = options.aspect > 0 ? options.aspect : 1.0;
  std::optional<Mapped> probed;
  if (rep.aspect.probed_component != kNone) {
    const std::optional<CutInputs>& dominant_cut = cut_inputs[rep.aspect.probed_component];
    ShapeChoice choice = choose_aspect(ctx, rep.aspect.probed_component, dominant_cut ? &*dominant_cut : nullptr, shares, size,
                                       options.map == MapKind::kArea ? AtlasShares::kExact : AtlasShares::kLeastError);
    rep.aspect.chosen = choice.aspect;
    rep.aspect.probes = std::move(choice.probes);
    rep.aspect.square_texel_stretch = choice.square_texel_stretch;
    probed = std::move(choice.dominant_map);
  }
  lay_out(options, shares, size, rep.aspect.chosen, *plan);
  std::vector<CutStats> cuts;
  std::vector<SquareMapStats> maps;
  rep.pages.large_maps_one_after_another =
      map_components(ctx, probed, rep.aspect.probed_component, cut_inputs, keep_all, *plan, cuts, maps);
  release_free_memory();  // what the maps freed, before the bake allocates its own
  clock.done("cut+map");

  fill_plan_report(input, *plan, areas, cuts, maps, rep);
  plan->report_json = to_json(rep);
  return Plan(std::move(plan));
}

}  // namespace

TextureBudget texture_budget(const TexturedMesh& input, const Options& options) {
  if (options.size > 0 && options.texels > 0) fail_input("options: --size and --texels go one without the other");
  if (options.size < 0 || options.texels < 0) fail_input("options: --size and --texels must not be negative");
  const int max_side = options.allow_large_textures ? 65536 : kLargeSide;
  const TextureBudget budget = options.size > 0     ? TextureBudget{options.size, false}
                               : options.texels > 0 ? TextureBudget{std::min(size_for_texels(options.texels), max_side), false}
                                                    : TextureBudget{default_size(input, max_side), true};
  check_budget(budget, options);
  return budget;
}

Plan plan_charts(const TexturedMesh& input, const Options& options) { return plan_charts(input, options, PlanHooks{}); }

Plan plan_charts(const TexturedMesh& input, const Options& options, const PlanHooks& hooks) {
  const TextureBudget budget = texture_budget(input, options);
  return plan_prepared(input, options, budget, hooks, prepare_state(input, options));
}

Plan plan_charts(const TexturedMesh& input, const Options& options, PreparedMesh&& prepared) {
  return plan_charts(input, options, texture_budget(input, options), &prepared);
}

Plan plan_charts(const TexturedMesh& input, const Options& options, const TextureBudget& budget, PreparedMesh* prepared) {
  if (!prepared) return plan_prepared(input, options, budget, PlanHooks{}, prepare_state(input, options));
  std::unique_ptr<PreparedMesh::State> state = prepared->take();
  if (!state) fail_input("{}: the preparation is empty (made by prepare_mesh? used already?)", input.source);
  validate_mesh(input);
  if (state->input_fingerprint != input_fingerprint(input))
    fail_input("{}: not the mesh the preparation was made from (its triangles, texture coordinates or materials differ)", input.source);
  return plan_prepared(input, options, budget, PlanHooks{}, std::move(state));
}

}  // namespace tightex
