#include "run/texture_bytes.hpp"

#include <tbb/parallel_for.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <ranges>

#include "io/gltf_document.hpp"
#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "run/budget_search.hpp"

namespace tightex {

bool answers_better(double target_psnr_db, uint64_t max_bytes, uint64_t bytes_a, double psnr_a, uint64_t bytes_b, double psnr_b) {
  if (target_psnr_db > 0) {
    const bool reach_a = psnr_a >= target_psnr_db, reach_b = psnr_b >= target_psnr_db;
    return reach_a != reach_b ? reach_a : reach_a ? bytes_a < bytes_b : psnr_a > psnr_b;
  }
  const bool fit_a = bytes_a <= max_bytes, fit_b = bytes_b <= max_bytes;
  return fit_a != fit_b ? fit_a : fit_a ? psnr_a > psnr_b : bytes_a < bytes_b;
}

std::vector<char> bound_textures(const TexturedMesh& mesh) {
  std::vector<char> bound(mesh.textures.size(), 0);
  for (const Material& m : mesh.materials) {
    if (m.texture >= 0) bound[size_t(m.texture)] = 1;
    for (const int t : m.maps)
      if (t >= 0) bound[size_t(t)] = 1;
  }
  return bound;
}

int lowest_quality_reaching(const std::function<std::vector<double>(const std::vector<int>&)>& psnr_at, double target, int hint) {
  int lo = 0, hi = 101;        // lo fails (or is 0), hi reaches (or is 101)
  std::map<int, double> psnr;  // every quality measured
  int q = hint > 0 && hint <= 100 ? hint : 75;
  for (;;) {
    std::vector<int> qualities{q};  // and the one below: where q is the answer, that proves it
    if (q - 1 > lo && !psnr.count(q - 1)) qualities.push_back(q - 1);
    const std::vector<double> measured = psnr_at(qualities);
    for (size_t i = 0; i < qualities.size(); ++i) {
      psnr[qualities[i]] = measured[i];
      if (measured[i] >= target)
        hi = std::min(hi, qualities[i]);
      else
        lo = std::max(lo, qualities[i]);
    }
    if (hi - lo <= 1 || lo == 100) return hi;
    const auto at_lo = psnr.find(lo), at_hi = psnr.find(hi);
    int next = (lo + hi) / 2;  // flat: no slope to follow
    if (psnr.size() < 2) {     // one measure (the hint was 1 or 100): a step towards the target
      next = at_hi != psnr.end() ? q - 8 : q + 8;
    } else if (at_lo != psnr.end() && at_hi != psnr.end() && at_hi->second > at_lo->second) {
      // Bracketed: interpolate, rounding towards reaching.
      next = int(std::ceil(lo + (target - at_lo->second) * double(hi - lo) / (at_hi->second - at_lo->second)));
    } else {
      // One side only: the secant through the two measures nearest the other side, a little beyond it.
      const bool reached = at_hi != psnr.end();
      const auto [q1, p1] = reached ? *psnr.begin() : *std::next(psnr.rbegin());
      const auto [q2, p2] = reached ? *std::next(psnr.begin()) : *psnr.rbegin();
      if (std::abs(p2 - p1) > 1e-9) {
        const double at = q1 + (target - p1) * double(q2 - q1) / (p2 - p1);
        next = reached ? int(std::floor(at - 1)) : int(std::ceil(at + 2));
      }
    }
    q = std::clamp(next, lo + 1, std::min(hi - 1, 100));
  }
}

namespace {

/// Rate control's one quality, for every lossy image (JPEG or WebP).
void set_quality(ImageEncoding& e, int quality) { e.jpeg_quality = e.webp_quality = quality; }

uint64_t total(const std::vector<std::string>& images) {
  uint64_t n = 0;
  for (const std::string& b : images) n += b.size();
  return n;
}

/// The surface PSNR (`judge`'s points) of `output` with its base colour images as `images` decode.
double psnr_as_written(const SurfacePsnrOfImages& judge, TexturedMesh& output, const std::vector<std::string>& images) {
  return psnr_as_written(judge, colour_textures(output), output, images);
}

/// The bytes of the input's images that its materials bind (base colour or another map), each once.
uint64_t bound_input_bytes(const TexturedMesh& input, const std::vector<TextureSource>& sources) {
  const std::vector<char> bound = bound_textures(input);
  uint64_t n = 0;
  for (size_t i = 0; i < sources.size() && i < bound.size(); ++i) n += bound[i] ? sources[i].bytes : 0;
  return n;
}

/// The bytes of the lossy images (JPEG, lossy WebP) among `images`, encoded as `e`: the only ones
/// rate control's quality changes.
uint64_t lossy_total(const std::vector<std::string>& images, const ImageEncoding& e) {
  uint64_t n = 0;
  for (size_t i = 0; i < images.size(); ++i) n += e.of_texture(i).lossy() ? images[i].size() : 0;
  return n;
}

/// The bytes of the input's images in the roles (base colour, map slots) that `output`'s lossy images
/// take under `e`, each image once: what the input spent on the images these replace.
uint64_t input_bytes_of_lossy_roles(const TexturedMesh& input, const std::vector<TextureSource>& sources, const TexturedMesh& output,
                                    const ImageEncoding& e) {
  auto lossy = [&](int t) { return t >= 0 && e.of_texture(size_t(t)).lossy(); };
  bool base_colour = false;
  std::vector<char> slot(kMaterialSlots, 0);
  for (const Material& m : output.materials) {
    base_colour = base_colour || lossy(m.texture);
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (m.maps[s] != m.texture && lossy(m.maps[s])) slot[s] = 1;
  }
  std::vector<char> bound(sources.size(), 0);
  for (const Material& m : input.materials) {
    if (base_colour && m.texture >= 0) bound[size_t(m.texture)] = 1;
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (slot[s] && m.maps[s] >= 0) bound[size_t(m.maps[s])] = 1;
  }
  uint64_t n = 0;
  for (size_t i = 0; i < sources.size(); ++i) n += bound[i] ? sources[i].bytes : 0;
  return n;
}

/// The lowest quality in [1, 100] for which `good` holds, where `good` holds from some quality on
/// (bisection, bracketed near `hint` first where one is given); 101 where it holds for none.
int lowest_quality(const std::function<bool(int)>& good, int hint = 0) {
  int lo = 0, hi = 100;          // good(hi), !good(lo) (or lo = 0)
  if (hint > 0 && hint < 100) {  // bracket the answer near the hint first: a few steps, not seven
    constexpr int kNear = 8;
    if (good(hint)) {
      hi = hint, lo = std::max(0, hint - kNear);
      if (lo > 0 && good(lo)) hi = lo, lo = 0;
    } else {
      lo = hint;
    }
  }
  if (hi == 100 && !good(100)) return 101;
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (good(mid) ? hi : lo) = mid;
  }
  return hi;
}

/// Tells request.progress that one more of rate control's encodings (at most 8 a search, then the final
/// one) is starting; a second search (the fallback below) stays at the first's end.
void step(const BytesRequest& request, int& steps) {
  if (request.progress) request.progress(std::min(8.0, double(++steps)) / 9.0);
}

/// Rate control's fallback where even quality 1 takes more than the input's own bytes (`bound`): the
/// lossless images (a PNG base colour or data maps grown with the texel budget) alone outgrow them, and
/// quality 1 would ruin the lossy maps for a bound no quality reaches. Instead, the highest quality
/// whose lossy images take at most the input's images they replace (same roles), as a lossy-only
/// output is bounded; the quality and why.
std::string within_own_roles(const BytesRequest& request, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                             const TexturedMesh& output, ImageEncoding& e, int& steps, uint64_t bound) {
  const uint64_t own = input_bytes_of_lossy_roles(input, sources, output, e);
  const TextureEncoders encoders(output);
  const int over = lowest_quality([&](int quality) {
    step(request, steps);
    set_quality(e, quality);
    return lossy_total(encoders.encode(e, true), e) > own;
  });
  set_quality(e, std::max(over - 1, 1));
  return fmt::format(
      "even quality 1 takes more than the input's own texture bytes ({} bytes), the lossless images being larger: the highest "
      "quality whose lossy images take at most the input's images in their roles ({} bytes){}",
      bound, own, over > 1 ? "" : ", not reached: quality 1");
}

/// The most qualities rate control steps up where its search's points erred against the report's.
constexpr int kMaxStepsUp = 4;

/// Where rate control's search for --target-psnr starts: with the texel search's codec error, the
/// lowest quality at which it and the images' own error (measured unencoded at `few`'s points) meet the
/// target; else request.quality_hint.
int starting_quality(const BytesRequest& request, const SurfacePsnrOfImages& few, const TexturedMesh& output) {
  if (request.codec_mse_by_quality.size() != 101) return request.quality_hint;
  const double room = mse_of_psnr(request.target_psnr_db) - mse_of_psnr(few(output));
  for (int q = 1; q <= 100; ++q)
    if (request.codec_mse_by_quality[size_t(q)] <= room) return q;
  return 100;
}

/// Rate control of a lossy encoding: the quality and why. With --target-psnr, the images chosen and
/// their PSNR at the report's points into `checked`, asked of `judges` (those missing made into it).
std::string pick_quality(const BytesRequest& request, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                         TexturedMesh& output, ImageEncoding& e, std::optional<std::pair<std::vector<std::string>, double>>& checked,
                         PsnrJudges& judges) {
  int steps = 0;
  const TextureEncoders encoders(output);
  if (request.target_psnr_db > 0) {
    // The search at a tenth of the report's points, then the report's own points, a quality up at a
    // time where the few erred.
    if (!judges.few) judges.few = std::make_shared<const SurfacePsnrOfImages>(input, output, kPsnrPoints / 10);
    if (!judges.all) judges.all = std::make_shared<const SurfacePsnrOfImages>(input, output);
    const SurfacePsnrOfImages &few = *judges.few, &judge = *judges.all;
    std::map<int, std::vector<std::string>> images;  // per quality tried, its files
    int lowest = lowest_quality_reaching(
        [&](const std::vector<int>& qualities) {
          // The qualities encoded side by side: a single image's encoder uses one core.
          std::vector<std::vector<std::string>> files(qualities.size());
          tbb::parallel_for(size_t(0), qualities.size(), [&](size_t i) {
            ImageEncoding at = e;
            set_quality(at, qualities[i]);
            files[i] = encoders.encode(at);
          });
          std::vector<double> psnr;
          for (size_t i = 0; i < qualities.size(); ++i) {
            step(request, steps);
            psnr.push_back(psnr_as_written(few, output, files[i]));
            images[qualities[i]] = std::move(files[i]);
          }
          return psnr;
        },
        request.target_psnr_db, starting_quality(request, few, output));
    for (int up = 0; lowest <= 100 && up < kMaxStepsUp; ++up, ++lowest) {
      set_quality(e, lowest);
      std::vector<std::string> images_at = images.count(lowest) ? std::move(images[lowest]) : encoders.encode(e);
      const double psnr = psnr_as_written(judge, output, images_at);
      if (psnr >= request.target_psnr_db) {
        checked.emplace(std::move(images_at), psnr);
        break;
      }
    }
    set_quality(e, std::min(lowest, 100));
    return lowest <= 100 ? fmt::format("the lowest quality whose written images reach --target-psnr {} dB", request.target_psnr_db)
                         : fmt::format("no quality reaches --target-psnr {} dB at this texel budget: the highest", request.target_psnr_db);
  }
  const uint64_t bound = request.max_bytes > 0 ? request.max_bytes : bound_input_bytes(input, sources);
  const char* what = request.max_bytes > 0 ? "--max-bytes" : "the input's own texture bytes";
  if (bound == 0) return "the default quality (no bound: the input's images have no bytes on disk)";
  // The highest quality within the bound: one above the lowest that exceeds it.
  const int over = lowest_quality(
      [&](int quality) {
        step(request, steps);
        set_quality(e, quality);
        return total(encoders.encode(e)) > bound;
      },
      request.quality_hint > 0 ? request.quality_hint + 1 : 0);
  set_quality(e, std::max(over - 1, 1));
  if (over > 1) return fmt::format("the highest quality whose images take at most {} ({} bytes)", what, bound);
  if (request.max_bytes > 0) return fmt::format("even quality 1 takes more than {} ({} bytes): quality 1", what, bound);
  return within_own_roles(request, input, sources, output, e, steps, bound);
}

/// Per texture of `output`, the codec of the input's images in the same role (base colour, or the
/// material map slot its materials bind it to; PNG where the input's differ or none is bound); empty
/// where every texture takes `base`.
std::vector<ImageFormat> codecs_by_role(const TexturedMesh& input, const std::vector<TextureSource>& sources, const TexturedMesh& output,
                                        ImageFormat base) {
  std::vector<ImageFormat> formats(output.textures.size(), base);
  for (const Material& m : output.materials)
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (m.maps[s] >= 0 && m.maps[s] != m.texture)
        formats[size_t(m.maps[s])] = material_map_format(input, sources, MaterialSlot(s)).value_or(ImageFormat::kPng);
  const bool all_base = std::all_of(formats.begin(), formats.end(), [base](ImageFormat f) { return f == base; });
  return all_base ? std::vector<ImageFormat>{} : formats;
}

/// The codecs and why: --format's for every image, else each image its input's.
std::string choose_codecs(const BytesRequest& request, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                          const TexturedMesh& output, ImageEncoding& e) {
  if (request.format) {
    e.format = *request.format;
    return fmt::format("--format {}", to_string(e.format));
  }
  e.format = base_colour_format(input, sources).value_or(ImageFormat::kPng);
  e.formats = codecs_by_role(input, sources, output, e.format);
  std::string reason = fmt::format("{}, as the input's base colour", to_string(e.format));
  if (!e.formats.empty()) reason += "; each other map as the input's map in its slot";
  return reason;
}

/// --target-psnr / --max-bytes with tightex's own texel budget: the texels and quality searched together
/// (budget_search.hpp) for --format's codec, or without it for each lossy codec the output format
/// reads everywhere (request.codecs), the best kept; the output's baked images shrunk to the scale chosen.
EncodingChoice search_codec_texels_and_quality(const BytesRequest& request, const TexturedMesh& input, TexturedMesh& output,
                                               EncodingChoice c) {
  std::vector<ImageFormat> codecs = request.format           ? std::vector<ImageFormat>{*request.format}
                                    : request.codecs.empty() ? std::vector<ImageFormat>{c.encoding.format}
                                                             : request.codecs;
  std::optional<BudgetSearchResult> best;
  ImageEncoding best_encoding;
  PsnrJudges judges = request.judges;  // made by the first codec's search, asked by the next
  for (size_t k = 0; k < codecs.size(); ++k) {
    ImageEncoding e = c.encoding;
    e.format = codecs[k], e.formats.clear();
    BudgetSearchRequest search{request.target_psnr_db, request.max_bytes, request.new_pages, codecs.size() > 1, judges, {}};
    if (request.progress) search.progress = [&](double f) { request.progress((double(k) + f) / double(codecs.size())); };
    BudgetSearchResult r = search_texels_and_quality(search, input, output, e);
    judges = r.judges;
    if (!best || answers_better(request.target_psnr_db, request.max_bytes, total(r.images), r.written_psnr_db, total(best->images),
                                best->written_psnr_db))
      best = std::move(r), best_encoding = e;
  }
  c.encoding = best_encoding;
  c.reason = request.format
                 ? fmt::format("--format {}; {}", to_string(c.encoding.format), best->reason)
                 : fmt::format("{} (the {} that answers best of {}); {}", to_string(c.encoding.format), "codec",
                               fmt::join(codecs | std::views::transform([](ImageFormat f) { return to_string(f); }), ", "), best->reason);
  for (size_t i = 0; i < best->scaled.size(); ++i)
    if (!best->scaled[i].empty()) std::swap(output.textures[i].image, best->scaled[i]);
  c.images = std::move(best->images);
  for (const std::string& b : c.images) c.bytes.push_back(b.size());
  if (!c.images.empty()) c.written_psnr_db = best->written_psnr_db;
  c.probes = std::move(best->probes);
  c.texel_scale = best->scale;
  c.codec_mse_at = std::move(best->codec_mse_at);
  c.bake_error_exponent = best->bake_error_exponent;
  c.judges = std::move(best->judges);
  return c;
}

}  // namespace

