#include "pipeline/bake_material_maps.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <random>

#include "core/image.hpp"
#include "core/tangents.hpp"

namespace tightex {

namespace {

/// The smallest reduction tried: a map's side is at least the base colour's over this.
constexpr int kMaxReduction = 16;
/// A map is judged at this many surface points (fixed seed), and may lose this much PSNR to a smaller
/// size (below Options::material_map_budget_db).
constexpr size_t kJudgePoints = 50000;
constexpr uint64_t kJudgeSeed = 20240606;
constexpr double kMaxReductionLossDb = 0.25;
/// A map below Options::material_map_budget_db is baked larger only by steps that gain at least this much PSNR
/// on a slot short of its target (besides paying for their texels: step_pays).
constexpr double kMinEnlargementGainDb = 0.25;
/// The ideal re-sampler's grid is turned by this angle against the input's texels (BENCHMARKS.md, "Every
/// map"), so that it is not the input's own grid.
constexpr double kIdealRotation = 30.0 * M_PI / 180.0;

/// The slots that read the same input textures the same way: one output map.
struct MapGroup {
  std::vector<MaterialSlot> slots;
  MaterialMapSource source;
};

/// What a triangle without the map reads: a neutral value (white for factors that multiply, black for
/// light and specular colour, the unperturbed normal, mid-grey height).
Rgba8 flat_value(MaterialSlot slot) {
  switch (slot) {
    case MaterialSlot::kEmissive:
    case MaterialSlot::kSpecular:
      return {0, 0, 0, 255};
    case MaterialSlot::kNormal:
    case MaterialSlot::kClearcoatNormal:
      return {128, 128, 255, 255};
    case MaterialSlot::kBump:
    case MaterialSlot::kDisplacement:
      return {128, 128, 128, 255};
    default:
      return {255, 255, 255, 255};
  }
}

const char* encoding_name(SlotEncoding e) {
  return e == SlotEncoding::kSrgbColour ? "srgb_colour" : e == SlotEncoding::kData ? "data" : "tangent_normal";
}

/// Whether two slots' textures per material can be one output image: where both bind a texture it is
/// the same one (a material that binds only one of them leaves the other's texels unread).
bool compatible(const std::vector<int>& a, const std::vector<int>& b) {
  for (size_t m = 0; m < a.size(); ++m)
    if (a[m] >= 0 && b[m] >= 0 && a[m] != b[m]) return false;
  return true;
}

/// The slots some material binds to a loaded texture, grouped into one output image per input image
/// role: slots of one encoding whose textures agree in every material that binds both (glTF's
/// occlusion packed into another material's metallic-roughness image stays one image), in slot order.
std::vector<MapGroup> map_groups(const TexturedMesh& input) {
  std::vector<MapGroup> groups;
  for (size_t s = 0; s < kMaterialSlots; ++s) {
    const MaterialSlot slot = MaterialSlot(s);
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
      return g.source.encoding == slot_encoding(slot) && compatible(g.source.texture_of_material, textures);
    });
    if (same != groups.end()) {
      same->slots.push_back(slot);
      for (size_t m = 0; m < textures.size(); ++m)
        if (textures[m] >= 0) same->source.texture_of_material[m] = textures[m];
      continue;
    }
    MapGroup g;
    g.slots = {slot};
    g.source.encoding = slot_encoding(slot);
    g.source.texture_of_material = std::move(textures);
    g.source.flat = flat_value(slot);
    groups.push_back(std::move(g));
  }
  return groups;
}

/// Whether group `g` reads the base colour's own images (a colour image bound as base colour and as
/// emissive): every material that binds it binds the same image as its base colour, so the new base
/// colour pages are its images too.
bool reads_base_colour(const TexturedMesh& input, const MapGroup& g) {
  if (g.source.encoding != SlotEncoding::kSrgbColour) return false;
  for (size_t m = 0; m < input.materials.size(); ++m)
    if (g.source.texture_of_material[m] >= 0 && g.source.texture_of_material[m] != input.materials[m].texture) return false;
  return true;
}

