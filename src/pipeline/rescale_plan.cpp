// rescale_plan: the same charts on smaller or larger textures, for the rate search's second bake.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "layout/float_coordinates.hpp"
#include "layout/layout.hpp"
#include "pipeline/plan_state.hpp"

namespace tightex {

namespace {

/// The least side of a rectangle (layout_atlas's min_side as the plan lays out).
constexpr int kMinRectSide = 4;

/// Rectangle r of a `from` (width, height) texture moved to a `to` one: each edge to the same
/// fraction of the side, rounded, so rectangles that shared an edge still share it.
Rect rect_in(const Rect& r, std::pair<int, int> from, std::pair<int, int> to) {
  auto at = [](int x, int a, int b) { return int(std::lround(double(x) * b / a)); };
  Rect s = r;
  s.x = at(r.x, from.first, to.first), s.w = at(r.x + r.w, from.first, to.first) - s.x;
  s.y = at(r.y, from.second, to.second), s.h = at(r.y + r.h, from.second, to.second) - s.y;
  return s;
}

/// The rectangles `on` one page (indices into `rects`) moved from a `from` page to a `to` one: in
/// proportion (rect_in) where every one keeps kMinRectSide; else laid out again in the smaller page
/// with the shares their areas had (a small component's rectangle rounds up to the least side, as in
/// the plan). False where the page cannot hold them.
bool move_page(const std::vector<size_t>& on, std::pair<int, int> from, std::pair<int, int> to, std::vector<Rect>& rects) {
  std::vector<Rect> moved;
  for (const size_t c : on) moved.push_back(rect_in(rects[c], from, to));
  if (std::any_of(moved.begin(), moved.end(), [](const Rect& r) { return r.w < kMinRectSide || r.h < kMinRectSide; })) {
    std::vector<double> areas;
    for (const size_t c : on) areas.push_back(double(rects[c].w) * double(rects[c].h));
    const std::optional<std::vector<Rect>> laid = try_layout_atlas(areas, to.first, to.second, kMinRectSide, AtlasShares::kExact);
    if (!laid) return false;
    moved = *laid;
  }
  for (size_t i = 0; i < on.size(); ++i) rects[on[i]] = Rect{rects[on[i]].image, moved[i].x, moved[i].y, moved[i].w, moved[i].h};
  return true;
}

}  // namespace

bool rescale_plan(Plan& plan, double scale, const std::map<std::string, double>& map_scales) {
  Plan::State& state = mutable_plan_state(plan);
  if (state.maps_released || !(scale > 0) || scale == 1) return false;
  if (std::any_of(state.kept.begin(), state.kept.end(), [](const std::string& k) { return !k.empty(); })) return false;
  std::vector<std::pair<int, int>> sizes;
  std::vector<std::vector<size_t>> on(state.image_size.size());
  for (const auto& [w, h] : state.image_size) sizes.push_back({texture_side_at(w, scale), texture_side_at(h, scale)});
  for (size_t c = 0; c < state.rects.size(); ++c) on[size_t(state.rects[c].image)].push_back(c);
  std::vector<Rect> rects = state.rects;
  for (size_t p = 0; p < on.size(); ++p)
    if (!move_page(on[p], state.image_size[p], sizes[p], rects)) return false;
  state.rects = std::move(rects);
  state.image_size = std::move(sizes);
  // The texture coordinates as written change with the rectangles: kept fold-free in float again.
  std::vector<FloatGuard> guards(state.rects.size());
  tbb::parallel_for(size_t(0), state.rects.size(), [&](size_t c) {
    const Rect& r = state.rects[c];
    const auto [w, h] = state.image_size[size_t(r.image)];
    guards[c] = keep_orientation_in_float(state.disks[c].mesh, r, w, h, state.uv[c]);
  });
  for (ComponentEntry& e : state.report.components) {
    e.rect = state.rects[e.index];
    e.map.float_moved += guards[e.index].moved, e.map.float_unfixed = guards[e.index].unfixed;
  }
  state.fixed_map_scales = map_scales;
  state.report.options.size = texture_side_at(state.report.options.size, scale);
  state.report_json = to_json(state.report);
  return true;
}

}  // namespace tightex