EncodingChoice choose_encoding(const BytesRequest& request, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                               TexturedMesh& output) {
  EncodingChoice c;
  c.encoding = request.encoding;
  c.reason = choose_codecs(request, input, sources, output, c.encoding);
  const bool search_texels = request.new_pages > 0 && (request.target_psnr_db > 0 || request.max_bytes > 0) && !request.quality_given;
  if (search_texels && (c.encoding.lossy() || (!request.format && !request.codecs.empty())))
    return search_codec_texels_and_quality(request, input, output, c);
  std::optional<std::pair<std::vector<std::string>, double>> checked;  // the images rate control measured last
  c.judges = request.judges;
  if (c.encoding.lossy() && !request.quality_given)
    c.reason += "; " + pick_quality(request, input, sources, output, c.encoding, checked, c.judges);
  if (request.progress) request.progress(8.0 / 9);
  if (checked) {
    c.images = std::move(checked->first), c.written_psnr_db = checked->second;
  } else {
    c.images = TextureEncoders(output).encode(c.encoding);
    if (c.encoding.lossy() && !c.judges.all) c.judges.all = std::make_shared<const SurfacePsnrOfImages>(input, output);
    if (c.encoding.lossy()) c.written_psnr_db = psnr_as_written(*c.judges.all, output, c.images);
  }
  for (const std::string& b : c.images) c.bytes.push_back(b.size());
  if (request.progress) request.progress(1);
  return c;
}