/// Binds `slots` of every mapped material on new image `page` to output texture `texture`, where its
/// input material binds the slot (nothing a material did not have is bound to it).
void bind_slots(const TexturedMesh& input, const std::vector<MaterialSlot>& slots, int page, int texture, OutputModel& om) {
  for (size_t o = 0; o < om.mapped_materials.size(); ++o) {
    const auto [in_mat, image] = om.mapped_materials[o];
    if (image != page || in_mat < 0) continue;
    for (MaterialSlot s : slots)
      if (input.materials[size_t(in_mat)].maps[size_t(s)] >= 0) om.mesh.materials[o].maps[size_t(s)] = texture;
  }
}

/// The output's tangents: from the new texture coordinates for the mapped triangles (the first
/// om.bake_triangles.size()), the input's own for the kept ones (their texture coordinates are the
/// input's).
void set_output_tangents(const std::vector<Vec4>& input_tangents, OutputModel& om) {
  std::vector<Vec4> tangents = compute_corner_tangents(om.mesh);
  for (size_t o = om.bake_triangles.size(); o < om.mesh.num_triangles(); ++o)
    for (size_t k = 0; k < 3; ++k) tangents[3 * o + k] = input_tangents[3 * size_t(om.mesh.input_triangle[o]) + om.input_corner[3 * o + k]];
  om.mesh.corner_tangent = std::move(tangents);
}

