#include "run/budget_search.hpp"

#include <tbb/parallel_for.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <optional>
#include <tuple>

#include "core/raster.hpp"
#include "io/image_io.hpp"
#include "layout/layout.hpp"
#include "report/metrics.hpp"

namespace tightex {

namespace {

/// The scales of the baked images' sides the search encodes (texels: 1/16, 1/4 and 1 of the bake's),
/// the cheap ones first; between them the model interpolates over log scale, to kSteps steps a halving.
constexpr double kProbeScales[] = {0.25, 0.5, 1.0};
/// Where the charts are baked again at the scale chosen (BudgetSearchRequest::check_shrunk
/// false), a model of the two smaller probes alone that chooses at most this scale, or the full size,
/// is kept: the probes at full size (the costliest, every map included) would not move a choice that
/// far from it by much, and the quality search on the images as written (the re-bake's, or the
/// checks at full size) corrects the rest.
constexpr double kLargestScaleWithoutFullProbes = 0.75;
constexpr int kSteps = 4;
/// The qualities each probed scale is encoded at; between them the model interpolates.
constexpr int kProbeQualities[] = {50, 75, 88, 96};
/// The lowest quality the model chooses: below the lowest probe it extrapolates, and not far.
constexpr int kLowestQuality = kProbeQualities[0] - 10;
/// The probes' surface PSNR points: the same points for every probe, a tenth of the report's.
constexpr size_t kProbePoints = kPsnrPoints / 10;
/// How far above --target-psnr the model aims, for the probes' points are not the report's.
constexpr double kTargetMarginDb = 0.05;
/// The most encodings the check of the model's choice makes on the images as written.
constexpr int kMaxChecks = 5;

/// Per texture of `output`, whether the bake made it: the first `new_pages` and every map of a material
/// that binds one of them as its base colour.
std::vector<char> baked_textures(const TexturedMesh& output, size_t new_pages) {
  std::vector<char> baked(output.textures.size(), 0);
  for (size_t i = 0; i < new_pages && i < baked.size(); ++i) baked[i] = 1;
  for (const Material& m : output.materials)
    if (m.texture >= 0 && size_t(m.texture) < new_pages)
      for (const int t : m.maps)
        if (t >= 0) baked[size_t(t)] = 1;
  return baked;
}

/// Per baked texture, the texels whose centres a triangle that reads it covers (empty for the others).
std::vector<std::vector<uint8_t>> chart_texels(const TexturedMesh& output, const std::vector<char>& baked) {
  std::vector<std::vector<uint8_t>> inside(output.textures.size());
  for (size_t i = 0; i < inside.size(); ++i)
    if (baked[i]) inside[i].assign(size_t(output.textures[i].image.width) * size_t(output.textures[i].image.height), 0);
  auto cover = [&](size_t t, int tex) {
    if (tex < 0 || !baked[size_t(tex)]) return;
    const Image& img = output.textures[size_t(tex)].image;
    Vec2 px[3];
    for (int k = 0; k < 3; ++k) px[k] = Vec2(output.sampled_uv(t, k).x() * img.width, (1 - output.sampled_uv(t, k).y()) * img.height);
    scan_triangle(px[0], px[1], px[2], 0, img.width, 0, img.height, EdgeRule::kInclusive,
                  [&](long x, long y, double, double, double) { inside[size_t(tex)][size_t(y) * size_t(img.width) + size_t(x)] = 1; });
  };
  for (size_t t = 0; t < output.num_triangles(); ++t) {
    const int32_t mat = output.face_material[t];
    if (mat < 0) continue;
    const Material& m = output.materials[size_t(mat)];
    cover(t, m.texture);
    for (const int tex : m.maps)
      if (tex != m.texture) cover(t, tex);
  }
  return inside;
}

/// The baked images of `output` at `scale` (empty where a texture is not baked, or at scale 1).
std::vector<Image> images_at(const TexturedMesh& output, const std::vector<char>& baked, const std::vector<std::vector<uint8_t>>& inside,
                             double scale) {
  std::vector<Image> scaled(output.textures.size());
  if (scale >= 1) return scaled;
  for (size_t i = 0; i < scaled.size(); ++i) {
    const Image& img = output.textures[i].image;
    if (baked[i] && !img.empty())
      scaled[i] = shrink_image(img, inside[i], texture_side_at(img.width, scale), texture_side_at(img.height, scale));
  }
  return scaled;
}

uint64_t total_bytes(const std::vector<std::string>& files) {
  return std::accumulate(files.begin(), files.end(), uint64_t(0), [](uint64_t n, const std::string& f) { return n + f.size(); });
}

/// A mean squared error as the surface PSNR it stands for (mse_of_psnr the other way).
double psnr_of(double mse) { return 10 * std::log10(255.0 * 255.0 / std::max(mse, 1e-12)); }

/// One probed scale's codec error (the log of the written images' MSE less the unencoded images' at
/// that scale) and log bytes, at kProbeQualities.
struct ScaleCurve {
  double scale = 1;
  std::vector<double> log_codec_mse, log_bytes;
};

/// The model of the surface PSNR and bytes over (scale, quality): the error of the images shrunk to each
/// of `scales` (measured, unencoded) plus the codec's, which with the bytes is interpolated from the
/// probes (piecewise linear over the quality, the quadratic through the probed scales over log scale).
struct RateModel {
  std::vector<double> scales, shrink_mse;
  std::vector<ScaleCurve> probes;  // per probed scale, in kProbeScales' order
};

/// The value at quality q of the piecewise-linear curve through (kProbeQualities, y), extended along
/// its end segments.
double at_quality(const std::vector<double>& y, int q) {
  const size_t n = std::size(kProbeQualities);
  size_t i = 0;
  while (i + 2 < n && q > kProbeQualities[i + 1]) ++i;
  const double t = double(q - kProbeQualities[i]) / double(kProbeQualities[i + 1] - kProbeQualities[i]);
  return y[i] + t * (y[i + 1] - y[i]);
}

/// The model's PSNR and log bytes at (model.scales[s], q), and its codec error (mean squared).
struct Prediction {
  double psnr = 0, log_bytes = 0, codec_mse = 0;
};
/// The probes' log codec error and log bytes interpolated over log scale (extrapolated beyond them) to
/// `scale` of the bake's side, at quality q.
std::pair<double, double> log_codec_mse_and_bytes(const RateModel& model, double scale, int q) {
  const double x = std::log(scale);
  double log_codec_mse = 0, log_bytes = 0;
  for (size_t i = 0; i < model.probes.size(); ++i) {
    double w = 1;  // Lagrange's weight of probe i at x
    for (size_t j = 0; j < model.probes.size(); ++j)
      if (j != i) w *= (x - std::log(model.probes[j].scale)) / (std::log(model.probes[i].scale) - std::log(model.probes[j].scale));
    log_codec_mse += w * at_quality(model.probes[i].log_codec_mse, q), log_bytes += w * at_quality(model.probes[i].log_bytes, q);
  }
  return {log_codec_mse, log_bytes};
}

Prediction predict(const RateModel& model, size_t s, int q) {
  const auto [log_codec_mse, log_bytes] = log_codec_mse_and_bytes(model, model.scales[s], q);
  return {psnr_of(model.shrink_mse[s] + std::exp(log_codec_mse)), log_bytes, std::exp(log_codec_mse)};
}

/// The scales the model chooses from: kSteps a halving, from 1 down to the smallest probed.
std::vector<double> model_scales() {
  std::vector<double> scales;
  for (int i = 0; std::pow(2.0, -double(i) / kSteps) >= kProbeScales[0] - 1e-9; ++i) scales.push_back(std::pow(2.0, -double(i) / kSteps));
  return scales;
}

/// The model's (scale index, quality) for the request: the fewest predicted bytes whose predicted PSNR
/// reaches the target, or the most predicted PSNR within the bytes; where none does, the closest.
std::pair<size_t, int> model_choice(const BudgetSearchRequest& request, const RateModel& model) {
  std::pair<size_t, int> best{0, 100};
  double best_score = -1e300;
  for (size_t s = 0; s < model.scales.size(); ++s) {
    double running_psnr = -1e300;  // PSNR never falls as the quality rises
    for (int q = kLowestQuality; q <= 100; ++q) {
      const auto [psnr, log_bytes, codec_mse] = predict(model, s, q);
      running_psnr = std::max(running_psnr, psnr);
      double score = 0;
      if (request.target_psnr_db > 0)
        score = running_psnr >= request.target_psnr_db + kTargetMarginDb ? 1e6 - log_bytes : running_psnr - 1e6;
      else
        score = log_bytes <= std::log(double(request.max_bytes)) ? 1e6 + running_psnr : -log_bytes;
      if (score > best_score) best_score = score, best = {s, q};
    }
  }
  return best;
}

/// Whether the images as written answer the request (the PSNR reached, or the bytes within the bound).
bool answers(const BudgetSearchRequest& request, double psnr, uint64_t bytes) {
  return request.target_psnr_db > 0 ? psnr >= request.target_psnr_db : bytes <= request.max_bytes;
}

/// The images of `output` at `scale` swapped in (and, called again, back).
void swap_in(TexturedMesh& output, std::vector<Image>& scaled) {
  for (size_t i = 0; i < scaled.size(); ++i)
    if (!scaled[i].empty()) std::swap(output.textures[i].image, scaled[i]);
}

/// What the rate model is fitted from: `judge`'s points, the baked textures and which of them are base
/// colour, and the chart texels of each.
struct ProbeContext {
  const BudgetSearchRequest& request;
  const SurfacePsnrOfImages& judge;
  const std::vector<char>&baked, &colour;
  const std::vector<std::vector<uint8_t>>& inside;
  const ImageEncoding& encoding;
};

/// The rate model (RateModel) of `output` without probes yet: every model scale's base colour images
/// measured unencoded (the surface PSNR reads the base colour alone).
RateModel shrink_model(const ProbeContext& c, TexturedMesh& output) {
  RateModel model;
  model.scales = model_scales();
  std::vector<char> baked_colour(c.baked.size());
  for (size_t i = 0; i < c.baked.size(); ++i) baked_colour[i] = c.baked[i] && c.colour[i];
  for (const double scale : model.scales) {
    std::vector<Image> scaled = images_at(output, baked_colour, c.inside, scale);
    swap_in(output, scaled);
    model.shrink_mse.push_back(mse_of_psnr(c.judge(output)));
    swap_in(output, scaled);
  }
  return model;
}

/// Adds to `model` the probes at `scale`: every baked image at that scale encoded at kProbeQualities
/// and measured; each into `probes`.
void add_probes(const ProbeContext& c, double scale, TexturedMesh& output, RateModel& model, nlohmann::json& probes) {
  if (c.request.progress) c.request.progress(0.8 * double(model.probes.size()) / double(std::size(kProbeScales)));
  std::vector<Image> scaled = images_at(output, c.baked, c.inside, scale);
  const TextureEncoders encoders(output, scaled);
  std::vector<std::vector<std::string>> files(std::size(kProbeQualities));
  tbb::parallel_for(size_t(0), files.size(), [&](size_t k) {
    ImageEncoding e = c.encoding;
    e.jpeg_quality = e.webp_quality = kProbeQualities[k];
    files[k] = encoders.encode(e);
  });
  const size_t s = size_t(std::find_if(model.scales.begin(), model.scales.end(), [&](double x) { return std::abs(x - scale) < 1e-9; }) -
                          model.scales.begin());
  ScaleCurve curve{scale, {}, {}};
  swap_in(output, scaled);
  for (size_t k = 0; k < files.size(); ++k) {
    const double psnr = psnr_as_written(c.judge, c.colour, output, files[k]), mse = mse_of_psnr(psnr);
    curve.log_codec_mse.push_back(std::log(std::max(mse - model.shrink_mse[s], 1e-3 * mse)));
    curve.log_bytes.push_back(std::log(double(std::max<uint64_t>(1, total_bytes(files[k])))));
    probes.push_back({{"scale", scale}, {"quality", kProbeQualities[k]}, {"bytes", total_bytes(files[k])}, {"psnr_db", psnr}});
  }
  swap_in(output, scaled);
  model.probes.push_back(std::move(curve));
}

/// Whether no scale below the bake's reaches --target-psnr even unencoded: the texels are kept, and the
/// full-size probes would only tell the quality, which the checks on the images as written find.
bool only_full_size_reaches(const BudgetSearchRequest& request, const RateModel& model) {
  if (!(request.target_psnr_db > 0)) return false;
  for (size_t s = 1; s < model.scales.size(); ++s)
    if (psnr_of(model.shrink_mse[s]) >= request.target_psnr_db + kTargetMarginDb) return false;
  return true;
}

/// The rate model of `output` and its choice (model_choice): the shrink measured, then the probes
/// scale by scale from the smallest; the full-size probes are left out where the caller re-bakes at
/// the scale chosen and the smaller probes alone choose the full size or at most
/// kLargestScaleWithoutFullProbes, and where only the full size reaches the target
/// (only_full_size_reaches).
std::pair<RateModel, std::pair<size_t, int>> fit_and_choose(const ProbeContext& c, TexturedMesh& output, nlohmann::json& probes) {
  RateModel model = shrink_model(c, output);
  std::pair<size_t, int> choice{0, 100};
  for (const double scale : kProbeScales) {
    if (!c.request.check_shrunk && model.probes.size() >= 2 &&
        (choice.first == 0 || model.scales[choice.first] <= kLargestScaleWithoutFullProbes))
      break;
    if (model.probes.size() >= 2 && only_full_size_reaches(c.request, model)) break;  // the checks find its quality
    add_probes(c, scale, output, model, probes);
    if (model.probes.size() >= 2) choice = model_choice(c.request, model);
  }
  return {std::move(model), choice};
}

/// The quality the model, corrected by what the last check measured (`psnr_offset`, `log_bytes_offset`:
/// measured less predicted), says answers the request at `scale` with the fewest bytes (a target) or
/// the most PSNR (a bound); within (lo, hi), the qualities not yet known to fail or to answer worse.
int corrected_quality(const BudgetSearchRequest& request, const RateModel& model, size_t scale, double psnr_offset, double log_bytes_offset,
                      int lo, int hi) {
  if (request.target_psnr_db > 0) {
    for (int q = std::max(lo + 1, kLowestQuality - 10); q < hi; ++q)
      if (predict(model, scale, q).psnr + psnr_offset >= request.target_psnr_db + kTargetMarginDb) return q;
    return hi - 1;
  }
  for (int q = hi - 1; q > lo; --q)
    if (predict(model, scale, q).log_bytes + log_bytes_offset <= std::log(double(request.max_bytes))) return q;
  return lo + 1;
}

/// Images written at one quality, and their surface PSNR as written.
struct Written {
  int quality = 0;
  std::vector<std::string> images;
  double psnr = 0;
};

/// Between a quality `lo` that misses a target (`psnr_lo`) and one `hi` that reaches it, the quality the
/// line through both reaches it at, rounded up: the checks, as written, say more there than the
/// model, whose quality curve is smoother than the codec's.
int bracketed_quality(int lo, double psnr_lo, int hi, double psnr_hi, double target) {
  const double at = lo + (target - psnr_lo) * double(hi - lo) / (psnr_hi - psnr_lo);
  return std::clamp(int(std::ceil(at)), lo + 1, hi - 1);
}

/// The model's choice at scale index s, starting at quality q: checked on the images as written
/// (`output` holds them at that scale) at `judge`'s points and moved along the quality by the model,
/// corrected by each check (for a target, once a missing and a reaching quality are measured, by the
/// line between them: bracketed_quality), to the best quality that answers the request, at most kMaxChecks
/// encodings. Returns the best that answers it, else the closest; each check into `probes`.
std::pair<std::optional<Written>, Written> check_qualities(const BudgetSearchRequest& request, const RateModel& model, size_t s, int q,
                                                           const SurfacePsnrOfImages& judge, const std::vector<char>& colour,
                                                           ImageEncoding& encoding, TexturedMesh& output, nlohmann::json& probes) {
  // Known so far: every quality <= lo is too low (a target) or within the bound; every quality >= hi
  // reaches the target or is over the bound.
  const bool target = request.target_psnr_db > 0;
  int lo = 0, hi = 101;
  std::map<int, double> measured;  // a target's PSNR per quality checked
  std::optional<Written> best, closest;
  const TextureEncoders encoders(output);
  for (int check = 0; check < kMaxChecks; ++check) {
    if (request.progress) request.progress(0.8 + 0.2 * check / kMaxChecks);
    // q, and beside it the quality that would prove q the answer (one below a target's, one above a
    // bound's), encoded side by side: a single image's encoder uses one core.
    std::vector<Written> written{Written{q, {}, 0}};
    const int proof = target ? q - 1 : q + 1;
    if (proof > lo && proof < hi) written.push_back(Written{proof, {}, 0});
    tbb::parallel_for(size_t(0), written.size(), [&](size_t i) {
      ImageEncoding e = encoding;
      e.jpeg_quality = e.webp_quality = written[i].quality;
      written[i].images = encoders.encode(e);
    });
    for (Written& w : written) {
      // q not answering (a target missed, a bound exceeded): neither does its proof, left unmeasured.
      if (&w != &written[0] && !answers(request, written[0].psnr, total_bytes(written[0].images))) break;
      w.psnr = psnr_as_written(judge, colour, output, w.images);
      const uint64_t bytes = total_bytes(w.images);
      probes.push_back({{"scale", model.scales[s]}, {"quality", w.quality}, {"bytes", bytes}, {"psnr_db", w.psnr}, {"check", true}});
      measured[w.quality] = w.psnr;
      const bool ok = answers(request, w.psnr, bytes);
      // A target reached or a bound exceeded: so is every higher quality.
      if (target == ok)
        hi = std::min(hi, w.quality);
      else
        lo = std::max(lo, w.quality);
      if (ok && (!best || (target ? w.quality < best->quality : w.quality > best->quality))) best = w;
      if (!ok && (!closest || (target ? w.psnr > closest->psnr : w.quality < closest->quality))) closest = w;
    }
    const auto [psnr, log_bytes, codec_mse] = predict(model, s, q);
    const uint64_t bytes = total_bytes(written[0].images);
    const double log_bytes_offset = std::log(double(std::max<uint64_t>(bytes, 1))) - log_bytes;
    int next = hi - lo <= 1 ? q : corrected_quality(request, model, s, written[0].psnr - psnr, log_bytes_offset, lo, hi);
    if (target && hi - lo > 1 && measured.count(lo) && measured.count(hi) && measured[hi] > measured[lo])
      next = bracketed_quality(lo, measured[lo], hi, measured[hi], request.target_psnr_db);
    if (next == q || next <= lo || next >= hi) break;
    q = next;
  }
  return {std::move(best), best ? Written{} : std::move(*closest)};
}

/// The model's codec error at any scale and quality (BudgetSearchResult::codec_mse_at), times `factor`.
std::function<double(double, int)> codec_mse_curve(const RateModel& model, double factor) {
  return [model, factor](double scale, int quality) { return factor * std::exp(log_codec_mse_and_bytes(model, scale, quality).first); };
}

/// What `checked` (the images at the bake's size as written) measured of the codec's error over what the
/// model predicts there.
double checked_over_predicted(const RateModel& model, const Written& checked) {
  const double written = mse_of_psnr(checked.psnr);
  return std::max(written - model.shrink_mse[0], 1e-3 * written) / predict(model, 0, checked.quality).codec_mse;
}

}  // namespace

TextureEncoders::TextureEncoders(const TexturedMesh& mesh, const std::vector<Image>& replaced, const std::vector<char>& only)
    : encoders_(mesh.textures.size()) {
  for (size_t i = 0; i < encoders_.size(); ++i) {
    const Image& img = i < replaced.size() && !replaced[i].empty() ? replaced[i] : mesh.textures[i].image;
    if (!img.empty() && (only.empty() || only[i])) encoders_[i] = std::make_unique<ImageEncoder>(img, mesh.textures[i].path);
  }
}

std::vector<std::string> TextureEncoders::encode(const ImageEncoding& encoding, bool lossy_only) const {
  std::vector<std::string> files(encoders_.size());
  tbb::parallel_for(size_t(0), files.size(), [&](size_t i) {
    if (encoders_[i] && (!lossy_only || encoding.of_texture(i).lossy())) files[i] = encoders_[i]->encode(encoding.of_texture(i));
  });
  return files;
}

std::vector<char> colour_textures(const TexturedMesh& output) {
  std::vector<char> colour(output.textures.size(), 0);
  for (const Material& m : output.materials)
    if (m.texture >= 0) colour[size_t(m.texture)] = 1;
  return colour;
}

double mse_of_psnr(double psnr) { return 255.0 * 255.0 * std::pow(10.0, -psnr / 10); }

double psnr_as_written(const SurfacePsnrOfImages& judge, const std::vector<char>& colour, TexturedMesh& output,
                       const std::vector<std::string>& files) {
  std::vector<Image> decoded(files.size());
  tbb::parallel_for(size_t(0), files.size(), [&](size_t i) {
    if (!files[i].empty() && colour[i])
      decoded[i] = decode_image(reinterpret_cast<const unsigned char*>(files[i].data()), files[i].size(), output.textures[i].path);
  });
  for (size_t i = 0; i < decoded.size(); ++i)
    if (!decoded[i].empty()) std::swap(output.textures[i].image, decoded[i]);
  const double psnr = judge(output);
  for (size_t i = 0; i < decoded.size(); ++i)
    if (!decoded[i].empty()) std::swap(output.textures[i].image, decoded[i]);
  return psnr;
}

BudgetSearchResult search_texels_and_quality(const BudgetSearchRequest& request, const TexturedMesh& input, TexturedMesh& output,
                                             ImageEncoding& encoding) {
  const std::vector<char> baked = baked_textures(output, request.new_pages);
  const std::vector<char> colour = colour_textures(output);
  const std::vector<std::vector<uint8_t>> inside = chart_texels(output, baked);
  BudgetSearchResult r;
  r.judges = request.judges;
  if (!r.judges.few) r.judges.few = std::make_shared<const SurfacePsnrOfImages>(input, output, kProbePoints);
  const SurfacePsnrOfImages& few = *r.judges.few;
  const auto [model, choice] = fit_and_choose(ProbeContext{request, few, baked, colour, inside, encoding}, output, r.probes);
  const auto half = std::find_if(model.scales.begin(), model.scales.end(), [](double x) { return std::abs(x - 0.5) < 1e-9; });
  if (half != model.scales.end() && model.shrink_mse[0] > 0)
    r.bake_error_exponent = std::log2(model.shrink_mse[size_t(half - model.scales.begin())] / model.shrink_mse[0]);
  // The model's choice, checked; where no quality at its scale reaches a target, the bake's own size.
  auto [s, q] = choice;
  const std::string asked = request.target_psnr_db > 0 ? fmt::format("--target-psnr {} dB", request.target_psnr_db)
                                                       : fmt::format("--max-bytes {}", request.max_bytes);
  if (!request.check_shrunk && s > 0) {
    r.scale = model.scales[s], r.quality = q;
    encoding.jpeg_quality = encoding.webp_quality = q;
    r.codec_mse_at = codec_mse_curve(model, 1);
    r.reason = fmt::format("texels and quality chosen together for {}: the model's {:.2f} of the side at quality {}", asked, r.scale, q);
    return r;
  }
  if (!r.judges.all) r.judges.all = std::make_shared<const SurfacePsnrOfImages>(input, output, kPsnrPoints);
  const SurfacePsnrOfImages& judge = *r.judges.all;
  std::optional<Written> best;
  Written closest;
  for (;;) {
    r.scale = model.scales[s];
    r.scaled = images_at(output, baked, inside, r.scale);
    swap_in(output, r.scaled);
    std::tie(best, closest) = check_qualities(request, model, s, q, judge, colour, encoding, output, r.probes);
    swap_in(output, r.scaled);
    if (best || request.target_psnr_db <= 0 || s == 0) break;
    s = 0, q = std::max(closest.quality, kProbeQualities[std::size(kProbeQualities) - 2]);
  }
  const Written& chosen = best ? *best : closest;
  if (!best && request.target_psnr_db > 0 && s == 0) r.codec_mse_at = codec_mse_curve(model, checked_over_predicted(model, chosen));
  encoding.jpeg_quality = encoding.webp_quality = chosen.quality;
  r.quality = chosen.quality, r.images = chosen.images, r.written_psnr_db = chosen.psnr;
  const Image& img = r.scaled.empty() || r.scaled[0].empty() ? output.textures[0].image : r.scaled[0];
  r.reason = fmt::format(
      "texels and quality chosen together for {}: the baked images at {:.2f} of their side ({}x{}), quality {} ({} bytes, {:.2f} dB as "
      "written){}",
      asked, r.scale, img.width, img.height, r.quality, total_bytes(r.images), r.written_psnr_db,
      best ? "" : "; no quality checked answers it: the closest");
  if (request.progress) request.progress(1);
  return r;
}

namespace {

/// Along one side of `source` texels shrunk to `target`, per output texel the source texels its side
/// covers: [first, first + count), each covering weights[offset + i] of a texel.
struct Footprints {
  struct Span {
    int first = 0, count = 0;
    size_t offset = 0;
  };
  std::vector<Span> spans;
  std::vector<double> weights;

