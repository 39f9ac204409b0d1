#include "pipeline/bake_maps.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "core/image.hpp"
#include "core/tangents.hpp"

namespace tightex {

namespace {

/// The smallest reduction tried: a map's side is at least the base colour's over this.
constexpr int kMaxReduction = 16;
/// A map is judged at this many surface points (fixed seed), and may lose this much PSNR to a smaller
/// size (below Options::map_budget_db).
constexpr size_t kJudgePoints = 50000;
constexpr uint64_t kJudgeSeed = 20240606;
constexpr double kMaxReductionLossDb = 0.25;
/// A map below Options::map_budget_db is baked larger only where that gains at least this much PSNR.
constexpr double kMinEnlargementGainDb = 0.25;

/// The slots that read the same input textures the same way: one output map.
struct MapGroup {
  std::vector<MapSlot> slots;
  MapSource source;
};

/// What a triangle without the map reads: a neutral value (white for factors that multiply, black for
/// light and specular colour, the unperturbed normal, mid-grey height).
Rgba8 flat_value(MapSlot slot) {
  switch (slot) {
    case MapSlot::kEmissive:
    case MapSlot::kSpecular:
      return {0, 0, 0, 255};
    case MapSlot::kNormal:
      return {128, 128, 255, 255};
    case MapSlot::kBump:
      return {128, 128, 128, 255};
    default:
      return {255, 255, 255, 255};
  }
}

const char* encoding_name(MapEncoding e) {
  return e == MapEncoding::kSrgbColour ? "srgb_colour" : e == MapEncoding::kData ? "data" : "tangent_normal";
}

/// The slots some material binds to a loaded texture, grouped by the textures they read (per material)
/// and their encoding, in slot order.
std::vector<MapGroup> map_groups(const TexturedMesh& input) {
  std::vector<MapGroup> groups;
  for (size_t s = 0; s < kMapSlots; ++s) {
    const MapSlot slot = MapSlot(s);
    std::vector<int> textures(input.materials.size(), -1);
    bool any = false;
    for (size_t m = 0; m < input.materials.size(); ++m) {
      const int tex = input.materials[m].maps[s];
      if (tex < 0 || input.textures[size_t(tex)].image.empty()) continue;
      textures[m] = tex;
      any = true;
    }
    if (!any) continue;
    auto same = std::find_if(groups.begin(), groups.end(), [&](const MapGroup& g) {
      return g.source.texture_of_material == textures && g.source.encoding == map_encoding(slot);
    });
    if (same != groups.end()) {
      same->slots.push_back(slot);
      continue;
    }
    MapGroup g;
    g.slots = {slot};
    g.source.encoding = map_encoding(slot);
    g.source.texture_of_material = std::move(textures);
    g.source.flat = flat_value(slot);
    groups.push_back(std::move(g));
  }
  return groups;
}

/// The output's tangents: from the new texture coordinates for the mapped triangles (the first
/// om.bake_triangles.size()), the input's own for the kept ones (their texture coordinates are the
/// input's).
void set_output_tangents(const std::vector<Eigen::Vector4d>& input_tangents, OutputModel& om) {
  std::vector<Eigen::Vector4d> tangents = compute_corner_tangents(om.mesh);
  for (size_t o = om.bake_triangles.size(); o < om.mesh.num_triangles(); ++o)
    for (size_t k = 0; k < 3; ++k) tangents[3 * o + k] = input_tangents[3 * size_t(om.mesh.input_triangle[o]) + om.input_corner[3 * o + k]];
  om.mesh.corner_tangent = std::move(tangents);
}

/// Each bake triangle's input and output tangent frames.
std::vector<NormalFrames> normal_frames(const TexturedMesh& input, const std::vector<Eigen::Vector4d>& input_tangents,
                                        const OutputModel& om) {
  std::vector<NormalFrames> frames(om.bake_triangles.size());
  tbb::parallel_for(size_t(0), frames.size(), [&](size_t o) {
    const size_t t = om.mesh.input_triangle[o];
    for (size_t k = 0; k < 3; ++k) {
      const int ic = om.input_corner[3 * o + k];
      const Eigen::Vector4d& ti = input_tangents[3 * t + size_t(ic)];
      const Eigen::Vector4d& to = om.mesh.corner_tangent[3 * o + k];
      frames[o].input[k] = {ti.head<3>(), frame_normal(input, t, ic), ti.w()};
      frames[o].output[k] = {to.head<3>(), frame_normal(om.mesh, o, int(k)), to.w()};
    }
  });
  return frames;
}

/// `full` box-filtered to a side `factor` times smaller. Requires both sides divisible by factor.
Image reduce_image(const Image& full, int factor) {
  Image small(full.width / factor, full.height / factor);
  const float inv = 1.0f / float(factor * factor);
  tbb::parallel_for(0, small.height, [&](int y) {
    for (int x = 0; x < small.width; ++x) {
      float sum[4] = {0, 0, 0, 0};
      for (int j = 0; j < factor; ++j)
        for (int i = 0; i < factor; ++i) {
          const Rgba8& c = full.at(x * factor + i, y * factor + j);
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a;
        }
      auto q = [&](float v) { return uint8_t(std::clamp(v * inv + 0.5f, 0.0f, 255.0f)); };
      small.at(x, y) = {q(sum[0]), q(sum[1]), q(sum[2]), q(sum[3])};
    }
  });
  return small;
}

/// Points on the output's surface where a map's size is judged: per point its bake triangle and
/// barycentrics, drawn uniformly by 3D area with a fixed seed.
struct JudgePoint {
  uint32_t triangle;
  double b[3];
};

std::vector<JudgePoint> judge_points(const std::vector<BakeTriangle>& triangles, size_t count) {
  std::vector<double> cdf(triangles.size());
  double acc = 0;
  for (size_t t = 0; t < triangles.size(); ++t) cdf[t] = acc += std::isfinite(triangles[t].area3) ? triangles[t].area3 : 0.0;
  std::vector<JudgePoint> points;
  if (!(acc > 0)) return points;
  std::mt19937_64 rng(kJudgeSeed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (size_t i = 0; i < count; ++i) {
    const size_t t = std::min(triangles.size() - 1, size_t(std::upper_bound(cdf.begin(), cdf.end(), uni(rng) * acc) - cdf.begin()));
    double r1 = uni(rng), r2 = uni(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    points.push_back({uint32_t(t), {1 - r1 - r2, r1, r2}});
  }
  return points;
}

/// PSNR over `channels` of the output map `pages` (the pages `triangles` were laid out on, or those
/// reduced by `reduction`: read back bilinearly at the point's new texture coordinates) against
/// `reference` at the same points: the input's map through the input coordinates, or
/// (`reference_pages` set) the full-size bake.
double judged_psnr(const TexturedMesh& input, const MapSource& map, const std::vector<BakeTriangle>& triangles,
                   const std::vector<JudgePoint>& points, const std::vector<Image>& pages, const std::vector<Image>* reference_pages,
                   unsigned channels, int reduction = 1) {
  double se = 0, n = 0;
  for (const JudgePoint& p : points) {
    const BakeTriangle& tri = triangles[p.triangle];
    if (tri.image >= pages.size()) continue;
    const Vec2 px = p.b[0] * tri.target_px[0] + p.b[1] * tri.target_px[1] + p.b[2] * tri.target_px[2];
    // Texture coordinates from the pixel coordinates of the page the triangles were laid out on.
    const double u = px.x() / (double(pages[tri.image].width) * reduction),
                 v = 1.0 - px.y() / (double(pages[tri.image].height) * reduction);
    std::array<float, 4> ref;
    if (reference_pages) {
      ref = sample_bilinear((*reference_pages)[tri.image], u, v);
    } else {
      const int tex =
          tri.material >= 0 && size_t(tri.material) < map.texture_of_material.size() ? map.texture_of_material[size_t(tri.material)] : -1;
      if (tex < 0 || input.textures[size_t(tex)].image.empty()) continue;
      const Vec2 uv = p.b[0] * tri.source_uv[0] + p.b[1] * tri.source_uv[1] + p.b[2] * tri.source_uv[2];
      ref = sample_bilinear(input.textures[size_t(tex)].image, uv.x(), uv.y());
    }
    const auto out = sample_bilinear(pages[tri.image], u, v);
    for (int ch = 0; ch < 3; ++ch)
      if (channels & (1u << ch)) {
        const double d = double(std::lround(out[size_t(ch)]) - std::lround(ref[size_t(ch)]));
        se += d * d, n += 1;
      }
  }
  return n > 0 && se > 0 ? 10 * std::log10(255.0 * 255.0 * n / se) : 99.0;
}

/// The largest reduction (a power of two up to kMaxReduction that divides every page's sides) at which
/// the map, read back at the judge points, keeps at least `min_psnr_db` against the input or loses at
/// most kMaxReductionLossDb against its full-size bake's PSNR `full_psnr`; a normal map (whose new
/// texels are in another frame than the input's) against its full-size bake, at least `min_psnr_db`.
/// Returns the reduction and its PSNR.
std::pair<int, double> choose_reduction(const TexturedMesh& input, const MapSource& map, const std::vector<BakeTriangle>& triangles,
                                        const std::vector<JudgePoint>& points, const std::vector<Image>& full, unsigned channels,
                                        double full_psnr, double min_psnr_db) {
  const bool normal = map.encoding == MapEncoding::kTangentNormal;
  int chosen = 1;
  double chosen_psnr = full_psnr;
  for (int factor = 2; factor <= kMaxReduction; factor *= 2) {
    std::vector<Image> reduced;
    for (const Image& page : full) {
      if (page.width % factor != 0 || page.height % factor != 0) return {chosen, chosen_psnr};
      reduced.push_back(reduce_image(page, factor));
    }
    const double psnr = judged_psnr(input, map, triangles, points, reduced, normal ? &full : nullptr, channels, factor);
    if (psnr < min_psnr_db && (normal || psnr < full_psnr - kMaxReductionLossDb)) break;
    chosen = factor, chosen_psnr = psnr;
  }
  return {chosen, chosen_psnr};
}

/// A map's side over the base colour's: num / den (den divides every page's sides, so that the same
/// texture coordinates address the same point of the larger page).
struct MapScale {
  int num = 1, den = 1;
  double value() const { return double(num) / den; }
};

/// The pages' bake triangles and rectangles at `scale`: pixel coordinates times the scale, rectangle
/// edges floored. For a scale >= 1 every texel centre inside a chart stays inside its rectangle, and
/// rectangles that did not overlap still do not.
std::pair<std::vector<BakeTriangle>, std::vector<Rect>> scaled_layout(const OutputModel& om, MapScale scale) {
  std::vector<BakeTriangle> triangles = om.bake_triangles;
  for (BakeTriangle& t : triangles)
    for (Vec2& px : t.target_px) px *= scale.value();
  std::vector<Rect> rects = om.rects;
  auto at = [&](int x) { return int((int64_t(x) * scale.num) / scale.den); };
  for (Rect& r : rects) {
    const int x0 = at(r.x), y0 = at(r.y);
    r.w = at(r.x + r.w) - x0, r.h = at(r.y + r.h) - y0, r.x = x0, r.y = y0;
  }
  return {std::move(triangles), std::move(rects)};
}

/// The larger scales a map may take: steps of 1/den (den the largest of 8, 4, 2, 1 dividing every new
/// page's sides) above 1, up to as many texels as the map's input images hold together and no page
/// side above `max_side` (Options::max_page_side; 0: no cap). In increasing order; empty when none fits.
std::vector<MapScale> enlargements(const TexturedMesh& input, const MapSource& map, const OutputModel& om, int max_side) {
  double input_texels = 0, page_texels = 0;
  std::vector<int> seen;
  for (int tex : map.texture_of_material)
    if (tex >= 0 && std::find(seen.begin(), seen.end(), tex) == seen.end()) {
      seen.push_back(tex);
      input_texels += double(input.textures[size_t(tex)].image.width) * input.textures[size_t(tex)].image.height;
    }
  int den = 8, longest_side = 0;
  for (int p = 0; p < om.new_images; ++p) {
    const Image& page = om.mesh.textures[size_t(p)].image;
    page_texels += double(page.width) * page.height;
    longest_side = std::max({longest_side, page.width, page.height});
    while (den > 1 && (page.width % den != 0 || page.height % den != 0)) den /= 2;
  }
  std::vector<MapScale> scales;
  for (int num = den + 1; page_texels > 0; ++num) {
    const MapScale s{num, den};
    if (s.value() * s.value() * page_texels > input_texels || (max_side > 0 && int64_t(longest_side) * num / den > max_side)) break;
    scales.push_back(s);
  }
  return scales;
}

/// Whether the texel budget is tightex's default (the input's used texels) rather than a --size or
/// --texels the caller chose: only then may a map grow beyond the base colour's pages, since a chosen
/// budget is what the caller's engine or delivery can hold.
bool budget_is_default(const Options& o) { return o.default_budget || o.size == 0; }

/// Allocated black pages for a map at `scale` of the base colour's pages.
std::vector<Image> blank_pages(const OutputModel& om, MapScale scale) {
  std::vector<Image> images;
  for (int p = 0; p < om.new_images; ++p) {
    const Image& colour = om.mesh.textures[size_t(p)].image;
    images.emplace_back(colour.width * scale.num / scale.den, colour.height * scale.num / scale.den, Rgba8{0, 0, 0, 255});
  }
  return images;
}

/// A map baked and sized: its pages, its scale (one of them 1) and PSNR at the judge points.
struct SizedMap {
  std::vector<Image> pages;
  MapScale enlarged;
  int reduction = 1;
  double psnr = 99;
};

/// The map baked at the base colour's size, then sized by `sizing`'s map_budget_db: below it, baked again larger (enlargements) at the
/// smallest scale that reaches it, or the largest one when none does, provided that gains at least kMinEnlargementGainDb; otherwise reduced
/// as far as choose_reduction allows. A normal map (judged against its own full-size bake) is never enlarged, nor any map under a budget
/// the caller chose (budget_is_default); no page side grows beyond sizing.max_page_side.
SizedMap bake_sized_map(const TexturedMesh& input, const MapSource& map, const OutputModel& om, unsigned channels, const Options& sizing,
                        const BakeOptions& options) {
  const double min_psnr_db = sizing.map_budget_db;
  SizedMap best;
  best.pages = blank_pages(om, {});
  bake_map(input, map, om.bake_triangles, om.rects, best.pages, nullptr, options);
  if (!(min_psnr_db > 0)) return best;
  const std::vector<JudgePoint> points = judge_points(om.bake_triangles, kJudgePoints);
  const bool normal = map.encoding == MapEncoding::kTangentNormal;
  best.psnr = normal ? 99.0 : judged_psnr(input, map, om.bake_triangles, points, best.pages, nullptr, channels);
  const std::vector<MapScale> scales = normal || best.psnr >= min_psnr_db || !budget_is_default(sizing)
                                           ? std::vector<MapScale>{}
                                           : enlargements(input, map, om, sizing.max_page_side);
  // Binary search over the scales for the smallest that reaches the budget, starting from the largest.
  size_t lo = 0, hi = scales.size();  // scales below lo were not enough; scales[hi] (if any) is enough
  const double gained_floor = best.psnr + kMinEnlargementGainDb;
  bool largest = true;
  while (lo < hi) {
    const size_t mid = largest ? hi - 1 : (lo + hi) / 2;
    auto [triangles, rects] = scaled_layout(om, scales[mid]);
    std::vector<Image> pages = blank_pages(om, scales[mid]);
    bake_map(input, map, triangles, rects, pages, nullptr, options);
    const double psnr = judged_psnr(input, map, triangles, points, pages, nullptr, channels);
    if (largest && psnr < gained_floor) break;  // more texels do not help this map
    if (largest || psnr >= min_psnr_db) best = {std::move(pages), scales[mid], 1, psnr};
    if (psnr >= min_psnr_db)
      hi = mid;
    else
      lo = mid + 1;
    largest = false;
  }
  if (best.enlarged.num != best.enlarged.den) return best;
  std::tie(best.reduction, best.psnr) =
      choose_reduction(input, map, om.bake_triangles, points, best.pages, channels, best.psnr, min_psnr_db);
  return best;
}

}  // namespace

std::vector<MapEntry> bake_other_maps(const TexturedMesh& input, const Options& options, OutputModel& om) {
  std::vector<MapGroup> groups = map_groups(input);
  const bool normal_map =
      std::any_of(groups.begin(), groups.end(), [](const MapGroup& g) { return g.source.encoding == MapEncoding::kTangentNormal; });
  std::vector<NormalFrames> frames;
  if (normal_map || !input.corner_tangent.empty()) {
    const std::vector<Eigen::Vector4d> input_tangents = completed_corner_tangents(input);
    set_output_tangents(input_tangents, om);
    if (normal_map) frames = normal_frames(input, input_tangents, om);
  }
  if (om.new_images == 0) return {};  // every component kept its input maps (kept_material copies them)
  BakeOptions bo;
  bo.fit = options.fit;
  if (options.fine_fit) bo.fit_samples = kFineFitSamples, bo.fit_lambda = kFineFitLambda;
  std::vector<MapEntry> entries;
  for (MapGroup& g : groups) {
    const auto start = std::chrono::steady_clock::now();
    g.source.frames = &frames;
    BakeOptions map_options = bo;
    // A normal map without the fit: the fit would match encoded texels, which a renderer decodes through
    // a frame that turns across the texel; without it the angles are about as good, at a fraction of
    // the time (measured in BENCHMARKS.md, "Every map").
    if (g.source.encoding == MapEncoding::kTangentNormal) map_options.fit = false;
    unsigned channels = 0;
    for (MapSlot s : g.slots) channels |= map_slot_channels(s);
    SizedMap sized = bake_sized_map(input, g.source, om, channels, options, map_options);
    MapEntry entry;
    entry.name = map_slot_name(g.slots[0]);
    for (MapSlot s : g.slots) entry.slots.push_back(map_slot_name(s));
    entry.encoding = encoding_name(g.source.encoding);
    entry.scale = sized.enlarged.value() / sized.reduction;
    entry.judged_psnr_db = sized.psnr;
    for (int p = 0; p < om.new_images; ++p) {
      Texture tex;
      tex.path = om.mesh.textures[size_t(p)].path + "_" + entry.name;
      tex.image = sized.reduction > 1 ? reduce_image(sized.pages[size_t(p)], sized.reduction) : std::move(sized.pages[size_t(p)]);
      entry.sizes.push_back({tex.image.width, tex.image.height});
      for (MapSlot s : g.slots) om.mesh.materials[size_t(p)].maps[size_t(s)] = int(om.mesh.textures.size());
      om.mesh.textures.push_back(std::move(tex));
    }
    entry.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entries.push_back(std::move(entry));
  }
  return entries;
}

}  // namespace tightex