/// Each bake triangle's input and output tangent frames.
std::vector<NormalFrames> normal_frames(const TexturedMesh& input, const std::vector<Vec4>& input_tangents, const OutputModel& om) {
  std::vector<NormalFrames> frames(om.bake_triangles.size());
  tbb::parallel_for(size_t(0), frames.size(), [&](size_t o) {
    const size_t t = om.mesh.input_triangle[o];
    for (size_t k = 0; k < 3; ++k) {
      const int ic = om.input_corner[3 * o + k];
      const Vec4& ti = input_tangents[3 * t + size_t(ic)];
      const Vec4& to = om.mesh.corner_tangent[3 * o + k];
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

/// Squared 8-bit differences per channel (red, green, blue) summed over the judge points that count,
/// and how many counted.
struct ChannelErrors {
  std::array<double, 4> se{0, 0, 0, 0};
  double points = 0;
  /// Mean squared difference over `channels` (0 where nothing counted).
  double mse(unsigned channels) const {
    double sum = 0, n = 0;
    for (int ch = 0; ch < 4; ++ch)
      if (channels & (1u << ch)) sum += se[size_t(ch)], n += points;
    return n > 0 ? sum / n : 0.0;
  }
  /// PSNR over `channels` (99 where nothing differs).
  double psnr(unsigned channels) const {
    const double m = mse(channels);
    return m > 0 ? 10 * std::log10(255.0 * 255.0 / m) : 99.0;
  }
  void add(const std::array<float, 4>& out, const std::array<float, 4>& ref) {
    for (size_t ch = 0; ch < 4; ++ch) {
      const double d = double(out[ch]) - double(ref[ch]);
      se[ch] += d * d;
    }
    points += 1;
  }
};

/// Each page of `images`, by address.
std::vector<const Image*> page_pointers(const std::vector<Image>& images) {
  std::vector<const Image*> pages;
  for (const Image& img : images) pages.push_back(&img);
  return pages;
}

/// The input's map image that judge point p reads and its texture coordinates there, or nullptr.
const Image* input_image_at(const TexturedMesh& input, const MaterialMapSource& map, const BakeTriangle& tri, const JudgePoint& p,
                            Vec2& uv) {
  const int tex =
      tri.material >= 0 && size_t(tri.material) < map.texture_of_material.size() ? map.texture_of_material[size_t(tri.material)] : -1;
  if (tex < 0 || input.textures[size_t(tex)].image.empty()) return nullptr;
  uv = p.b[0] * tri.source_uv[0] + p.b[1] * tri.source_uv[1] + p.b[2] * tri.source_uv[2];
  return &input.textures[size_t(tex)].image;
}

/// The errors of the output map `pages` (the pages `triangles` were laid out on, or those reduced by
/// `reduction`: read back bilinearly at the point's new texture coordinates) against `reference` at the
/// same points: the input's map through the input coordinates, or (`reference_pages` set) the
/// full-size bake.
ChannelErrors judged_errors(const TexturedMesh& input, const MaterialMapSource& map, const std::vector<BakeTriangle>& triangles,
                            const std::vector<JudgePoint>& points, const std::vector<const Image*>& pages,
                            const std::vector<const Image*>* reference_pages, int reduction = 1) {
  ChannelErrors errors;
  for (const JudgePoint& p : points) {
    const BakeTriangle& tri = triangles[p.triangle];
    if (tri.image >= pages.size()) continue;
    const Vec2 px = p.b[0] * tri.target_px[0] + p.b[1] * tri.target_px[1] + p.b[2] * tri.target_px[2];
    // Texture coordinates from the pixel coordinates of the page the triangles were laid out on.
    const double u = px.x() / (double(pages[tri.image]->width) * reduction),
                 v = 1.0 - px.y() / (double(pages[tri.image]->height) * reduction);
    std::array<float, 4> ref;
    if (reference_pages) {
      ref = sample_bilinear(*(*reference_pages)[tri.image], u, v);
    } else {
      Vec2 uv;
      const Image* img = input_image_at(input, map, tri, p, uv);
      if (!img) continue;
      ref = sample_bilinear(*img, uv.x(), uv.y());
    }
    errors.add(sample_bilinear(*pages[tri.image], u, v), ref);
  }
  return errors;
}

/// The ideal re-sampler's value of `img` at uv: each new texel the box average of 4 x 4 bilinear samples
/// over its footprint, on a grid rotated 30 degrees at the image's own texel density, rounded to 8 bits,
/// read back bilinearly. The reference of the maps' check (BENCHMARKS.md, "Every map"); the evaluator,
/// tools/map_eval.cpp, keeps its own copy so that it stays independent of what it checks.
std::array<float, 4> ideal_resample(const Image& img, const Vec2& uv) {
  const Eigen::Rotation2Dd rot(kIdealRotation);
  const Vec2 q = rot.inverse() * Eigen::Vector2d(uv.x() * img.width, (1 - uv.y()) * img.height);  // rotated grid units
  const double gx = q.x() - 0.5, gy = q.y() - 0.5;
  const double fx = std::floor(gx), fy = std::floor(gy), tx = gx - fx, ty = gy - fy;
  std::array<float, 4> out{0, 0, 0, 0};
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const double w = (di ? tx : 1 - tx) * (dj ? ty : 1 - ty);
      std::array<float, 4> texel{0, 0, 0, 0};
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
          const Vec2 x = rot * Eigen::Vector2d(fx + di + (a + 0.5) / 4, fy + dj + (b + 0.5) / 4);
          const auto c = sample_bilinear(img, x.x() / img.width, 1 - x.y() / img.height);
          for (size_t k = 0; k < 4; ++k) texel[k] += c[k] / 16;
        }
      for (size_t k = 0; k < 4; ++k) out[k] += float(w * std::round(texel[k]));
    }
  return out;
}

/// The ideal re-sampler's errors for `map` at the judge points, against the input's map read bilinearly.
ChannelErrors ideal_errors(const TexturedMesh& input, const MaterialMapSource& map, const std::vector<BakeTriangle>& triangles,
                           const std::vector<JudgePoint>& points) {
  std::vector<std::array<float, 4>> ideal(points.size()), exact(points.size());
  std::vector<uint8_t> counts(points.size(), 0);
  tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
    Vec2 uv;
    const Image* img = input_image_at(input, map, triangles[points[i].triangle], points[i], uv);
    if (!img) return;
    ideal[i] = ideal_resample(*img, uv), exact[i] = sample_bilinear(*img, uv.x(), uv.y()), counts[i] = 1;
  });
  ChannelErrors errors;
  for (size_t i = 0; i < points.size(); ++i)
    if (counts[i]) errors.add(ideal[i], exact[i]);
  return errors;
}

