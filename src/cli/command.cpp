// The tightex command (command.hpp): the flags mapped onto Options, and what the command prints.
#include "cli/command.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "report/report.hpp"
#include "run/option_help.hpp"
#include "tightex/run.hpp"
#include "tightex/version.hpp"

namespace fs = std::filesystem;

namespace tightex::cli {

namespace {

/// The names of every value of an enum, in the table's order: the CLI's list of allowed values.
template <typename Enum, size_t N>
std::vector<std::string> names_of(const std::array<Enum, N>& values) {
  std::vector<std::string> names;
  for (Enum v : values) names.emplace_back(to_string(v));
  return names;
}

/// The value a name checked by CLI::IsMember(names_of(values)) stands for.
template <typename Enum, size_t N>
Enum parsed(const std::array<Enum, N>& values, const std::string& name) {
  const std::optional<Enum> v = from_string(values, name);
  if (!v) throw InternalError("command line: '" + name + "' passed the option's check but names no value");
  return *v;
}

/// --aspect's check: "auto" or a number in [1/16, 16]; an empty string means it passes.
std::string check_aspect(const std::string& v) {
  if (v == "auto") return std::string();
  try {
    size_t used = 0;
    const double a = std::stod(v, &used);
    if (used == v.size() && a >= 0.0625 && a <= 16) return std::string();
  } catch (...) {
  }
  return std::string("must be auto or a number in [1/16, 16]");
}

/// The flags' values as given, before they become Options fields (enum names, "auto", optional and
/// inverted settings).
struct GivenFlags {
  std::string layout, format, holes, map, corners;  // format empty: the input's
  std::string output_format;                        // empty: not given
  std::string aspect;                               // empty, "auto" or a number
  std::string png_level;                            // 0..9 or "fast"
  int jpeg_quality = 0, webp_quality = 0;
  bool no_fit = false, no_html = false;
  CLI::Option *size = nullptr, *png = nullptr, *jpeg = nullptr, *webp = nullptr;
};

/// The flag that sets `field` (option_help's table), declared with its description.
CLI::Option* add(CLI::App& app, std::string_view field, auto& value) {
  for (const OptionHelp& h : option_helps())
    if (h.field == field) return app.add_option(std::string(h.flag), value, std::string(h.help));
  throw InternalError("command line: no flag for " + std::string(field));
}
CLI::Option* add_flag(CLI::App& app, std::string_view field, bool& value) {
  for (const OptionHelp& h : option_helps())
    if (h.field == field) return app.add_flag(std::string(h.flag), value, std::string(h.help));
  throw InternalError("command line: no flag for " + std::string(field));
}

/// Declares the texture codec flags.
void define_encoding_flags(CLI::App& app, Options& o, GivenFlags& given) {
  add(app, "texture_format", given.format)->check(CLI::IsMember(names_of(kImageFormats)));
  given.png = add(app, "png_level", given.png_level)->check(CLI::IsMember({"fast", "0", "1", "2", "3", "4", "5", "6", "7", "8", "9"}));
  given.jpeg = add(app, "jpeg_quality", given.jpeg_quality)->check(CLI::Range(1, 100));
  given.webp = add(app, "webp_quality", given.webp_quality)->check(CLI::Range(1, 100));
  add_flag(app, "webp_lossless", o.webp_lossless);
  add(app, "target_psnr_db", o.target_psnr_db)->check(CLI::Range(1.0, 99.0));
  add(app, "max_bytes", o.max_bytes)->check(CLI::PositiveNumber);
  add_flag(app, "compare_reencode", o.compare_reencode);
}

/// Declares every flag of the main command on `app`, bound to `line` and `given`.
void define_flags(CLI::App& app, CommandLine& line, GivenFlags& given) {
  Options& o = line.options;
  given.layout = to_string(o.layout), given.holes = to_string(o.holes), given.map = to_string(o.map);
  given.corners = to_string(o.corners);
  app.add_option("input", line.input,
                 "textured model: OBJ + MTL, PLY, glTF (.gltf) or GLB, with its textures or vertex colours (3D Tiles: python3 -m "
                 "tightex.tiles)")
      ->required();
  app.add_option("-o,--output", line.outdir, "output directory")->required();
  app.set_version_flag("--version", std::string(version()), "print the version (git describe of the build) and exit");
  given.size = add(app, "size", o.size)->check(CLI::Range(8, 65536));
  add(app, "texels", o.texels)->check(CLI::PositiveNumber)->excludes(given.size);
  add(app, "map", given.map)->check(CLI::IsMember(names_of(kMapKinds)));
  add(app, "aspect", given.aspect)->check(check_aspect);
  add(app, "max_page_side", o.max_page_side)->check(CLI::Range(0, 65536));
  add(app, "max_piece_faces", o.max_piece_faces)->check([](const std::string& value) {
    return value.find('-') == std::string::npos ? std::string() : "must be 0 or more, not " + value;
  });
  add(app, "balance", o.balance)->check(CLI::Range(0.0, 1.0));
  add(app, "corners", given.corners)->check(CLI::IsMember(names_of(kCornerRules)));
  auto* no_fit = add_flag(app, "fit", given.no_fit);
  add_flag(app, "fine_fit", o.fine_fit)->excludes(no_fit);
  add(app, "material_map_budget_db", o.material_map_budget_db)->check(CLI::Range(0.0, 99.0));
  add_flag(app, "allow_large_textures", o.allow_large_textures);
  add_flag(app, "allow_outside_files", o.allow_outside_files);
  add(app, "max_memory_mib", o.max_memory_mib)->check(CLI::PositiveNumber);
  add(app, "layout", given.layout)->check(CLI::IsMember(names_of(kLayouts)));
  define_encoding_flags(app, o, given);
  add(app, "model_format", given.output_format)->check(CLI::IsMember(names_of(kModelFormats)));
  add(app, "holes", given.holes)->check(CLI::IsMember(names_of(kHoleModes)));
  add(app, "report_path", o.report_path);
  add(app, "preview_path", o.preview_path);
  add_flag(app, "html", given.no_html);
  app.add_flag("-q,--quiet", line.quiet, "print nothing but errors");
  app.add_flag("-v,--verbose", line.verbose, "print the report's main figures");
}

constexpr const char* kDescription =
    "tightex: one compact texture per surface, from a scan's fragmented UV atlas\n"
    "(global parameterization by a harmonic map onto a square; Chen et al., arXiv 2406.04115)";

/// The command line once CLI11 has parsed it into `line` and `given`: the Options fields that the
/// flags give indirectly.
void finish_command_line(CommandLine& line, const GivenFlags& given) {
  Options& o = line.options;
  o.layout = parsed(kLayouts, given.layout);
  o.holes = parsed(kHoleModes, given.holes);
  o.map = parsed(kMapKinds, given.map);
  o.corners = parsed(kCornerRules, given.corners);
  if (!given.format.empty()) o.texture_format = parsed(kImageFormats, given.format);
  if (!given.output_format.empty()) o.model_format = parsed(kModelFormats, given.output_format);
  if (given.png->count() > 0) o.png_level = given.png_level == "fast" ? kPngLevelFast : std::stoi(given.png_level);
  if (given.jpeg->count() > 0) o.jpeg_quality = given.jpeg_quality;
  if (given.webp->count() > 0) o.webp_quality = given.webp_quality;
  // --size promises a side: a square unless a shape is asked for, which the library's Options::aspect 0
  // means with a size (effective_aspect); "auto" chooses the shape even then.
  o.aspect = given.aspect.empty() ? 0.0 : given.aspect == "auto" ? kAspectAuto : std::stod(given.aspect);
  o.fit = !given.no_fit;
  o.html = !given.no_html;
}

/// The progress line on a terminal's stderr.
bool print_progress(std::string_view stage, double f) {
  if (f > 0 && f < 1)
    fmt::print(stderr, "\r\033[Ktightex: {} {:.0f}%...", stage, 100 * f);
  else
    fmt::print(stderr, "\r\033[Ktightex: {}...", stage);
  return true;
}

/// The one-line summary (and with --verbose the metrics) on stdout.
void print_summary(const CommandLine& line, const Report& r) {
  // The new texture's size (the first of several: per-component layout).
  std::string texture;
  if (!r.texture_sizes.empty())
    texture = fmt::format("{}x{}{} texture, ", r.texture_sizes[0].first, r.texture_sizes[0].second, r.texture_sizes.size() > 1 ? " +" : "");
  fmt::print(
      "tightex: {} -> {}/{}  ({}{} components, {:.1f}% -> {:.1f}% texels used, {} charts, "
      "PSNR {:.1f} dB as written ({:.1f} baked), textures {:.0f} -> {:.0f} KiB {}, {} lost, {} flipped, {:.2f} s)\n",
      line.input, line.outdir, fs::path(r.model_path).filename().string(), texture, r.components, 100 * r.input_texels_used,
      100 * r.output_texels_used, r.charts, r.surface_psnr_db, r.surface_psnr_bake_db, double(r.input_texture_bytes) / 1024,
      double(r.output_texture_bytes) / 1024, r.texture_format, r.lost_triangles, r.flipped_triangles, r.wall_seconds);
  if (line.verbose) fmt::print("{}\n", report_json(r)["metrics"].dump(2));
}

}  // namespace

std::optional<CommandLine> parse_command_line(int argc, char** argv, int& exit_code) {
  CLI::App app{kDescription, "tightex"};  // named, so that --help reads the same whatever path started it
  CommandLine line;
  GivenFlags given;
  define_flags(app, line, given);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    exit_code = app.exit(e) == 0 ? 0 : 1;
    return std::nullopt;
  }
  finish_command_line(line, given);
  return line;
}

CommandLine parse_arguments(const std::vector<std::string>& args) {
  CLI::App app{kDescription, "tightex"};  // named, so that --help reads the same whatever path started it
  CommandLine line;
  GivenFlags given;
  define_flags(app, line, given);
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    fail_input("options: --help: the options are those `tightex --help` lists");
  } catch (const CLI::CallForVersion&) {
    fail_input("options: --version: the version is tightex.__version__");
  } catch (const CLI::ParseError& e) {
    fail_input("options: {}", e.what());
  }
  finish_command_line(line, given);
  return line;
}

Report run_command(const CommandLine& line) {
  const bool show_progress = !line.quiet && isatty(STDERR_FILENO);
  Options options = line.options;
  if (show_progress) options.progress = print_progress;
  const Report report = run(line.input, line.outdir, options);
  if (show_progress) fmt::print(stderr, "\r\033[K");
  if (line.quiet) return report;
  for (const std::string& w : report.warnings) fmt::print(stderr, "tightex: warning: {}\n", w);
  for (const std::string& n : report.notes) fmt::print(stderr, "tightex: note: {}\n", n);
  print_summary(line, report);
  fmt::print("tightex: report: {}\n", report.report_path);
  return report;
}

}  // namespace tightex::cli
