// The tightex command: a thin shell over the library. Exit codes: 0 ok, 1 bad input (the message names
// the file and element), 2 internal error.
#include <sys/resource.h>
#include <unistd.h>

#include <tbb/parallel_invoke.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "core/error.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "report/metrics.hpp"
#include "report/preview.hpp"
#include "tightex/tightex.hpp"

namespace fs = std::filesystem;
using namespace tightex;

namespace {

void write_text_atomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.parent_path() / ("." + path.filename().string() + ".tmp");
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) fail_input("{}: cannot write", path.string());
    f << text;
    if (!f) fail_input("{}: write failed", path.string());
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    fail_input("{}: cannot rename into place", path.string());
  }
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int run_measure(int argc, char** argv) {
  CLI::App app{"tightex measure: the figures of METRICS.md for an input model and an output model"};
  std::string in_path, out_path;
  size_t samples = 200000;
  app.add_option("input", in_path, "the original model (OBJ)")->required();
  app.add_option("output", out_path, "the re-textured model (OBJ)")->required();
  app.add_option("--samples", samples, "surface PSNR samples");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  const TexturedMesh in = read_obj(in_path), out = read_obj(out_path);
  std::cout << to_json(measure(in, out, samples)).dump(2) << "\n";
  return 0;
}

int run_main(int argc, char** argv) {
  CLI::App app{"tightex: one compact texture per surface, from a scan's fragmented UV atlas\n"
               "(global parameterization by a harmonic map onto a square; Chen et al., arXiv 2406.04115)"};
  std::string input, outdir, report_path, preview_path, layout = "atlas", format = "png", holes = "fill", map = "detail", corners = "arcs";
  int size = 0;
  double texels = 0, balance = 1.0;
  std::string aspect_arg;
  bool quiet = false, verbose = false, force = false, no_fit = false, fine_fit = false;
  double max_memory_mib = 0;
  app.add_option("input", input, "textured model (OBJ + MTL + textures)")->required();
  app.add_option("-o,--output", outdir, "output directory")->required();
  auto* size_opt = app.add_option("--size", size, "texture side in texels (per-component: of the largest component); above 16384 needs --force. "
                                   "Default: the side that holds as many texels as the input uses (per-component: all the textures together; "
                                   "grown if the atlas cannot hold a 4x4 rectangle per component; see --texels)")
      ->check(CLI::Range(8, 65536));
  app.add_option("--texels", texels, "texel budget: the texture holds this many texels: the smallest square (side a multiple of 4), or as many "
                                     "in the shape --aspect gives or chooses (per-component: the largest component's texture). "
                                     "Default: the input's used texels, so the output keeps the input's information")
      ->check(CLI::PositiveNumber)->excludes(size_opt);
  app.add_option("--map", map, "detail (default): texels where the input texture has detail (colour gradient per 3D length), "
                               "capped at 4x the input's own density; area: the same texels per unit of 3D area everywhere; "
                               "texel: the input's own texel density per triangle; harmonic: the paper's map exactly (docs/maps.md)")
      ->check(CLI::IsMember({"detail", "texel", "area", "harmonic"}));
  app.add_option("--aspect", aspect_arg,
                 "width/height of the texture, which holds as many texels as a square would: auto (default, area/texel/detail "
                 "maps): the component holding most of the texture is mapped at 1:2, 1:1 and 2:1 and the shape whose "
                 "texels keep the most of the input is chosen (the square unless another is clearly better); a number "
                 "(e.g. 2) fixes it. With --size the default is 1, a square of that side")
      ->check([](const std::string& v) {
        if (v == "auto") return std::string();
        try {
          size_t used = 0;
          const double a = std::stod(v, &used);
          if (used == v.size() && a >= 0.0625 && a <= 16) return std::string();
        } catch (...) {
        }
        return std::string("must be auto or a number in [1/16, 16]");
      });
  app.add_option("--balance", balance, "area/texel/detail maps: 1 = target density exactly, 0 = the harmonic map's density (least angle "
                                       "distortion); between: a geometric blend")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--corners", corners, "which boundary points become the square's corners: arcs (default): four arcs of equal "
                                       "length; turning: where the boundary turns most (docs/corners.md)")
      ->check(CLI::IsMember({"arcs", "turning"}));
  auto* no_fit_opt = app.add_flag("--no-fit", no_fit, "bake each texel by sampling only, without the least-squares fit to the input");
  app.add_flag("--fine-fit", fine_fit, "fit on 4x4 points per texel instead of 2x2: +0.1-0.3 dB surface PSNR, about twice the bake time")
      ->excludes(no_fit_opt);
  app.add_flag("--force", force, "allow --size above 16384");
  app.add_option("--max-memory", max_memory_mib, "refuse inputs whose estimated memory exceeds this many MiB (default: 90% of RAM)")
      ->check(CLI::PositiveNumber);
  app.add_option("--layout", layout, "atlas: all components in one texture; per-component: one texture each (the paper's)")
      ->check(CLI::IsMember({"atlas", "per-component"}));
  app.add_option("--format", format, "texture file format")->check(CLI::IsMember({"png", "jpg"}));
  app.add_option("--holes", holes, "fill: cap holes with scaffolding (paper §4.1); cut: open them into the seam")
      ->check(CLI::IsMember({"fill", "cut"}));
  app.add_option("--report", report_path, "where to write the JSON report (default OUTDIR/report.json)");
  app.add_option("--preview", preview_path, "write a PNG of the input texture(s) beside the output texture");
  app.add_flag("-q,--quiet", quiet, "print nothing but errors");
  app.add_flag("-v,--verbose", verbose, "print the report's main figures");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  if (fs::is_directory(input)) fail_input("{}: is a directory, not a model file", input);
  {
    // The outputs are named after the input: written into the input's own folder they would replace it.
    std::error_code ec;
    const fs::path in_dir = fs::absolute(fs::path(input)).parent_path();
    if (fs::exists(outdir, ec) && fs::exists(in_dir, ec) && fs::equivalent(outdir, in_dir, ec))
      fail_input("{}: the output folder {} is the input's own folder; {}.obj would replace the input (choose another -o)", input, outdir,
                 fs::path(input).stem().string());
  }
  // Geometry first (milliseconds); the texture pixels are decoded while the geometric stages run,
  // since only the bake needs them. The OBJ is parsed twice: cheap, and every texture error keeps its
  // MTL file and line.
  ObjReadStats read_stats;
  ObjReadOptions geometry_only;
  geometry_only.load_textures = false;
  TexturedMesh geometry = read_obj(input, geometry_only, &read_stats);
  const double read_s = seconds_since(t0);
  for (Texture& t : geometry.textures) std::tie(t.width, t.height) = image_dimensions(t.path);
  if (size == 0) {
    const int max_side = force ? 65536 : kDefaultSizeMax;
    size = texels > 0 ? std::min(size_for_texels(texels), max_side) : default_size(geometry, max_side);
  }
  if (size > 16384 && !force)
    fail_input("--size {} is above 16384 ({:.1f} GiB of RGBA texture); add --force to allow it", size,
               double(size) * size * 4 / double(1 << 30));
  const bool show_progress = !quiet && isatty(STDERR_FILENO);
  if (max_memory_mib <= 0)
    max_memory_mib = 0.9 * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE)) / double(1 << 20);


  // Resource guard, before any pixel is allocated: decoded input textures (RGBA), the mesh and its
  // stages (~1.2 KB a triangle, measured peak on the scans), and for the atlas the output texture with
  // its coverage masks (~7 bytes a texel). Per-component outputs are checked once the layout is known.
  auto guard = [&](double bytes, const std::string& what) {
    if (bytes / double(1 << 20) > max_memory_mib)
      fail_input("{}: {} needs about {:.0f} MiB, more than the limit of {:.0f} MiB (--max-memory)", input, what,
                 bytes / double(1 << 20), max_memory_mib);
  };
  double estimate = double(geometry.num_triangles()) * 1200.0;
  for (const Texture& t : geometry.textures) estimate += double(t.width) * double(t.height) * 4.0;
  if (layout == "atlas") estimate += double(size) * double(size) * 7.0;
  guard(estimate, "this model at this --size");

  Options opt;
  opt.size = size;
  opt.default_budget = size_opt->count() == 0 && !(texels > 0);  // the default budget (Options::default_budget)
  opt.layout = layout == "atlas" ? Layout::kAtlas : Layout::kPerComponent;
  opt.holes = holes == "fill" ? HoleMode::kFill : HoleMode::kCut;
  opt.map = map == "harmonic" ? MapKind::kHarmonic : map == "area" ? MapKind::kArea : map == "texel" ? MapKind::kTexel : MapKind::kDetail;
  opt.balance = balance;
  // --size promises a side: a square, unless a shape is asked for.
  opt.aspect = aspect_arg.empty() ? (size_opt->count() > 0 ? 1.0 : 0.0) : aspect_arg == "auto" ? 0.0 : std::stod(aspect_arg);
  opt.corners = corners == "turning" ? CornerRule::kTurningAngle : CornerRule::kEqualArcs;
  opt.fit = !no_fit;
  opt.fine_fit = fine_fit;
  opt.measure = false;
  if (show_progress)
    opt.progress = [](std::string_view stage, double f) {
      if (f > 0 && f < 1) fmt::print(stderr, "\r\033[Ktightex: {} {:.0f}%...", stage, 100 * f);
      else fmt::print(stderr, "\r\033[Ktightex: {}...", stage);
    };
  TexturedMesh mesh;
  Plan plan;
  double textures_s = 0;
  std::exception_ptr texture_error, plan_error;
  auto read_textures = [&] {
    try {
      mesh = read_obj(input);
      textures_s = seconds_since(t0);
    } catch (...) {
      texture_error = std::current_exception();
    }
  };
  if (opt.map == MapKind::kDetail || (opt.aspect == 0 && opt.map != MapKind::kHarmonic && opt.layout == Layout::kAtlas)) {
    // The detail map reads the texture's pixels to place its texels, the auto aspect to compare its
    // shapes: textures first.
    read_textures();
    if (!texture_error) {
      try {
        plan = plan_charts(mesh, opt);
      } catch (...) {
        plan_error = std::current_exception();
      }
    }
  } else {
    tbb::parallel_invoke(read_textures, [&] {
      try {
        plan = plan_charts(geometry, opt);
      } catch (...) {
        plan_error = std::current_exception();
      }
    });
  }
  if (texture_error) std::rethrow_exception(texture_error);  // a bad texture is the user's first problem
  if (plan_error) std::rethrow_exception(plan_error);
  if (layout != "atlas") {
    double out_texels = 0;
    for (const auto& [w, h] : plan.image_size) out_texels += double(w) * double(h);
    guard(estimate + out_texels * 7.0, "this model's per-component textures");
  }
  Result result = bake_plan(plan, mesh, opt);
  if (show_progress) fmt::print(stderr, "\r\033[K");
  // Components the method could not map are kept as they were (Plan::kept): one line says so.
  size_t kept_components = 0, kept_triangles = 0;
  const std::string* kept_reason = nullptr;
  for (size_t c = 0; c < plan.kept.size(); ++c)
    if (!plan.kept[c].empty()) {
      ++kept_components;
      kept_triangles += plan.components[c].num_faces();
      if (kept_reason == nullptr) kept_reason = &plan.kept[c];
    }
  if (kept_components > 0 && !quiet)
    fmt::print(stderr,
               "tightex: warning: {} component(s), {} triangles, could not be re-parameterized and keep their original "
               "texture coordinates and texture(s) ({}); see \"kept_original_uvs\" in the report\n",
               kept_components, kept_triangles, *kept_reason);

  // The default budget grown to hold every component (Options::default_budget): one line says so.
  if (const auto& grown = plan.report["options"]["size_grown_from"]; !grown.is_null() && !quiet)
    fmt::print(stderr, "tightex: note: {} components need a 4x4 texel rectangle each: the texture grew from {}^2 to {}^2 texels (--size sets it)\n",
               plan.components.size(), grown.get<int>(), plan.report["options"]["size"].get<int>());

  // Writing (PNG compression) and measuring are independent: run them side by side.
  const auto tw = std::chrono::steady_clock::now();
  std::string name = fs::path(input).stem().string();
  double write_s = 0, measure_s = 0;
  Metrics metrics;
  tbb::parallel_invoke(
      [&] {
        write_obj(result.output, outdir, name, format == "png" ? ImageFormat::kPng : ImageFormat::kJpeg);
        write_s = seconds_since(tw);
      },
      [&] {
        metrics = measure(mesh, result.output);
        measure_s = seconds_since(tw);
      });
  nlohmann::json& rep = result.report;
  rep["metrics"] = to_json(metrics);
  rep["timings"].push_back(nlohmann::json{{"stage", "write (beside measure)"}, {"seconds", write_s}});
  rep["timings"].push_back(nlohmann::json{{"stage", "measure (beside write)"}, {"seconds", measure_s}});
  rep["timings"].insert(rep["timings"].begin(), nlohmann::json{{"stage", "read geometry"}, {"seconds", read_s}});
  rep["timings"].insert(rep["timings"].begin() + 1,
                        nlohmann::json{{"stage", "read textures (beside the geometric stages, from start)"}, {"seconds", textures_s}});
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  rep["wall_seconds"] = seconds_since(t0);
  rep["peak_rss_mib"] = double(u.ru_maxrss) / 1024.0;
  rep["input"]["polygons_triangulated"] = read_stats.polygons_triangulated;
  rep["input"]["paths_found"] = read_stats.paths_found;  // MTL/texture names found without case or by a tail
  rep["output"] = {{"directory", outdir}, {"obj", name + ".obj"}};
  if (!preview_path.empty()) {
    const fs::path p(preview_path);
    const fs::path tmp = p.parent_path() / ("." + p.filename().string() + ".tmp");
    save_image(tmp.string(), make_preview(mesh, result.output), ImageFormat::kPng);
    std::error_code ec;
    fs::rename(tmp, p, ec);
    if (ec) fail_input("{}: cannot write preview ({})", preview_path, ec.message());
  }
  if (report_path.empty()) report_path = (fs::path(outdir) / "report.json").string();
  write_text_atomically(report_path, rep.dump(2) + "\n");

  if (!quiet) {
    const auto& m = rep["metrics"];
    // The new texture's size (the first of several: per-component layout).
    std::string texture;
    if (!result.output.textures.empty()) {
      const Image& img = result.output.textures[0].image;
      texture = fmt::format("{}x{}{} texture, ", img.width, img.height, result.output.textures.size() > 1 ? " +" : "");
    }
    fmt::print("tightex: {} -> {}/{}.obj  ({}{} components, {:.1f}% -> {:.1f}% texels used, {} charts, "
               "PSNR {:.1f} dB, {} lost, {} flipped, {:.2f} s)\n",
               input, outdir, name, texture, rep["preparation"]["components"].get<size_t>(),
               100 * m["input"]["utilization"].get<double>(), 100 * m["output"]["utilization"].get<double>(),
               m["charts"].get<size_t>(), m["surface_psnr_db"].get<double>(), m["lost_triangles"].get<size_t>(),
               m["flipped"].get<size_t>(), rep["wall_seconds"].get<double>());
    if (verbose) fmt::print("{}\n", m.dump(2));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc > 1 && std::string(argv[1]) == "measure") return run_measure(argc - 1, argv + 1);
    return run_main(argc, argv);
  } catch (const InputError& e) {
    fmt::print(stderr, "tightex: error: {}\n", e.what());
    return int(ExitCode::kBadInput);
  } catch (const InternalError& e) {
    fmt::print(stderr, "tightex: internal error: {}\n", e.what());
    return int(ExitCode::kInternal);
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "tightex: internal error: out of memory\n");
    return int(ExitCode::kInternal);
  } catch (const std::exception& e) {
    fmt::print(stderr, "tightex: internal error: {}\n", e.what());
    return int(ExitCode::kInternal);
  }
}