/// The largest reduction (a power of two up to kMaxReduction that divides every page's sides) at which
/// each of the map's slots (`slot_channels`), read back at the judge points against the input, loses
/// at most kMaxReductionLossDb of what it had at the base colour's size (`full`): a map is made smaller
/// only where that costs it nothing a viewer would see, however high its PSNR (a mostly black emissive
/// map is high and still loses its lit parts). A normal map (whose new texels are in another frame than
/// the input's) against its full-size bake, at least `min_psnr_db`. Returns the reduction and its errors.
std::pair<int, ChannelErrors> choose_reduction(const TexturedMesh& input, const MaterialMapSource& map,
                                               const std::vector<BakeTriangle>& triangles, const std::vector<JudgePoint>& points,
                                               const std::vector<Image>& full_pages, const std::vector<unsigned>& slot_channels,
                                               const ChannelErrors& full, double min_psnr_db) {
  const bool normal = map.encoding == SlotEncoding::kTangentNormal;
  const std::vector<const Image*> full_size = page_pointers(full_pages);
  int chosen = 1;
  ChannelErrors chosen_errors = full;
  for (int factor = 2; factor <= kMaxReduction; factor *= 2) {
    std::vector<Image> reduced;
    for (const Image& page : full_pages) {
      if (page.width % factor != 0 || page.height % factor != 0) return {chosen, chosen_errors};
      reduced.push_back(reduce_image(page, factor));
    }
    const ChannelErrors errors =
        judged_errors(input, map, triangles, points, page_pointers(reduced), normal ? &full_size : nullptr, factor);
    const bool kept = std::all_of(slot_channels.begin(), slot_channels.end(), [&](unsigned ch) {
      const double psnr = errors.psnr(ch);
      return normal ? psnr >= min_psnr_db : psnr >= full.psnr(ch) - kMaxReductionLossDb;
    });
    if (!kept) break;
    chosen = factor, chosen_errors = errors;
  }
  return {chosen, chosen_errors};
}

/// A map's side over the base colour's: num / den (den divides every page's sides, so that the same
/// texture coordinates address the same point of the larger page).
struct MaterialMapScale {
  int num = 1, den = 1;
  double value() const { return double(num) / den; }
};