  Footprints(int source, int target) : spans(static_cast<size_t>(target)) {
    const double f = double(source) / target;
    for (int x = 0; x < target; ++x) {
      const double x0 = x * f, x1 = (x + 1) * f;
      Span& span = spans[size_t(x)];
      span.first = int(x0), span.offset = weights.size();
      for (int sx = span.first; sx < std::min(source, int(std::ceil(x1))); ++sx, ++span.count)
        weights.push_back(std::min(x1, sx + 1.0) - std::max(x0, double(sx)));
    }
  }
};

/// Adds to `sum` the texels of `image` under the spans `x` (of `columns`) and `y` (of `rows`), each
/// weighted by how much of it they cover: those `inside` marks, or all where `only_inside` is false.
/// Returns the weights' sum.
double add_footprint(const Image& image, const std::vector<uint8_t>& inside, bool only_inside, const Footprints& columns, size_t x,
                     const Footprints& rows, size_t y, double (&sum)[4]) {
  const Footprints::Span &fx = columns.spans[x], &fy = rows.spans[y];
  double wsum = 0;
  for (int j = 0; j < fy.count; ++j) {
    const size_t at = size_t(fy.first + j) * size_t(image.width) + size_t(fx.first);
    const Rgba8* p = image.pixels.data() + at;
    const uint8_t* in = inside.empty() ? nullptr : inside.data() + at;
    for (int i = 0; i < fx.count; ++i) {
      if (only_inside && (!in || !in[i])) continue;
      const double w = rows.weights[fy.offset + size_t(j)] * columns.weights[fx.offset + size_t(i)];
      sum[0] += w * p[i].r, sum[1] += w * p[i].g, sum[2] += w * p[i].b, sum[3] += w * p[i].a;
      wsum += w;
    }
  }
  return wsum;
}

/// std::lround of a level in [0, 255], inline: the part below the whole is exact in a double.
uint8_t round_level(double v) {
  const long whole = long(v);
  return uint8_t(std::clamp(whole + (v - double(whole) >= 0.5 ? 1l : 0l), 0l, 255l));
}

}  // namespace

Image shrink_image(const Image& image, const std::vector<uint8_t>& inside, int width, int height) {
  width = std::min(width, image.width), height = std::min(height, image.height);
  const Footprints columns(image.width, width), rows(image.height, height);
  Image out(width, height);
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) {
      // The chart texels under the output texel; where none is (between charts), all of them.
      double sum[4] = {0, 0, 0, 0};
      double wsum = add_footprint(image, inside, true, columns, size_t(x), rows, size_t(y), sum);
      if (!(wsum > 0)) wsum = add_footprint(image, inside, false, columns, size_t(x), rows, size_t(y), sum);
      out.at(x, y) = {round_level(sum[0] / wsum), round_level(sum[1] / wsum), round_level(sum[2] / wsum), round_level(sum[3] / wsum)};
    }
  });
  return out;
}

}  // namespace tightex