namespace {

/// Whether a model written as `format` binds `slot` (glTF: its core and KHR_materials_* slots; OBJ: the
/// MTL's map statements; PLY: none); nullopt: the model as read, every slot.
bool holds(std::optional<ModelFormat> format, MaterialSlot slot) {
  if (!format) return true;
  switch (*format) {
    case ModelFormat::kGltf:
    case ModelFormat::kGlb:
      return std::any_of(std::begin(kGltfSlots), std::end(kGltfSlots), [&](const GltfSlot& g) { return g.slot == slot; });
    case ModelFormat::kObj:
      return slot != MaterialSlot::kOcclusion && !(slot >= MaterialSlot::kSpecularStrength && slot <= MaterialSlot::kAnisotropy);
    case ModelFormat::kPly:
      break;
  }
  return false;
}

/// The bytes of a model's images by the slot its materials bind them to (each image once, under its
/// first slot: the base colour first; only slots `format` holds), and in total.
nlohmann::json slot_bytes(const TexturedMesh& mesh, const std::vector<uint64_t>& bytes, std::optional<ModelFormat> format) {
  std::vector<int> slot(mesh.textures.size(), -2);  // -1: base colour, else the MaterialSlot
  for (const Material& m : mesh.materials)
    if (m.texture >= 0) slot[size_t(m.texture)] = -1;
  for (const Material& m : mesh.materials)
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (m.maps[s] >= 0 && slot[size_t(m.maps[s])] == -2 && holds(format, MaterialSlot(s))) slot[size_t(m.maps[s])] = int(s);
  nlohmann::json j = {{"base_colour", 0}, {"maps", nlohmann::json::object()}, {"total", 0}};
  for (size_t i = 0; i < slot.size() && i < bytes.size(); ++i) {
    if (slot[i] == -2) continue;
    if (slot[i] == -1)
      j["base_colour"] = j["base_colour"].get<uint64_t>() + bytes[i];
    else
      j["maps"][material_slot_name(MaterialSlot(slot[i]))] =
          j["maps"].value(material_slot_name(MaterialSlot(slot[i])), uint64_t(0)) + bytes[i];
    j["total"] = j["total"].get<uint64_t>() + bytes[i];
  }
  return j;
}

/// The quality a lossy codec wrote texture i at; nullopt for a lossless one.
std::optional<int> quality_of(const ImageEncoding& e, size_t i) {
  const ImageEncoding t = e.of_texture(i);
  if (t.format == ImageFormat::kJpeg) return t.jpeg_quality;
  if (t.format == ImageFormat::kWebp && !t.webp_lossless) return t.webp_quality;
  return std::nullopt;
}

/// report.json's "bytes"."images": every image the output's file binds, once: its file name, size, the
/// slots that bind it, codec, quality (lossy codecs), bytes, and the written PSNR of what it shows (the
/// surface PSNR for a base colour page, the slot's figure for a map: docs/metrics.md).
nlohmann::json written_images(const TexturedMesh& output, const EncodingChoice& choice, const Metrics& written, ModelFormat format) {
  std::vector<std::vector<std::string>> slots(output.textures.size());
  auto bind = [&](int tex, const char* slot) {
    if (tex >= 0 && std::find(slots[size_t(tex)].begin(), slots[size_t(tex)].end(), slot) == slots[size_t(tex)].end())
      slots[size_t(tex)].push_back(slot);
  };
  for (const Material& m : output.materials) {
    bind(m.texture, "base_colour");
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (holds(format, MaterialSlot(s))) bind(m.maps[s], material_slot_name(MaterialSlot(s)));
  }
  auto figure = [&](const std::string& slot) -> nlohmann::json {
    if (slot == "base_colour") return written.surface_psnr;
    for (const MaterialMapFigures& f : written.maps)
      if (slot == material_slot_name(f.slot))
        return f.angle_median >= 0 ? nlohmann::json{{"angle_median_deg", f.angle_median}} : nlohmann::json(f.surface_psnr);
    return nullptr;
  };
  nlohmann::json images = nlohmann::json::array();
  for (size_t i = 0; i < slots.size(); ++i) {
    if (slots[i].empty() || output.textures[i].image.empty()) continue;
    const ImageFormat codec = choice.encoding.of_texture(i).format;
    nlohmann::json figures = nlohmann::json::object();
    for (const std::string& slot : slots[i]) figures[slot] = figure(slot);
    nlohmann::json image = {{"file", output.textures[i].path + image_extension(codec)},
                            {"width", output.textures[i].image.width},
                            {"height", output.textures[i].image.height},
                            {"slots", slots[i]},
                            {"codec", to_string(codec)},
                            {"bytes", i < choice.bytes.size() ? choice.bytes[i] : 0},
                            {"written_psnr_db", figures}};
    if (const auto q = quality_of(choice.encoding, i)) image["quality"] = *q;
    images.push_back(std::move(image));
  }
  return images;
}

}  // namespace