/// The pages' bake triangles and rectangles at `scale`: pixel coordinates times the scale, rectangle
/// edges floored. For a scale >= 1 every texel centre inside a chart stays inside its rectangle, and
/// rectangles that did not overlap still do not.
std::pair<std::vector<BakeTriangle>, std::vector<Rect>> scaled_layout(const OutputModel& om, MaterialMapScale scale) {
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
std::vector<MaterialMapScale> enlargements(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om, int max_side) {
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
  std::vector<MaterialMapScale> scales;
  for (int num = den + 1; page_texels > 0; ++num) {
    const MaterialMapScale s{num, den};
    if (s.value() * s.value() * page_texels > input_texels || (max_side > 0 && int64_t(longest_side) * num / den > max_side)) break;
    scales.push_back(s);
  }
  return scales;
}

/// Allocated black pages for a map at `scale` of the base colour's pages.
std::vector<Image> blank_pages(const OutputModel& om, MaterialMapScale scale) {
  std::vector<Image> images;
  for (int p = 0; p < om.new_images; ++p) {
    const Image& colour = om.mesh.textures[size_t(p)].image;
    images.emplace_back(colour.width * scale.num / scale.den, colour.height * scale.num / scale.den, Rgba8{0, 0, 0, 255});
  }
  return images;
}

/// The base colour's figures at the judge points, against which the other maps are sized.
struct BaseColour {
  ChannelErrors baked, ideal;  // the new pages', and the ideal re-sampler's, against the input
  double texels = 0;           // the new pages' texels
  /// The squared error (per channel, in 8-bit levels squared) that the base colour's last texels remove,
  /// per texel: its mean squared error at half its side (box-filtered) less that at its size, over the
  /// three quarters of its texels that halving takes away. 0 where a page side is odd.
  double mse_per_texel = 0;
};

BaseColour base_colour_figures(const TexturedMesh& input, const OutputModel& om, const std::vector<JudgePoint>& points) {
  MaterialMapSource colour;
  for (const Material& m : input.materials) colour.texture_of_material.push_back(m.texture);
  BaseColour b;
  std::vector<const Image*> pages;
  bool even = true;
  for (int p = 0; p < om.new_images; ++p) {
    const Image& page = om.mesh.textures[size_t(p)].image;
    pages.push_back(&page);
    b.texels += double(page.width) * page.height;
    even = even && page.width % 2 == 0 && page.height % 2 == 0;
  }
  b.baked = judged_errors(input, colour, om.bake_triangles, points, pages, nullptr);
  b.ideal = ideal_errors(input, colour, om.bake_triangles, points);
  if (!even || !(b.texels > 0)) return b;
  std::vector<Image> halved;
  for (const Image* page : pages) halved.push_back(reduce_image(*page, 2));
  const ChannelErrors half = judged_errors(input, colour, om.bake_triangles, points, page_pointers(halved), nullptr, 2);
  b.mse_per_texel = std::max(0.0, half.mse(7u) - b.baked.mse(7u)) / (0.75 * b.texels);
  return b;
}

/// What sizing one map needs: its judge points, its slots (the channels each reads) and the PSNR each
/// slot's check asks (slot_targets), the larger scales it may take, and the base colour's figures.
struct Sizing {
  const std::vector<JudgePoint>& points;
  std::vector<unsigned> slot_channels;
  std::vector<double> targets;
  std::vector<MaterialMapScale> scales;
  const BaseColour* base = nullptr;
};

/// Per slot: the PSNR its check asks at the judge points (BENCHMARKS.md, "Every map"): the base
/// colour's, plus the difference that the ideal re-sampler leaves between the slot and the base colour
/// (what a re-sampling at the input's own density keeps of each); at most `budget_db`.
std::vector<double> slot_targets(const BaseColour& base, const ChannelErrors& map_ideal, const std::vector<unsigned>& slot_channels,
                                 double budget_db) {
  std::vector<double> targets;
  for (unsigned ch : slot_channels) targets.push_back(std::min(budget_db, base.baked.psnr(7u) + map_ideal.psnr(ch) - base.ideal.psnr(7u)));
  return targets;
}

/// How far the map with `errors` falls short of its slots' targets: the largest target less PSNR (dB);
/// at most 0 where every slot reaches its target.
double shortfall(const ChannelErrors& errors, const Sizing& z) {
  double worst = -99;
  for (size_t s = 0; s < z.slot_channels.size(); ++s) worst = std::max(worst, z.targets[s] - errors.psnr(z.slot_channels[s]));
  return worst;
}

/// A map baked at `scale` of the base colour's pages, and its errors at the judge points.
struct ScaledBake {
  std::vector<Image> pages;
  MaterialMapScale scale;
  ChannelErrors errors;
};

ScaledBake bake_at(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om, MaterialMapScale scale, const Sizing& z,
                   const BakeOptions& options) {
  auto [triangles, rects] = scaled_layout(om, scale);
  ScaledBake b{blank_pages(om, scale), scale, {}};
  bake_material_map(input, map, triangles, rects, b.pages, nullptr, options);
  b.errors = judged_errors(input, map, triangles, z.points, page_pointers(b.pages), nullptr);
  return b;
}

/// The texels of a map at `scale` of the base colour's pages.
double texels_at(MaterialMapScale scale, const Sizing& z) { return scale.value() * scale.value() * z.base->texels; }

/// Whether growing the map from `from` to `to` pays for its texels: for some slot still short of its
/// target, the step gains at least kMinEnlargementGainDb and removes at least as much squared error per
/// added texel as the base colour's last texels remove (BaseColour::mse_per_texel).
bool step_pays(const ScaledBake& from, const ScaledBake& to, const Sizing& z) {
  const double added = texels_at(to.scale, z) - texels_at(from.scale, z);
  for (size_t s = 0; s < z.slot_channels.size(); ++s) {
    const unsigned ch = z.slot_channels[s];
    if (from.errors.psnr(ch) >= z.targets[s] || to.errors.psnr(ch) < from.errors.psnr(ch) + kMinEnlargementGainDb) continue;
    if ((from.errors.mse(ch) - to.errors.mse(ch)) / added >= z.base->mse_per_texel) return true;
  }
  return false;
}

/// Within a step from `from` to `to` (z.scales[last]) that reaches every target: the scale of
/// z.scales[first, last) where the shortfall, interpolated over log2 of the texels, reaches 0 (rounded
/// up), baked, if that reaches every target; else `to`.
ScaledBake smallest_reaching(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om, const Sizing& z,
                             const BakeOptions& options, const ScaledBake& from, ScaledBake to, size_t first, size_t last) {
  const double before = shortfall(from.errors, z), after = shortfall(to.errors, z);
  const double lo = std::log2(texels_at(from.scale, z)), hi = std::log2(texels_at(to.scale, z));
  const double want = lo + before / (before - after) * (hi - lo);
  size_t j = first;
  while (j < last && std::log2(texels_at(z.scales[j], z)) < want) ++j;
  if (j == last) return to;
  ScaledBake between = bake_at(input, map, om, z.scales[j], z, options);
  return shortfall(between.errors, z) <= 0 ? std::move(between) : std::move(to);
}

/// `best` (the map at the base colour's size, short of its targets) baked larger while each step pays
/// (step_pays), in steps that about double its texels (the smallest of z.scales with twice the texels,
/// else the largest), stopping at the first step that reaches every target (smallest_reaching within
/// it). Returns whether it grew.
bool enlarge(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om, const Sizing& z, const BakeOptions& options,
             ScaledBake& best) {
  bool grew = false;
  for (size_t next = 0; next < z.scales.size();) {
    size_t i = next;
    while (i + 1 < z.scales.size() && texels_at(z.scales[i], z) < 2 * texels_at(best.scale, z)) ++i;
    ScaledBake step = bake_at(input, map, om, z.scales[i], z, options);
    if (!step_pays(best, step, z)) break;
    if (shortfall(step.errors, z) <= 0) {
      best = smallest_reaching(input, map, om, z, options, best, std::move(step), next, i);
      return true;
    }
    best = std::move(step), grew = true, next = i + 1;
  }
  return grew;
}

/// A map baked and sized: its pages and its scale (one of them 1).
struct SizedMap {
  std::vector<Image> pages;
  MaterialMapScale enlarged;
  int reduction = 1;
};

/// The map baked at the base colour's size, then sized by `sizing`'s material_map_budget_db. Where some slot is
/// below it and the budget is tightex's own (TextureBudget::is_default), the map is baked larger (enlarge) while
/// some slot falls short of what its check asks (slot_targets) and the added texels pay for themselves
/// (step_pays), within its input images' texels (enlargements); otherwise it is reduced as far as
/// choose_reduction allows. A normal map (judged against its own full-size bake) is never enlarged.
/// `base` gives the base colour's figures (computed once, on first use).
SizedMap bake_sized_map(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om,
                        const std::vector<unsigned>& slot_channels, const Options& sizing, const BakeOptions& options,
                        const std::vector<JudgePoint>& points, const std::function<const BaseColour&()>& base) {
  const double min_psnr_db = sizing.material_map_budget_db;
  ScaledBake best{blank_pages(om, {}), {}, {}};
  bake_material_map(input, map, om.bake_triangles, om.rects, best.pages, nullptr, options);
  if (!(min_psnr_db > 0)) return {std::move(best.pages), {}, 1};
  const bool normal = map.encoding == SlotEncoding::kTangentNormal;
  if (!normal) best.errors = judged_errors(input, map, om.bake_triangles, points, page_pointers(best.pages), nullptr);
  const bool below =
      std::any_of(slot_channels.begin(), slot_channels.end(), [&](unsigned ch) { return best.errors.psnr(ch) < min_psnr_db; });
  bool grew = false;
  if (!normal && below && om.budget_is_default) {
    Sizing z{points, slot_channels, {}, enlargements(input, map, om, sizing.max_page_side), &base()};
    z.targets = slot_targets(*z.base, ideal_errors(input, map, om.bake_triangles, points), slot_channels, min_psnr_db);
    if (shortfall(best.errors, z) > 0) grew = enlarge(input, map, om, z, options, best);
  }
  SizedMap sized{std::move(best.pages), best.scale, 1};
  if (!grew)
    sized.reduction = choose_reduction(input, map, om.bake_triangles, points, sized.pages, slot_channels, best.errors, min_psnr_db).first;
  return sized;
}

/// The map at `scale` of the base colour's side as an earlier bake sized it (OutputModel::
/// fixed_map_scales): baked larger by that fraction, or at the base colour's size and reduced by its
/// inverse. nullopt where the scale is not one the sizing gives on these pages (a fraction of eighths
/// above 1 whose denominator divides every page side, the inverse of a whole number below): sized anew.
std::optional<SizedMap> bake_fixed_map(const TexturedMesh& input, const MaterialMapSource& map, const OutputModel& om, double scale,
                                       const BakeOptions& options) {
  const int reduction = scale < 1 ? int(std::lround(1 / scale)) : 1;
  MaterialMapScale larger{scale > 1 ? int(std::lround(scale * 8)) : 1, scale > 1 ? 8 : 1};
  while (larger.den > 1 && larger.num % 2 == 0) larger.num /= 2, larger.den /= 2;
  if (std::abs(larger.value() / reduction - scale) > 1e-6) return std::nullopt;
  for (int p = 0; p < om.new_images; ++p)
    if (om.mesh.textures[size_t(p)].image.width % larger.den != 0 || om.mesh.textures[size_t(p)].image.height % larger.den != 0)
      return std::nullopt;
  auto [triangles, rects] = scaled_layout(om, larger);
  SizedMap sized{blank_pages(om, larger), larger, reduction};
  bake_material_map(input, map, triangles, rects, sized.pages, nullptr, options);
  return sized;
}

}  // namespace

