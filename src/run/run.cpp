// The library's whole run (tightex/run.hpp): read, guard, decode beside the repair, plan, bake, encode,
// write, measure, report; and optimize(), the same on a mesh in memory.
#include "tightex/run.hpp"

#include <tbb/parallel_invoke.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <tuple>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "core/resources.hpp"
#include "io/image_io.hpp"
#include "io/model_files.hpp"
#include "io/output_files.hpp"
#include "io/texture_sources.hpp"
#include "layout/layout.hpp"
#include "pipeline/plan_state.hpp"
#include "report/report.hpp"
#include "run/budget_search.hpp"
#include "run/memory_guard.hpp"
#include "run/process_tuning.hpp"
#include "run/reencode.hpp"
#include "run/run_output.hpp"
#include "run/run_warnings.hpp"
#include "run/texture_bytes.hpp"
#include "tightex/tightex.hpp"

namespace fs = std::filesystem;

namespace tightex {

namespace {

/// Throws InputError naming the option (as the CLI spells it) unless `value` is in [lo, hi].
template <typename T>
void check_range(T value, T lo, T hi, const char* option) {
  if (!(value >= lo && value <= hi)) fail_input("options: {} {} is out of range ({}..{})", option, value, lo, hi);
}

/// The model format the run writes: Options::model_format, else the input's kind.
ModelFormat output_format(const std::string& input, const Options& options) {
  return options.model_format.value_or(model_format_of(input));
}

/// Refuses a codec option that does nothing with the codec written (`format`: Options::texture_format,
/// else the input's base colour's), and rate control where the images are written losslessly.
void check_codec_options(const std::string& input, const Options& o, ImageFormat format) {
  const std::string_view name = to_string(format);
  const auto refuse = [&](const char* option, ImageFormat needs) {
    if (o.texture_format) fail_input("{}: {} needs --format {} (does nothing with --format {})", input, option, to_string(needs), name);
    fail_input("{}: {} does nothing: the images are written as {}, the input's codec (--format chooses another)", input, option, name);
  };
  if (o.png_level && format != ImageFormat::kPng) refuse("--png-level", ImageFormat::kPng);
  if (o.jpeg_quality && format != ImageFormat::kJpeg) refuse("--jpeg-quality", ImageFormat::kJpeg);
  if (o.webp_quality && format != ImageFormat::kWebp) refuse("--webp-quality", ImageFormat::kWebp);
  if (o.webp_lossless && format != ImageFormat::kWebp) refuse("--webp-lossless", ImageFormat::kWebp);
  const bool lossy = format == ImageFormat::kJpeg || (format == ImageFormat::kWebp && !o.webp_lossless);
  const bool codec_searched = !o.texture_format && o.size == 0 && o.texels == 0;  // search_codecs chooses one
  if ((o.target_psnr_db > 0 || o.max_bytes > 0) && !lossy && !codec_searched)
    fail_input(
        "{}: --target-psnr and --max-bytes with --size or --texels choose a lossy codec's quality, and this input's images would be "
        "written as {}: add --format webp or --format jpg",
        input, o.webp_lossless ? "lossless WebP" : "PNG");
}

/// What the options ask of the output's images.
BytesRequest bytes_request(const Options& o) {
  ImageEncoding e(o.texture_format.value_or(ImageFormat::kPng));
  e.png_level = o.png_level.value_or(kDefaultPngLevel);
  e.jpeg_quality = o.jpeg_quality.value_or(kDefaultJpegQuality);
  e.webp_quality = o.webp_quality.value_or(kDefaultWebpQuality);
  e.webp_lossless = o.webp_lossless;
  return {
      o.texture_format, e, o.jpeg_quality.has_value() || o.webp_quality.has_value(), o.target_psnr_db, o.max_bytes, 0, 0, {}, {}, {}, {}};
}

/// The model's geometry (no pixels) with its textures' sizes from their headers, checked against the
/// memory limit; the reader's figures into `read_stats`.
TexturedMesh read_geometry(const std::string& input, const Options& options, ModelReadStats* read_stats) {
  ModelReadOptions geometry_only;
  geometry_only.load_textures = false;
  geometry_only.allow_outside_files = options.allow_outside_files;
  // OBJ and PLY have no scene graph: a glTF scene written as one is placed in world space.
  const ModelFormat format = output_format(input, options);
  geometry_only.flatten_scene = format == ModelFormat::kObj || format == ModelFormat::kPly;
  TexturedMesh geometry = read_model(input, geometry_only, read_stats);
  for (Texture& t : geometry.textures)
    if (t.image.empty() && t.width == 0)  // a vertex-colour texture is made, a glTF's embedded image sized by its reader
      std::tie(t.width, t.height) = image_dimensions(t.path);
  check_texture_headers(memory_guard(input, options), geometry);
  return geometry;
}

/// The options the method runs with in a run writing `format`: measured beside the write, the
/// untextured triangles baked into PLY, which has no material to keep their colour in, and its "done"
/// kept for the run's own, once the files are in place.
Options method_options(const Options& options, ModelFormat format) {
  Options o = options;
  o.measure = false;
  if (options.progress)
    o.progress = [progress = options.progress](std::string_view stage, double fraction) {
      return stage == "done" || progress(stage, fraction);
    };
  o.keep_untextured = options.keep_untextured && format != ModelFormat::kPly;
  return o;
}

/// The model with its texture pixels and the plan made from it.
struct PlannedModel {
  TexturedMesh mesh;
  Plan plan;
  double textures_s = 0;  // when the textures were read, in seconds from the start
};

/// Decodes the textures of `geometry` (read without pixels), which becomes the planned model, and plans
/// the charts at `budget`. The geometric stages need no pixels, so the textures are decoded beside
/// them, unless the plan needs the pixels (the detail map places texels by them, the auto aspect
/// compares its shapes with them): then only the preparation (repair, components, seams, handles) is
/// made beside them, and the rest after. A texture error is thrown before a plan error: a bad texture
/// is the user's first problem.
PlannedModel read_textures_and_plan(TexturedMesh geometry, const Options& opt, const TextureBudget& budget,
                                    std::chrono::steady_clock::time_point t0) {
  PlannedModel r;
  std::exception_ptr texture_error, plan_error;
  std::vector<Texture> textures;
  auto read_textures = [&] {
    try {
      textures = load_texture_pixels(geometry, ModelReadOptions{}.max_texture_pixels);
      r.textures_s = seconds_since(t0);
    } catch (...) {
      texture_error = std::current_exception();
    }
  };
  auto planning = [&](auto&& step) {  // a step of the plan, its error kept for after the textures'
    try {
      step();
    } catch (...) {
      plan_error = std::current_exception();
    }
  };
  const bool plan_needs_pixels =
      opt.map == MapKind::kDetail || (effective_aspect(opt) == 0 && opt.map != MapKind::kHarmonic && opt.layout == Layout::kAtlas);
  PreparedMesh prepared;
  tbb::parallel_invoke(read_textures, [&] {
    planning([&] {
      if (plan_needs_pixels)
        prepared = prepare_mesh(geometry, opt);
      else
        r.plan = plan_charts(geometry, opt, budget);
    });
  });
  r.mesh = std::move(geometry);
  if (!texture_error) r.mesh.textures = std::move(textures);
  if (plan_needs_pixels && !texture_error && !plan_error) planning([&] { r.plan = plan_charts(r.mesh, opt, budget, &prepared); });
  if (texture_error) std::rethrow_exception(texture_error);
  if (plan_error) std::rethrow_exception(plan_error);
  return r;
}

/// The lossy codecs --target-psnr and --max-bytes choose from without --format: those every reader of
/// `format` decodes (glTF's core images are PNG and JPEG; WebP needs EXT_texture_webp, which a viewer
/// may lack, so it is written only when asked for).
std::vector<ImageFormat> search_codecs(ModelFormat format) {
  if (format == ModelFormat::kGltf || format == ModelFormat::kGlb) return {ImageFormat::kJpeg};
  return {ImageFormat::kWebp, ImageFormat::kJpeg};
}

/// The least and the most scale of the side by which the texels grow where --target-psnr is not
/// reached at tightex's budget (growth_scale): a smaller step is within the search's own error, and a
/// larger one (over 4x the texels) is more a different --size than a search.
constexpr double kLeastGrowth = 1.2, kMostGrowth = 2;

/// Where the images as written at tightex's texel budget stay below --target-psnr (the bake's own error,
/// or the codec's at quality 100): the scale of the side at which a bake may reach it, taking the
/// written error as falling with the side as the bake's own error rises as it shrinks
/// (EncodingChoice::bake_error_exponent, taken within [1, 2]), 10% more, and at least kLeastGrowth.
/// 1 where the target is reached, or where that scale is beyond kMostGrowth, puts a page beyond
/// Options::max_page_side (16380 where there is none: WebP's limit) or the textures beyond `guard`'s
/// memory: the warning then asks for more texels.
double growth_scale(const Options& options, const EncodingChoice& choice, const std::vector<std::pair<int, int>>& pages,
                    const MemoryGuard& guard) {
  const double written = choice.written_psnr_db.value_or(0);
  if (!(options.target_psnr_db > 0) || choice.images.empty() || written >= options.target_psnr_db) return 1;
  const double exponent = std::clamp(choice.bake_error_exponent, 1.0, 2.0);
  const double scale = std::max(kLeastGrowth, 1.1 * std::pow(mse_of_psnr(written) / mse_of_psnr(options.target_psnr_db), 1 / exponent));
  const int cap = options.max_page_side > 0 ? options.max_page_side : 16380;
  for (const auto& [w, h] : pages)
    if (texture_side_at(std::max(w, h), scale) > cap) return 1;
  return scale <= kMostGrowth && fits_larger_textures(guard, pages, scale) ? scale : 1;
}

/// The images' codec and quality (the input's codec; rate control), chosen for `result`: with
/// --target-psnr or --max-bytes and tightex's own texel budget, the texels of the baked images too
/// (budget_search.hpp). Where the search shrinks them, or a target is not reached at the bake's size
/// (growth_scale), the charts of `plan` (its maps kept by the first bake) are baked once more at that
/// scale (rescale_plan; where it cannot, planned again at that budget): a bake at fewer texels reads
/// the input once where the shrunk images resample the bake (WaterBottle at 0.59 of its side: 46.9 dB
/// re-baked, 43.4 shrunk), and its quality is chosen alone; whichever answers better replaces
/// `result`'s images, the report's stage timings kept the first bake's. `method`: the options the
/// method ran with; `guard`: the run's memory, which larger textures must fit. Tells `progress`
/// "encode" as it goes, and may throw Cancelled.
EncodingChoice choose_images(const Options& options, const Options& method, const TexturedMesh& input,
                             const std::vector<TextureSource>& sources, const TextureBudget& budget, const MemoryGuard& guard,
                             ModelFormat format, Plan& plan, Result& result, const StageProgress& progress) {
  BytesRequest request = bytes_request(options);
  request.progress = [&](double f) { progress("encode", 0.8 * f); };
  if (budget.is_default) request.new_pages = result.report.texture_sizes.size();
  request.codecs = search_codecs(format);
  EncodingChoice choice = choose_encoding(request, input, sources, result.output);
  // A bound kept at the bake's size is tried once at half its texels too: the model judges a smaller
  // scale by the shrunk bake, which reads lower than a bake at that budget (meshroom_esp32cam within
  // 42,950 bytes: 37.02 dB kept at its size, 37.5 at 0.65-0.73 of its side by hand).
  double scale = choice.texel_scale;
  if (!choice.probes.is_null() && !(scale < 1) && options.max_bytes > 0) scale = std::sqrt(0.5);
  if (!choice.probes.is_null() && !(scale < 1)) scale = growth_scale(options, choice, result.report.texture_sizes, guard);
  if (choice.probes.is_null() || scale == 1) return choice;
  Options quiet = method;
  quiet.progress = [&](std::string_view, double) { return progress("encode", 0.8), true; };
  const TextureBudget rescaled{texture_side_at(budget.side, scale), true};
  std::map<std::string, double> map_scales;  // each material map as the first bake sized it
  for (const nlohmann::json& m : report_json(result.report).value("maps", nlohmann::json::array()))
    map_scales[m.at("name").get<std::string>()] = m.at("scale").get<double>();
  const bool same_charts = rescale_plan(plan, scale, map_scales);
  Result rebaked =
      same_charts ? bake_plan_releasing_maps(plan, input, quiet) : bake_plan(plan_charts(input, quiet, rescaled), input, quiet);
  round_uvs_as_stored(rebaked.output, format);
  BytesRequest alone = bytes_request(options);
  alone.format = choice.encoding.format;
  alone.quality_hint = choice.encoding.format == ImageFormat::kJpeg ? choice.encoding.jpeg_quality : choice.encoding.webp_quality;
  if (choice.codec_mse_at) {  // the model's codec error at the scale baked again
    alone.codec_mse_by_quality.assign(101, 0);
    for (int quality = 0; quality <= 100; ++quality) alone.codec_mse_by_quality[size_t(quality)] = choice.codec_mse_at(scale, quality);
  }
  // The same charts baked again: the same triangles, corners and vertices, so the first search's
  // judges find every point where they did (they read the texture coordinates at each call).
  if (same_charts && rebaked.output.triangles == result.output.triangles && rebaked.output.positions == result.output.positions &&
      rebaked.output.face_material == result.output.face_material)
    alone.judges = choice.judges;
  alone.progress = [&](double f) { progress("encode", 0.8 + 0.2 * f); };
  EncodingChoice c = choose_encoding(alone, input, sources, rebaked.output);
  const auto bytes = [](const EncodingChoice& e) { return std::accumulate(e.bytes.begin(), e.bytes.end(), uint64_t(0)); };
  if (!choice.images.empty() &&  // empty: the model's choice, unchecked
      !answers_better(options.target_psnr_db, options.max_bytes, bytes(c), c.written_psnr_db.value_or(0), bytes(choice),
                      choice.written_psnr_db.value_or(0)))
    return choice;
  const auto [w, h] = rebaked.report.texture_sizes.at(0);
  c.reason = fmt::format("{}; {} again at {}x{} ({:.2f} of the side), which answers it better: {}", choice.reason,
                         same_charts ? "the same charts baked" : "planned and baked", w, h, scale, c.reason);
  c.probes = std::move(choice.probes);
  c.texel_scale = scale;
  nlohmann::json timings = std::move(report_json(result.report)["timings"]);
  result = std::move(rebaked);
  report_json(result.report)["timings"] = std::move(timings);
  return c;
}

/// --compare-reencode: report.json bytes.reencode, the input's own images re-encoded in the output's
/// lossy codec at the surface PSNR the written images reach (`written_psnr_db`), beside the output's
/// bytes; a reason where there is nothing to compare (a lossless output, an input without images) or
/// the codec cannot hold an input image (a WebP side is at most 16383).
/// Its time into the report's timings.
void add_reencode(TexturedMesh& input, const ImageEncoding& encoding, double written_psnr_db, nlohmann::json& json) {
  nlohmann::json& r = json["bytes"]["reencode"];
  if (!encoding.lossy()) {
    r = {{"reason", "the output's images are lossless: a re-encode at the same PSNR is the input as it is"}};
    return;
  }
  const bool has_images = std::any_of(input.materials.begin(), input.materials.end(), [&](const Material& m) {
    return m.texture >= 0 && !input.textures[size_t(m.texture)].from_vertex_colours;
  });
  if (!has_images) {
    r = {{"reason", "the input's colours are vertex colours: no image to re-encode"}};
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const CpuTimes cpu = process_cpu_times();
  ReencodeFigures f;
  try {
    f = reencode_at_psnr(input, encoding.format, written_psnr_db);
  } catch (const InputError& e) {  // an input image the codec cannot hold: the run's files stay, the figure says why
    r = {{"reason", fmt::format("the input's images cannot be re-encoded as {}: {}", to_string(encoding.format), e.what())}};
    return;
  }
  const uint64_t output_bytes = json["bytes"]["output"]["total"].get<uint64_t>();
  r = {{"codec", to_string(encoding.format)},
       {"quality", f.quality},
       {"bytes", f.bytes},
       {"psnr_db", f.reached_psnr_db},
       {"bytes_at_written_psnr", f.bytes_at_psnr},
       {"output_over_reencode", double(output_bytes) / std::max(1.0, f.bytes_at_psnr)},
       {"probes", f.probes}};
  if (f.quality > 100) r["reason"] = "even quality 100 does not reach the output's PSNR: its bytes and PSNR at 100";
  const CpuTimes now = process_cpu_times();
  json["timings"].push_back(to_json(
      StageTiming{"re-encode the input (--compare-reencode)", seconds_since(t0), std::nullopt, now.user - cpu.user, now.sys - cpu.sys}));
}

}  // namespace

void check_options(const Options& o) {
  if (o.size != 0) check_range(o.size, 8, 65536, "--size");  // above 16384 without --force: texture_budget refuses it
  if (o.size != 0 && o.texels != 0) fail_input("options: --size and --texels go one without the other");
  if (o.texels < 0) fail_input("options: --texels {} must be positive", o.texels);
  if (o.aspect != 0 && o.aspect != kAspectAuto) check_range(o.aspect, 1.0 / 16, 16.0, "--aspect");
  check_range(o.balance, 0.0, 1.0, "--balance");
  check_range(o.material_map_budget_db, 0.0, 99.0, "--material-map-budget");
  check_range(o.max_page_side, 0, 65536, "--max-size");
  if (o.max_memory_mib < 0) fail_input("options: --max-memory {} must be positive", o.max_memory_mib);
  if (o.png_level && *o.png_level != kPngLevelFast) check_range(*o.png_level, 0, 9, "--png-level");
  if (o.jpeg_quality) check_range(*o.jpeg_quality, 1, 100, "--jpeg-quality");
  if (o.webp_quality) check_range(*o.webp_quality, 1, 100, "--webp-quality");
  if (o.target_psnr_db != 0) check_range(o.target_psnr_db, 1.0, 99.0, "--target-psnr");
  if (o.target_psnr_db > 0 && o.max_bytes > 0) fail_input("options: --target-psnr goes without --max-bytes");
  if ((o.target_psnr_db > 0 || o.max_bytes > 0) && (o.jpeg_quality || o.webp_quality))
    fail_input("options: --target-psnr/--max-bytes choose the quality: they go without --jpeg-quality and --webp-quality");
}

ModelFormat model_format_of(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  for (const ModelFormat f : kModelFormats)
    if (f != ModelFormat::kObj && equals_ignoring_case(extension, fmt::format(".{}", to_string(f)))) return f;
  return ModelFormat::kObj;
}

Report run(const std::string& input, const std::string& outdir, const Options& options) {
  const auto t0 = std::chrono::steady_clock::now();
  keep_freed_memory_for_reuse();
  check_options(options);
  const ModelFormat format = output_format(input, options);
  check_paths(input, outdir, format);
  const StageProgress progress(options.progress);
  progress("read", 0);
  // Geometry first; the texture pixels are decoded while the geometric stages run, into the same model.
  RunTimings timings;
  ModelReadStats read_stats;
  TexturedMesh geometry = read_geometry(input, options, &read_stats);
  timings.read_s = seconds_since(t0);
  timings.read_cpu = process_cpu_times();
  const std::vector<TextureSource> geometry_sources = texture_sources(geometry);
  check_codec_options(input, options,
                      options.texture_format.value_or(base_colour_format(geometry, geometry_sources).value_or(ImageFormat::kPng)));
  const TextureBudget budget = texture_budget(geometry, options);
  const MemoryGuard guard = check_memory(input, options, geometry, budget.side);
  const Options opt = method_options(options, format);
  PlannedModel planned = read_textures_and_plan(std::move(geometry), opt, budget, t0);
  timings.textures_s = planned.textures_s;
  if (options.layout != Layout::kAtlas) check_per_component_memory(guard, planned.plan);
  // The rate search may bake the same charts again at fewer texels (choose_images): their maps are kept.
  const bool may_bake_again = budget.is_default && (options.target_psnr_db > 0 || options.max_bytes > 0);
  Result result = may_bake_again ? bake_plan(planned.plan, planned.mesh, opt) : bake_plan_releasing_maps(planned.plan, planned.mesh, opt);
  round_uvs_as_stored(result.output, format);

  const std::vector<TextureSource> sources = texture_sources(planned.mesh);
  const auto encode_start = std::chrono::steady_clock::now();
  const CpuTimes encode_cpu = process_cpu_times();
  const EncodingChoice choice = choose_images(options, opt, planned.mesh, sources, budget, guard, format, planned.plan, result, progress);
  timings.encode_s = seconds_since(encode_start);
  timings.encode_cpu = CpuTimes{process_cpu_times().user - encode_cpu.user, process_cpu_times().sys - encode_cpu.sys};
  const ModelFormat input_format = model_format_of(input);
  const ModelTarget target{outdir,
                           fs::path(input).stem().string(),
                           format,
                           choice.encoding,
                           &choice.images,
                           options.html,
                           input_format == ModelFormat::kGltf || input_format == ModelFormat::kGlb};
  WrittenAndMeasured written = write_and_measure(target, planned.mesh, result.output, timings, progress);
  // The figures are the files' as written (a lossy codec's images decoded back); the bake's beside them,
  // asked of the judge that measured the written images where there is one (the same points and figure
  // as surface_psnr, without finding them again).
  if (choice.encoding.lossy())
    written.metrics.surface_psnr_bake = choice.judges.all ? (*choice.judges.all)(result.output) : surface_psnr(planned.mesh, result.output);
  const Metrics& metrics = written.metrics;
  nlohmann::json json = report_json(result.report);
  add_run_figures(json, metrics, timings, seconds_since(t0), read_stats,
                  OutputFiles{outdir, output_model_name(input, format), options.html ? kHtmlName : "", written.removed});
  json["bytes"] = bytes_json(planned.mesh, sources, result.output, choice, metrics, format);
  json["bytes"]["surface_psnr_bake_db"] = metrics.surface_psnr_bake.value_or(metrics.surface_psnr);
  if (!choice.probes.is_null()) json["bytes"]["probes"] = choice.probes;
  if (options.compare_reencode) add_reencode(planned.mesh, choice.encoding, metrics.surface_psnr, json);
  add_warnings(planned.plan, planned.mesh, read_stats, format, written.removed, json);
  add_rate_warnings(options, json);
  if (!options.preview_path.empty()) write_preview(options.preview_path, planned.mesh, result.output);
  Report report = public_report(std::move(json), result.output, result.report.texture_sizes.size());
  const fs::path json_path = options.report_path.empty() ? fs::path(outdir) / "report.json" : fs::path(options.report_path);
  report.report_path = write_reports(json_path, outdir, report.json, options.html ? &written.html_data : nullptr).string();
  report.model_path = (fs::path(outdir) / output_model_name(input, format)).string();
  // Every file is in place: the last event, whose answer changes nothing.
  if (options.progress) options.progress("done", 1);
  return report;
}

double estimate_memory(const std::string& input, const Options& options) {
  const TexturedMesh geometry = read_geometry(input, options, nullptr);
  Options as_atlas = options;
  as_atlas.layout = Layout::kAtlas;
  as_atlas.max_memory_mib = std::numeric_limits<double>::max();
  return check_memory(input, as_atlas, geometry, texture_budget(geometry, options).side).estimate;
}

Result optimize(const TexturedMesh& mesh, const Options& options) {
  const auto t0 = std::chrono::steady_clock::now();
  keep_freed_memory_for_reuse();
  check_options(options);
  const std::string name = mesh.source.empty() ? std::string("mesh") : mesh.source;
  check_texture_headers(memory_guard(name, options), mesh);
  const TextureBudget budget = texture_budget(mesh, options);
  const MemoryGuard guard = check_memory(name, options, mesh, budget.side);
  Plan plan = plan_charts(mesh, options, budget);
  if (options.layout != Layout::kAtlas) check_per_component_memory(guard, plan);
  Result result = bake_plan_releasing_maps(plan, mesh, options);
  nlohmann::json json = report_json(result.report);
  json["wall_seconds"] = seconds_since(t0);
  json["peak_rss_mib"] = peak_rss_mib();
  add_warnings(plan, mesh, ModelReadStats{}, std::nullopt, {}, json);
  const size_t new_textures = result.report.texture_sizes.size();
  result.report = public_report(std::move(json), result.output, new_textures);
  return result;
}

}  // namespace tightex