nlohmann::json bytes_json(const TexturedMesh& input, const std::vector<TextureSource>& sources, const TexturedMesh& output,
                          const EncodingChoice& choice, const Metrics& written, ModelFormat format) {
  const double written_psnr_db = written.surface_psnr;
  std::vector<uint64_t> in_bytes;
  for (const TextureSource& s : sources) in_bytes.push_back(s.bytes);
  const ImageEncoding& e = choice.encoding;
  nlohmann::json encoding = {{"format", to_string(e.format)}, {"reason", choice.reason}};
  if (!e.formats.empty()) {
    encoding["per_image"] = nlohmann::json::array();
    for (const ImageFormat f : e.formats) encoding["per_image"].push_back(to_string(f));
  }
  const bool jpeg = e.format == ImageFormat::kJpeg || std::count(e.formats.begin(), e.formats.end(), ImageFormat::kJpeg) > 0;
  if (jpeg) encoding["quality"] = e.jpeg_quality;
  if (e.format == ImageFormat::kWebp)
    encoding[e.webp_lossless ? "lossless" : "quality"] = e.webp_lossless ? nlohmann::json(true) : nlohmann::json(e.webp_quality);
  return {{"input", slot_bytes(input, in_bytes, std::nullopt)},
          {"output", slot_bytes(output, choice.bytes, format)},
          {"images", written_images(output, choice, written, format)},
          {"encoding", encoding},
          {"surface_psnr_written_db", written_psnr_db}};
}

}  // namespace tightex