std::vector<MaterialMapEntry> bake_material_maps(const TexturedMesh& input, const Options& options, OutputModel& om) {
  std::vector<MapGroup> groups = map_groups(input);
  const bool normal_map =
      std::any_of(groups.begin(), groups.end(), [](const MapGroup& g) { return g.source.encoding == SlotEncoding::kTangentNormal; });
  std::vector<NormalFrames> frames;
  if (normal_map || !input.corner_tangent.empty()) {
    const std::vector<Vec4> input_tangents = completed_corner_tangents(input);
    set_output_tangents(input_tangents, om);
    if (normal_map) frames = normal_frames(input, input_tangents, om);
  }
  if (om.new_images == 0) return {};  // every component kept its input maps (kept_material copies them)
  BakeOptions bo;
  bo.fit = options.fit;
  if (options.fine_fit) bo.fit_samples = kFineFitSamples, bo.fit_lambda = kFineFitLambda;
  // The judge points and the base colour's figures are shared by every map that is sized.
  const std::vector<JudgePoint> points =
      options.material_map_budget_db > 0 && !groups.empty() ? judge_points(om.bake_triangles, kJudgePoints) : std::vector<JudgePoint>{};
  std::optional<BaseColour> base;
  const std::function<const BaseColour&()> base_colour = [&]() -> const BaseColour& {
    if (!base) base = base_colour_figures(input, om, points);
    return *base;
  };
  std::vector<MaterialMapEntry> entries;
  for (MapGroup& g : groups) {
    const auto start = std::chrono::steady_clock::now();
    if (reads_base_colour(input, g)) {  // one image, one bake: the base colour's pages serve its slots too
      for (int p = 0; p < om.new_images; ++p) bind_slots(input, g.slots, p, p, om);
      continue;
    }
    g.source.frames = &frames;
    BakeOptions map_options = bo;
    // A normal map without the fit: the fit would match encoded texels, which a renderer decodes through
    // a frame that turns across the texel; without it the angles are about as good, at a fraction of
    // the time (measured in BENCHMARKS.md, "Every map").
    if (g.source.encoding == SlotEncoding::kTangentNormal) map_options.fit = false;
    std::vector<unsigned> slot_channels;
    for (MaterialSlot s : g.slots) slot_channels.push_back(material_slot_channels(s));
    MaterialMapEntry entry;
    entry.name = material_slot_name(g.slots[0]);
    const auto fixed = om.fixed_map_scales.find(entry.name);
    std::optional<SizedMap> fixed_size =
        fixed == om.fixed_map_scales.end() ? std::nullopt : bake_fixed_map(input, g.source, om, fixed->second, map_options);
    SizedMap sized =
        fixed_size ? std::move(*fixed_size) : bake_sized_map(input, g.source, om, slot_channels, options, map_options, points, base_colour);
    for (MaterialSlot s : g.slots) entry.slots.push_back(material_slot_name(s));
    entry.encoding = encoding_name(g.source.encoding);
    entry.scale = sized.enlarged.value() / sized.reduction;
    for (int p = 0; p < om.new_images; ++p) {
      Texture tex;
      tex.path = om.mesh.textures[size_t(p)].path + "_" + entry.name;
      tex.image = sized.reduction > 1 ? reduce_image(sized.pages[size_t(p)], sized.reduction) : std::move(sized.pages[size_t(p)]);
      entry.sizes.push_back({tex.image.width, tex.image.height});
      bind_slots(input, g.slots, p, int(om.mesh.textures.size()), om);
      om.mesh.textures.push_back(std::move(tex));
    }
    entry.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entries.push_back(std::move(entry));
  }
  return entries;
}

}  // namespace tightex
