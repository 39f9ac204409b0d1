// The tightex command as a library (command.hpp): the options' one definition, and the run from an
// input file to the written model, report and figures.
#include "cli/command.hpp"

#include <unistd.h>

#include <tbb/parallel_invoke.h>

#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <array>
#include <chrono>
#include <numeric>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "core/resources.hpp"
#include "io/model_files.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "io/output_files.hpp"
#include "report/html_report.hpp"
#include "report/metrics.hpp"
#include "report/preview.hpp"
#include "report/report.hpp"
#include "cli/texture_bytes.hpp"

namespace fs = std::filesystem;

namespace tightex::cli {

/// The --output-format names, in ModelFormat's order, each also its file extension.
constexpr std::array<const char*, 4> kModelFormatNames{"obj", "ply", "gltf", "glb"};

/// The model format a file's extension names (without case): .ply, .gltf, .glb, else OBJ.
ModelFormat model_format_of(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  for (size_t i = 1; i < kModelFormatNames.size(); ++i)
    if (equals_ignoring_case(extension, std::string(".") + kModelFormatNames[i])) return ModelFormat(i);
  return ModelFormat::kObj;
}

namespace {
fs::path temporary_beside(const fs::path& path) { return path.parent_path() / ("." + path.filename().string() + ".tmp"); }

/// Writes each text to its path under a temporary name, and only once all are written renames them
/// into place, in order: a reader never sees one file of the set without the others written. Throws
/// InputError naming the path that cannot be written or renamed (the temporary files are removed then).
void write_texts_atomically(const std::vector<std::pair<fs::path, std::string>>& files) {
  std::error_code ec;
  auto remove_temporaries = [&] {
    for (const auto& [path, text] : files) fs::remove(temporary_beside(path), ec);
  };
  for (const auto& [path, text] : files) {
    std::ofstream f(temporary_beside(path), std::ios::binary);
    if (f) f << text;
    if (!f) {
      f.close();
      remove_temporaries();
      fail_input("{}: cannot write", path.string());
    }
  }
  for (const auto& [path, text] : files) {
    fs::rename(temporary_beside(path), path, ec);
    if (ec) {
      remove_temporaries();
      fail_input("{}: cannot rename into place", path.string());
    }
  }
}

/// Seconds from t0 to now.
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

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

/// The option names as given on the command line, before they become enum values.
struct ChoiceNames {
  std::string layout, format, holes, map, corners;  // format empty: the input's
  std::string output_format;  // empty: not given
};

/// Declares --png-level and --jpeg-quality, and refuses each beside the other format (it would do nothing).
void define_encoding_options(CLI::App& app, CommandLine& line, const ChoiceNames& names) {
  auto* png_level = app.add_option("--png-level", line.encoding.png_level,
                                   "PNG textures: zlib level 0..9 with the adaptive filter (9: the smallest files, about a tenth "
                                   "smaller than the default, many times slower to write). Default: fast settings (level 1, "
                                   "run-length matches, the Up filter)")
                        ->check(CLI::Range(0, 9));
  auto* jpeg_quality = app.add_option("--jpeg-quality", line.encoding.jpeg_quality,
                                      "JPEG textures: quality 1..100 (default: rate control, see --format)")
                           ->check(CLI::Range(1, 100));
  auto* webp_quality = app.add_option("--webp-quality", line.encoding.webp_quality,
                                      "lossy WebP textures: quality 1..100 (default: rate control, see --format)")
                           ->check(CLI::Range(1, 100));
  auto* webp_lossless = app.add_flag("--webp-lossless", line.encoding.webp_lossless, "WebP textures: lossless (with --format webp)");
  auto* target = app.add_option("--target-psnr", line.target_psnr_db,
                                "lossy textures: the fewest bytes whose written images reach this surface PSNR against the input (dB): the "
                                "quality and, without --size or --texels, the texel budget")
                     ->check(CLI::Range(1.0, 99.0));
  auto* max_bytes = app.add_option("--max-bytes", line.max_bytes, "lossy textures: the highest quality whose images take at most this many bytes")
                        ->check(CLI::PositiveNumber);
  app.callback([png_level, jpeg_quality, webp_quality, webp_lossless, target, max_bytes, &names, &line] {
    auto needs = [&](const CLI::Option* o, const char* option, std::initializer_list<const char*> formats) {
      if (o->count() == 0 || names.format.empty()) return;
      for (const char* f : formats)
        if (names.format == f) return;
      throw CLI::ValidationError(option, fmt::format("needs --format {} (does nothing with --format {})", *formats.begin(), names.format));
    };
    needs(png_level, "--png-level", {"png"});
    needs(jpeg_quality, "--jpeg-quality", {"jpg"});
    needs(webp_quality, "--webp-quality", {"webp"});
    needs(webp_lossless, "--webp-lossless", {"webp"});
    needs(target, "--target-psnr", {"jpg", "webp"});
    needs(max_bytes, "--max-bytes", {"jpg", "webp"});
    if (target->count() > 0 && max_bytes->count() > 0) throw CLI::ValidationError("--target-psnr", "goes without --max-bytes");
    if ((target->count() > 0 || max_bytes->count() > 0) && (jpeg_quality->count() > 0 || webp_quality->count() > 0))
      throw CLI::ValidationError("--target-psnr/--max-bytes", "choose the quality: they go without --jpeg-quality and --webp-quality");
    line.quality_given = jpeg_quality->count() > 0 || webp_quality->count() > 0;
    for (const auto* o : {png_level, jpeg_quality, webp_quality, webp_lossless})
      if (o->count() > 0) line.codec_options.push_back(o->get_name());
  });
}

/// Declares every option of the main command on `app`, bound to `line` and `names`. Returns --size's
/// option, whose count says whether it was given.
CLI::Option* define_options(CLI::App& app, CommandLine& line, ChoiceNames& names) {
  names.layout = to_string(line.layout), names.holes = to_string(line.holes), names.map = to_string(line.map);
  names.corners = to_string(line.corners);
  app.add_option("input", line.input,
                 "textured model: OBJ + MTL, PLY, glTF (.gltf) or GLB, with its textures or vertex colours (3D Tiles: python3 -m "
                 "tightex.tiles)")
      ->required();
  app.add_option("-o,--output", line.outdir, "output directory")->required();
  auto* size_opt =
      app.add_option("--size", line.size,
                     "texture side in texels (per-component: of the largest component); above 16384 needs --force. "
                     "Default: the side that holds as many texels as the input uses (per-component: all the textures together; "
                     "grown if the atlas cannot hold a 4x4 rectangle per component; see --texels)")
          ->check(CLI::Range(8, 65536));
  app.add_option("--texels", line.texels,
                 "texel budget: the texture holds this many texels: the smallest square (side a multiple of 4), or as many "
                 "in the shape --aspect gives or chooses (per-component: the largest component's texture). "
                 "Default: the input's used texels, so the output keeps the input's information")
      ->check(CLI::PositiveNumber)
      ->excludes(size_opt);
  app.add_option("--map", names.map,
                 "detail (default): texels where the input texture has detail (colour gradient per 3D length), "
                 "capped at 4x the input's own density; area: the same texels per unit of 3D area everywhere; "
                 "texel: the input's own texel density per triangle; harmonic: the paper's map exactly (docs/maps.md)")
      ->check(CLI::IsMember(names_of(kMapKinds)));
  app.add_option("--aspect", line.aspect,
                 "width/height of the texture, which holds as many texels as a square would: auto (default, area/texel/detail "
                 "maps): the component holding most of the texture is mapped at 1:1 and, where its texels are stretched, at "
                 "the 2:1 or 1:2 the stretch points to, and the shape whose texels keep the most of the input is chosen "
                 "(the square unless the other is clearly better); a number "
                 "(e.g. 2) fixes it. With --size the default is 1, a square of that side")
      ->check(check_aspect);
  app.add_option("--max-size", line.max_size,
                 "atlas: the largest side of a texture page (default 8192, what WebGL and most engines accept; Cesium ion's cap is "
                 "16384; 0: no cap). A budget that does not fit one page goes on several, each component whole on one page; a "
                 "component too large for a page is split into pieces that fit, each its own chart (report: \"pages\")")
      ->check(CLI::Range(0, 65536));
  app.add_option("--max-piece-faces", line.max_piece_faces,
                 "the most triangles one chart holds (default 6000000; 0: no cap). A larger component is split into "
                 "pieces, each its own chart, so that the map's memory stays about proportional to the triangles (a 10M-face "
                 "component in one chart needs about 18 GiB, in two about 12)")
      ->check([](const std::string& value) {
        return value.find('-') == std::string::npos ? std::string() : "must be 0 or more, not " + value;
      });
  app.add_option("--balance", line.balance,
                 "area/texel/detail maps: 1 = target density exactly, 0 = the harmonic map's density (least angle "
                 "distortion); between: a geometric blend")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--corners", names.corners,
                 "which boundary points become the square's corners: arcs (default): four arcs of equal "
                 "length; turning: where the boundary turns most (docs/corners.md)")
      ->check(CLI::IsMember(names_of(kCornerRules)));
  auto* no_fit_opt = app.add_flag("--no-fit", line.no_fit, "bake each texel by sampling only, without the least-squares fit to the input");
  app.add_flag("--fine-fit", line.fine_fit,
               "fit on 4x4 points per texel instead of 2x2: a little higher surface PSNR, about twice the bake time")
      ->excludes(no_fit_opt);
  app.add_flag("--linear-light-colour", line.linear_light_colour, "filter the base colour in linear light (measurement only)")
      ->group("");  // hidden: Options::linear_light_colour
  app.add_option("--map-budget", line.map_budget_db,
                 "maps other than the base colour (metallic-roughness, occlusion, emissive, normal, specular, ...): a map some "
                 "slot of which (each over the channels it reads) is below this many surface-PSNR dB against the input's map at "
                 "the base colour's size may be baked larger, up to as many texels as its input image has, while a slot falls "
                 "short of what the map check asks (the base colour's PSNR plus an ideal re-sampler's difference, at most this) "
                 "and each step pays for its texels (removes as much error per added texel as the base colour's texels do); "
                 "any other map is halved (down to 1/16 of the base colour's side) while each slot stays at or above this or "
                 "within 0.25 dB of the base colour's size's (a normal map: against itself at full size, never larger); "
                 "default 51; 0 keeps every map at the base colour's size")
      ->check(CLI::Range(0.0, 99.0));
  app.add_flag("--force", line.force, "allow --size above 16384");
  app.add_option("--max-memory", line.max_memory_mib, "refuse inputs whose estimated memory exceeds this many MiB (default: 90% of RAM)")
      ->check(CLI::PositiveNumber);
  app.add_option("--layout", names.layout, "atlas: all components in one texture; per-component: one texture each (the paper's)")
      ->check(CLI::IsMember(names_of(kLayouts)));
  app.add_option("--format", names.format,
                 "texture file format: png, jpg or webp. Default: the input's base colour's (PNG for vertex colours or mixed "
                 "inputs); a lossy one at the highest quality whose images take no more bytes than the input's")
      ->check(CLI::IsMember({"png", "jpg", "webp"}));
  define_encoding_options(app, line, names);
  app.add_option("--output-format", names.output_format,
                 "model file format: obj (OBJ + MTL), ply (binary PLY, textures named by comment TextureFile), gltf (.gltf + .bin "
                 "+ texture files) or glb. Default: the input's kind (.ply, .gltf or .glb as the input, anything else .obj)")
      ->check(CLI::IsMember({"obj", "ply", "gltf", "glb"}));
  app.add_option("--holes", names.holes, "fill: cap holes with scaffolding (paper §4.1); cut: open them into the seam")
      ->check(CLI::IsMember(names_of(kHoleModes)));
  app.add_option("--report", line.report_path, "where to write the JSON report (default OUTDIR/report.json)");
  app.add_option("--preview", line.preview_path, "write a PNG of the input texture(s) beside the output texture");
  app.add_flag("--no-html", line.no_html,
               "do not write OUTDIR/report.html (the figures, atlases, components and a 3D before/after viewer in one "
               "self-contained page)");
  app.add_flag("-q,--quiet", line.quiet, "print nothing but errors");
  app.add_flag("-v,--verbose", line.verbose, "print the report's main figures");
  return size_opt;
}

constexpr const char* kDescription =
    "tightex: one compact texture per surface, from a scan's fragmented UV atlas\n"
    "(global parameterization by a harmonic map onto a square; Chen et al., arXiv 2406.04115)";

/// The command line once CLI11 has parsed it into `line` and `names`: the enum values, whether --size
/// was given, the output format.
void finish_command_line(CommandLine& line, const ChoiceNames& names, const CLI::Option* size_opt) {
  line.size_given = size_opt->count() > 0;
  line.layout = parsed(kLayouts, names.layout);
  line.holes = parsed(kHoleModes, names.holes);
  line.map = parsed(kMapKinds, names.map);
  line.corners = parsed(kCornerRules, names.corners);
  if (!names.format.empty())
    line.image_format = names.format == "png" ? ImageFormat::kPng : names.format == "jpg" ? ImageFormat::kJpeg : ImageFormat::kWebp;
  line.encoding.format = line.image_format.value_or(ImageFormat::kPng);
  line.output_format = model_format_of(line.input);
  for (size_t i = 0; i < kModelFormatNames.size(); ++i)
    if (names.output_format == kModelFormatNames[i]) line.output_format = ModelFormat(i);
}

/// The output model's file name inside the output folder: the input's stem and the output format's
/// extension.
std::string output_model_name(const CommandLine& line) {
  return fs::path(line.input).stem().string() + "." + kModelFormatNames[size_t(line.output_format)];
}

/// Refuses an input that is a folder, an output folder that cannot be created or written into
/// (check_output_folder: before the work, not after it), and an output folder that is the input's own:
/// the outputs are named after the input, so written there they would replace it or lie among its
/// files. Throws InputError.
void check_paths(const CommandLine& line) {
  if (fs::is_directory(line.input)) fail_input("{}: is a directory, not a model file", line.input);
  check_output_folder(line.outdir);
  std::error_code ec;
  const fs::path in_dir = fs::absolute(fs::path(line.input)).parent_path();
  if (fs::exists(line.outdir, ec) && fs::exists(in_dir, ec) && fs::equivalent(line.outdir, in_dir, ec)) {
    const std::string model = output_model_name(line);
    const bool replaces = model == fs::path(line.input).filename().string();
    fail_input("{}: the output folder {} is the input's own folder; {} would {} (choose another -o)", line.input, line.outdir, model,
               replaces ? "replace the input" : "be written among the input's files");
  }
}

/// The texture side: --size, else the side for --texels, else the default for the input's used texels
/// (at most 16384 without --force). Throws InputError for a side above 16384 without --force.
int texture_side(const CommandLine& line, const TexturedMesh& geometry) {
  int size = line.size;
  if (size == 0) {
    const int max_side = line.force ? 65536 : kDefaultSizeMax;
    size = line.texels > 0 ? std::min(size_for_texels(line.texels), max_side) : default_size(geometry, max_side);
  }
  if (size > 16384 && !line.force)
    fail_input("--size {} is above 16384 ({:.1f} GiB of RGBA texture); add --force to allow it", size,
               double(size) * size * 4 / double(1 << 30));
  return size;
}

/// Memory a run needs whatever the model (the process, its pools, the other maps' images and the
/// report's pictures), per input triangle (the mesh and its stages, with components of at most
/// Options::max_piece_faces) and per output texel and image (RGBA and the bake's coverage masks), in
/// bytes: at or above the peaks measured from 1k to 10M triangles (BENCHMARKS.md, "Memory").
constexpr double kBaseBytes = 256.0 * (1 << 20);
constexpr double kBytesPerTriangle = 1500.0;
constexpr double kBytesPerOutputTexel = 7.0;

/// The resource guard: refuses a run whose estimated memory is above --max-memory (default 90% of RAM)
/// before any pixel is allocated.
struct MemoryGuard {
  std::string input;
  double limit_mib = 0;
  /// The memory before the per-component output textures: decoded input textures (RGBA), the mesh and
  /// its stages, and for the atlas the output texture.
  double estimate = 0;
  /// Output images per base colour texel (output_images).
  double output_images = 1;

  /// Throws InputError naming `what` if `bytes` is above the limit.
  void check(double bytes, const std::string& what) const {
    if (bytes / double(1 << 20) > limit_mib)
      fail_input("{}: {} needs about {:.0f} MiB, more than the limit of {:.0f} MiB (--max-memory)", input, what, bytes / double(1 << 20),
                 limit_mib);
  }
};

/// The guard for this command line: --max-memory, or 90% of this machine's memory.
MemoryGuard memory_guard(const CommandLine& line) {
  MemoryGuard guard;
  guard.input = line.input;
  guard.limit_mib = line.max_memory_mib > 0 ? line.max_memory_mib
                                            : 0.9 * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE)) / double(1 << 20);
  return guard;
}

/// Refuses, from the image headers alone, a texture whose decoded pixels would not fit the limit (a
/// hostile header can declare 200000 x 200000 pixels); before anything is sized by those pixels.
void check_texture_headers(const MemoryGuard& guard, const TexturedMesh& geometry) {
  for (const Texture& t : geometry.textures)
    guard.check(double(t.width) * double(t.height) * 4.0, fmt::format("texture {} ({} x {} pixels)", t.path, t.width, t.height));
}

/// The output images baked per base colour texel: the base colour's and one per map slot some
/// material binds (a slot may share another's image, or be baked larger: one each is the estimate).
double output_images(const TexturedMesh& geometry) {
  std::array<bool, kMapSlots> bound{};
  for (const Material& m : geometry.materials)
    for (size_t s = 0; s < kMapSlots; ++s) bound[s] = bound[s] || m.maps[s] >= 0;
  return 1.0 + double(std::count(bound.begin(), bound.end(), true));
}

/// Checks the memory the model needs at this size; per-component outputs are checked once the layout
/// is known (check_per_component_memory).
MemoryGuard check_memory(const CommandLine& line, const TexturedMesh& geometry, int size) {
  MemoryGuard guard = memory_guard(line);
  guard.estimate = kBaseBytes + double(geometry.num_triangles()) * kBytesPerTriangle;
  for (const Texture& t : geometry.textures) guard.estimate += double(t.width) * double(t.height) * 4.0;
  guard.output_images = output_images(geometry);
  if (line.layout == Layout::kAtlas) guard.estimate += double(size) * double(size) * kBytesPerOutputTexel * guard.output_images;
  guard.check(guard.estimate, "this model at this --size");
  return guard;
}

/// Checks the memory of the per-component layout's output textures, now that the plan has sized them.
void check_per_component_memory(const MemoryGuard& guard, const Plan& plan) {
  double out_texels = 0;
  for (const auto& [w, h] : plan.texture_sizes()) out_texels += double(w) * double(h);
  guard.check(guard.estimate + out_texels * kBytesPerOutputTexel * guard.output_images, "this model's per-component textures");
}

/// The library's options for this command line at texture side `size`. Metrics are left to the CLI,
/// which measures beside the write.
Options library_options(const CommandLine& line, int size, ProgressCallback progress) {
  Options opt;
  opt.size = size;
  opt.default_budget = !line.size_given && !(line.texels > 0);
  opt.layout = line.layout;
  opt.holes = line.holes;
  opt.map = line.map;
  opt.balance = line.balance;
  // --size promises a side: a square, unless a shape is asked for.
  opt.aspect = line.aspect.empty() ? (line.size_given ? 1.0 : 0.0) : line.aspect == "auto" ? 0.0 : std::stod(line.aspect);
  opt.corners = line.corners;
  opt.max_page_side = line.max_size;
  opt.max_piece_faces = line.max_piece_faces;
  opt.fit = !line.no_fit;
  opt.fine_fit = line.fine_fit;
  opt.linear_light_colour = line.linear_light_colour;
  opt.map_budget_db = line.map_budget_db;
  opt.measure = false;
  opt.keep_untextured = line.output_format != ModelFormat::kPly;  // PLY has no material for an untextured colour
  opt.progress = std::move(progress);
  return opt;
}

/// The progress line on a terminal's stderr.
bool print_progress(std::string_view stage, double f) {
  if (f > 0 && f < 1)
    fmt::print(stderr, "\r\033[Ktightex: {} {:.0f}%...", stage, 100 * f);
  else
    fmt::print(stderr, "\r\033[Ktightex: {}...", stage);
  return true;
}

/// The model with its texture pixels and the plan made from it.
struct PlannedModel {
  TexturedMesh mesh;
  Plan plan;
  double textures_s = 0;  // when the textures were read, in seconds from the start
};

/// Decodes the textures of `geometry` (read without pixels), which becomes the planned model, and plans
/// the charts. The geometric stages need no pixels, so the textures are decoded beside them, unless the
/// plan needs the pixels (the detail map places texels by them, the auto aspect compares its shapes
/// with them): then only the preparation (repair, components, seams, handles) is made beside them, and
/// the rest after. A texture error is thrown before a plan error: a bad texture is the user's first
/// problem.
PlannedModel read_textures_and_plan(TexturedMesh geometry, const Options& opt, std::chrono::steady_clock::time_point t0) {
  PlannedModel r;
  std::exception_ptr texture_error, plan_error;
  std::vector<Texture> textures;
  auto read_textures = [&] {
    try {
      textures = load_texture_pixels(geometry, ObjReadOptions{}.max_texture_pixels);
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
      opt.map == MapKind::kDetail || (opt.aspect == 0 && opt.map != MapKind::kHarmonic && opt.layout == Layout::kAtlas);
  PreparedMesh prepared;
  tbb::parallel_invoke(read_textures, [&] {
    planning([&] {
      if (plan_needs_pixels)
        prepared = prepare_mesh(geometry, opt);
      else
        r.plan = plan_charts(geometry, opt);
    });
  });
  r.mesh = std::move(geometry);
  if (!texture_error) r.mesh.textures = std::move(textures);
  if (plan_needs_pixels && !texture_error && !plan_error) planning([&] { r.plan = plan_charts(r.mesh, opt, std::move(prepared)); });
  if (texture_error) std::rethrow_exception(texture_error);
  if (plan_error) std::rethrow_exception(plan_error);
  return r;
}

/// One line each where the result is not what was asked: components kept as they were (Plan::kept),
/// and the default budget grown to hold every component (Options::default_budget).
void print_notes(const Plan& plan, const nlohmann::json& report) {
  if (const size_t kept_components = plan.kept_components(); kept_components > 0)
    fmt::print(stderr,
               "tightex: warning: {} component(s), {} triangles, could not be re-parameterized and keep their original "
               "texture coordinates and texture(s) ({}); see \"kept_original_uvs\" in the report\n",
               kept_components, plan.kept_triangles(), plan.first_kept_reason());
  const nlohmann::json& prep = report["preparation"];
  if (const size_t untextured = prep["untextured_kept"].get<size_t>(); untextured > 0)
    fmt::print(stderr, "tightex: warning: {} triangles have no texture to bake from (no texture, no vertex colours) and are written as they came\n",
               untextured);
  if (const size_t repeats = prep["exact_repeats_copied"].get<size_t>(); repeats > 0)
    fmt::print(stderr,
               "tightex: warning: {} triangles repeat another of their mesh exactly (positions, texture coordinates, material): each is "
               "written as a copy of the one it repeats\n",
               repeats);
  if (const auto& grown = report["options"]["size_grown_from"]; !grown.is_null())
    fmt::print(stderr,
               "tightex: note: {} components need a 4x4 texel rectangle each: the texture grew from {}^2 to {}^2 texels (--size sets it)\n",
               report["preparation"]["components"].get<size_t>(), grown.get<int>(), report["options"]["size"].get<int>());
}

/// How long the CLI's own stages took, in seconds (read_s, textures_s from the start), and the process's
/// CPU time while they ran (read: from the start; write, measure and the page's data: each from the
/// start of the three to its own end).
struct CliTimings {
  double read_s = 0, textures_s = 0, write_s = 0, measure_s = 0, html_s = 0;
  CpuTimes read_cpu, write_cpu, measure_cpu, html_cpu;
};

/// What the run's last stage gives: the output's metrics, what the writer left out, and report.html's
/// model data (empty with --no-html).
struct WrittenAndMeasured {
  Metrics metrics;
  std::vector<std::string> removed;
  std::string html_data;
};

/// Writes the output model in the command line's format. Returns what the writer left out: what the
/// glTF writer removed, or the map slots OBJ or PLY cannot bind.
std::vector<std::string> write_model(const CommandLine& line, const TexturedMesh& output, const std::string& name) {
  switch (line.output_format) {
    case ModelFormat::kPly:
      return write_ply(output, line.outdir, name, line.encoding);
    case ModelFormat::kGltf:
      return write_gltf(output, line.outdir, name, line.encoding, GltfContainer::kGltf);
    case ModelFormat::kGlb:
      return write_gltf(output, line.outdir, name, line.encoding, GltfContainer::kGlb);
    case ModelFormat::kObj:
      break;
  }
  return write_obj(output, line.outdir, name, line.encoding);
}

/// Writes the output model, measures it and gathers report.html's model data (the models' shown
/// triangles, their textures as JPEG), side by side: the three are independent. The times go to
/// `timings`.
WrittenAndMeasured write_and_measure(const CommandLine& line, const TexturedMesh& input, const TexturedMesh& output,
                                     const std::string& name, CliTimings& timings) {
  const auto tw = std::chrono::steady_clock::now();
  const CpuTimes cpu_before = process_cpu_times();
  const auto cpu_since = [&] {
    const CpuTimes now = process_cpu_times();
    return CpuTimes{now.user - cpu_before.user, now.sys - cpu_before.sys};
  };
  WrittenAndMeasured r;
  nlohmann::json html_data;
  auto measure_and_gather = [&] {
    // The models' welded edges once, for the measure's charts and the page's seams.
    WeldedEdges input_edges, output_edges;
    tbb::parallel_invoke([&] { input_edges = welded_edges(input); }, [&] { output_edges = welded_edges(output); });
    tbb::parallel_invoke(
        [&] {
          r.metrics = measure(input, output, input_edges, output_edges);
          timings.measure_s = seconds_since(tw);
          timings.measure_cpu = cpu_since();
        },
        [&] {
          if (line.no_html) return;
          html_data = html_model_data_without_charts(input, output, input_edges, output_edges);
          timings.html_s = seconds_since(tw);
          timings.html_cpu = cpu_since();
        });
  };
  tbb::parallel_invoke(
      [&] {
        r.removed = write_model(line, output, name);
        timings.write_s = seconds_since(tw);
        timings.write_cpu = cpu_since();
      },
      measure_and_gather);
  // The page's chart counts are the measure's.
  if (!line.no_html) r.html_data = html_model_data(std::move(html_data), r.metrics.charts_input, r.metrics.charts);
  return r;
}

/// Adds what the CLI knows to the library's report: the metrics, its own stages' times (reading first,
/// writing and measuring last), wall time, peak RSS, the reader's figures and the output files.
void add_cli_figures(nlohmann::json& rep, const Metrics& metrics, const CliTimings& t, double wall_seconds, const ObjReadStats& read_stats,
                     const OutputFiles& files) {
  rep["metrics"] = to_json(metrics);
  nlohmann::json& timings = rep["timings"];
  auto timing = [](const char* stage, double seconds, const CpuTimes& cpu) {
    return to_json(StageTiming{stage, seconds, std::nullopt, cpu.user, cpu.sys});
  };
  timings.push_back(timing("write (beside measure)", t.write_s, t.write_cpu));
  timings.push_back(timing("measure (beside write)", t.measure_s, t.measure_cpu));
  if (t.html_s > 0) timings.push_back(timing("report.html data (beside write and measure)", t.html_s, t.html_cpu));
  timings.insert(timings.begin(), timing("read geometry", t.read_s, t.read_cpu));
  timings.insert(timings.begin() + 1, to_json(StageTiming{"read textures (beside the geometric stages, from start)", t.textures_s,
                                                          std::nullopt, std::nullopt, std::nullopt}));
  rep["wall_seconds"] = wall_seconds;
  rep["peak_rss_mib"] = peak_rss_mib();
  rep["input"].update(reader_json(read_stats));
  rep["output"] = to_json(files);
}

/// Writes the preview picture under a temporary name, then renames it into place.
void write_preview(const std::string& preview_path, const TexturedMesh& input, const TexturedMesh& output) {
  const fs::path p(preview_path);
  const fs::path tmp = temporary_beside(p);
  save_image(tmp.string(), make_preview(input, output), ImageFormat::kPng);
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) fail_input("{}: cannot write preview ({})", preview_path, ec.message());
}

/// One warning line each for what the output does not carry: the input's parts the reader left as they
/// were (written back only to glTF), what the glTF writer removed (texture slots that cannot follow
/// the new texture coordinates; one line), and each map slot OBJ or PLY cannot bind (one line each).
/// The input's textured materials whose colour factor is not white (read from glTF: the factor a
/// glTF output keeps in its material, which OBJ and PLY outputs lose).
size_t tinted_textures(const TexturedMesh& input) {
  if (!input.gltf) return 0;
  size_t n = 0;
  for (const Material& m : input.materials) n += m.texture >= 0 && (m.kd[0] != 1.0 || m.kd[1] != 1.0 || m.kd[2] != 1.0);
  return n;
}

void print_not_carried(const CommandLine& line, const TexturedMesh& input, const ObjReadStats& read_stats,
                       const std::vector<std::string>& removed) {
  const bool gltf = line.output_format == ModelFormat::kGltf || line.output_format == ModelFormat::kGlb;
  for (const std::string& w : read_stats.warnings) fmt::print(stderr, "tightex: warning: {}\n", w);
  if (read_stats.instances_flattened > 0)
    fmt::print(stderr, "tightex: note: the glTF scene's {} mesh instances are written in world space ({} has no scene graph)\n",
               read_stats.instances_flattened, kModelFormatNames[size_t(line.output_format)]);
  if (!gltf && tinted_textures(input) > 0)
    fmt::print(stderr,
               "tightex: warning: {} textured material(s) have a colour factor (glTF baseColorFactor) that {} cannot carry and the new "
               "texture does not hold; --output-format glb keeps it\n",
               tinted_textures(input), kModelFormatNames[size_t(line.output_format)]);
  if (!gltf && !read_stats.not_read.empty())
    fmt::print(
        stderr, "tightex: warning: {} {} of the input {} not written ({} has no place for them; --output-format glb keeps them): {}\n",
        read_stats.not_read.size(), read_stats.not_read.size() == 1 ? "part" : "parts", read_stats.not_read.size() == 1 ? "is" : "are",
        kModelFormatNames[size_t(line.output_format)], fmt::join(read_stats.not_read, ", "));
  if (gltf && !removed.empty())
    fmt::print(stderr, "tightex: warning: removed from the output, as they cannot follow the new texture coordinates: {}\n",
               fmt::join(removed, ", "));
  if (!gltf)
    for (const std::string& unbound : removed) fmt::print(stderr, "tightex: warning: {}\n", unbound);
}

/// The report page's file name in the output folder.
constexpr const char* kHtmlName = "report.html";

/// Writes report.json and, unless --no-html, OUTDIR/report.html (`model_data`: html_model_data's; the
/// page shows the same report as the file), renamed into place together, the JSON last. Returns the
/// report a reader opens: the page, or the JSON with --no-html. Throws InputError naming a file that
/// cannot be written.
fs::path write_reports(const CommandLine& line, const nlohmann::json& report, const std::string& model_data) {
  const fs::path json_path = line.report_path.empty() ? fs::path(line.outdir) / "report.json" : fs::path(line.report_path);
  if (line.no_html) {
    write_texts_atomically({{json_path, report.dump(2) + "\n"}});
    return json_path;
  }
  std::string json_text = report.dump(2) + "\n";
  std::string page = html_report_page(json_text, model_data);
  const fs::path html_path = fs::path(line.outdir) / kHtmlName;
  write_texts_atomically({{html_path, std::move(page)}, {json_path, std::move(json_text)}});
  return html_path;
}

/// The one-line summary (and with --verbose the metrics) on stdout.
void print_summary(const CommandLine& line, const TexturedMesh& output, size_t components, const Metrics& metrics,
                   const nlohmann::json& bytes, double wall_seconds) {
  // The new texture's size (the first of several: per-component layout).
  std::string texture;
  if (!output.textures.empty()) {
    const Image& img = output.textures[0].image;
    texture = fmt::format("{}x{}{} texture, ", img.width, img.height, output.textures.size() > 1 ? " +" : "");
  }
  fmt::print(
      "tightex: {} -> {}/{}  ({}{} components, {:.1f}% -> {:.1f}% texels used, {} charts, "
      "PSNR {:.1f} dB as written ({:.1f} baked), textures {:.0f} -> {:.0f} KiB {}, {} lost, {} flipped, {:.2f} s)\n",
      line.input, line.outdir, output_model_name(line), texture, components, 100 * metrics.input.utilization,
      100 * metrics.output.utilization, metrics.charts, metrics.surface_psnr, metrics.surface_psnr_bake.value_or(metrics.surface_psnr),
      bytes["input"]["total"].get<double>() / 1024, bytes["output"]["total"].get<double>() / 1024,
      bytes["encoding"]["format"].get<std::string>(), metrics.lost_triangles, metrics.flipped, wall_seconds);
  if (line.verbose) fmt::print("{}\n", to_json(metrics).dump(2));
}

BytesRequest bytes_request(const CommandLine& line) {
  return {line.image_format, line.encoding, line.quality_given, line.target_psnr_db, line.max_bytes};
}

/// Refuses --target-psnr or --max-bytes where the images will be written losslessly (no --format, and
/// the input's base colour is PNG): they choose a lossy codec's quality.
void check_rate_control(const CommandLine& line, const TexturedMesh& geometry) {
  const bool rate = line.target_psnr_db > 0 || line.max_bytes > 0;
  if ((!rate && line.codec_options.empty()) || line.image_format) return;  // with --format, the parser checked them
  const ImageFormat f = base_colour_format(geometry, texture_sources(geometry)).value_or(ImageFormat::kPng);
  const char* name = f == ImageFormat::kJpeg ? "jpg" : f == ImageFormat::kWebp ? "webp" : "png";
  if (rate && f == ImageFormat::kPng)
    fail_input("{}: --target-psnr and --max-bytes choose a lossy codec's quality, and this input's images would be written as PNG: "
               "add --format webp or --format jpg",
               line.input);
  for (const std::string& option : line.codec_options) {
    const bool fits = (option == "--png-level" && f == ImageFormat::kPng) || (option == "--jpeg-quality" && f == ImageFormat::kJpeg) ||
                      (option.rfind("--webp", 0) == 0 && f == ImageFormat::kWebp);
    if (!fits)
      fail_input("{}: {} does nothing: the images are written as {}, the input's codec (--format chooses another)", line.input, option, name);
  }
}

/// Whether --target-psnr chooses the texel budget too: a lossy codec, and no budget given.
bool budget_follows_target(const CommandLine& line, const EncodingChoice& choice) {
  return line.target_psnr_db > 0 && choice.encoding.lossy() && !line.size_given && !(line.texels > 0);
}

/// The texel budgets --target-psnr tries, as fractions of the default's texels, largest first.
constexpr double kTargetBudgetFractions[] = {0.7, 0.5, 0.35, 0.25, 0.18};

/// --target-psnr's budget search: `result` and `choice` (the default budget's, at the lowest quality
/// that reaches the target as written) are replaced by a smaller budget's, re-planned and baked, where
/// it reaches the target in fewer bytes. Stops at the first budget that misses the target or takes more
/// bytes than the best so far. Returns each budget tried (side, quality, bytes, written PSNR).
nlohmann::json smallest_reaching_target(const CommandLine& line, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                                        const Options& opt, Result& result, EncodingChoice& choice) {
  auto total = [](const EncodingChoice& c) { return std::accumulate(c.bytes.begin(), c.bytes.end(), uint64_t(0)); };
  auto entry = [&](int side, const EncodingChoice& c) {
    return nlohmann::json{{"size", side},
                          {"quality", c.encoding.format == ImageFormat::kJpeg ? c.encoding.jpeg_quality : c.encoding.webp_quality},
                          {"bytes", total(c)},
                          {"surface_psnr_written_db", c.written_psnr_db.value_or(0)}};
  };
  nlohmann::json tried = nlohmann::json::array({entry(opt.size, choice)});
  if (!(choice.written_psnr_db.value_or(0) >= line.target_psnr_db)) return tried;  // the default budget misses it already
  for (const double fraction : kTargetBudgetFractions) {
    Options smaller = opt;
    smaller.size = std::max(8, int(std::lround(opt.size * std::sqrt(fraction) / 4)) * 4);
    smaller.progress = nullptr;
    Result r = bake_plan(plan_charts(input, smaller), input, smaller);
    EncodingChoice c = choose_encoding(bytes_request(line), input, sources, r.output);
    tried.push_back(entry(smaller.size, c));
    if (!(c.written_psnr_db.value_or(0) >= line.target_psnr_db) || total(c) >= total(choice)) break;
    c.reason += fmt::format("; a texel budget of {}^2 (of the default {}^2) reaches the target in the fewest bytes", smaller.size, opt.size);
    result = std::move(r), choice = std::move(c);
  }
  return tried;
}

/// The model's geometry (no pixels) with its textures' sizes from their headers, checked against the
/// memory limit; the reader's figures into `read_stats`.
TexturedMesh read_geometry(const CommandLine& line, ObjReadStats* read_stats) {
  ObjReadOptions geometry_only;
  geometry_only.load_textures = false;
  // OBJ and PLY have no scene graph: a glTF scene written as one is placed in world space.
  geometry_only.flatten_scene = line.output_format == ModelFormat::kObj || line.output_format == ModelFormat::kPly;
  TexturedMesh geometry = read_model(line.input, geometry_only, read_stats);
  for (Texture& t : geometry.textures)
    if (t.image.empty() && t.width == 0)  // a vertex-colour texture is made, a glTF's embedded image sized by its reader
      std::tie(t.width, t.height) = image_dimensions(t.path);
  check_texture_headers(memory_guard(line), geometry);
  return geometry;
}

}  // namespace

std::optional<CommandLine> parse_command_line(int argc, char** argv, int& exit_code) {
  CLI::App app{kDescription};
  CommandLine line;
  ChoiceNames names;
  const CLI::Option* size_opt = define_options(app, line, names);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    exit_code = app.exit(e) == 0 ? 0 : 1;
    return std::nullopt;
  }
  finish_command_line(line, names, size_opt);
  return line;
}

CommandLine parse_arguments(const std::vector<std::string>& args) {
  CLI::App app{kDescription};
  CommandLine line;
  ChoiceNames names;
  const CLI::Option* size_opt = define_options(app, line, names);
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    fail_input("options: --help: the options are those `tightex --help` lists");
  } catch (const CLI::ParseError& e) {
    fail_input("options: {}", e.what());
  }
  finish_command_line(line, names, size_opt);
  return line;
}

nlohmann::json run_command(const CommandLine& line, const CommandHooks& hooks) {
  const auto t0 = std::chrono::steady_clock::now();
  check_paths(line);
  // Geometry first; the texture pixels are decoded while the geometric stages run, into the same model
  // (each texture keeps where the model names it, for its error).
  CliTimings timings;
  ObjReadStats read_stats;
  TexturedMesh geometry = read_geometry(line, &read_stats);
  timings.read_s = seconds_since(t0);
  timings.read_cpu = process_cpu_times();
  check_rate_control(line, geometry);
  const int size = texture_side(line, geometry);
  const bool printing = hooks.print && !line.quiet;
  const bool show_progress = !hooks.progress && printing && isatty(STDERR_FILENO);
  const MemoryGuard guard = check_memory(line, geometry, size);
  const Options opt = library_options(line, size, show_progress ? ProgressCallback(print_progress) : hooks.progress);
  PlannedModel planned = read_textures_and_plan(std::move(geometry), opt, t0);
  timings.textures_s = planned.textures_s;
  if (line.layout != Layout::kAtlas) check_per_component_memory(guard, planned.plan);
  Result result = bake_plan(planned.plan, planned.mesh, opt);
  if (show_progress) fmt::print(stderr, "\r\033[K");
  if (printing) print_notes(planned.plan, planned.plan.report());

  // The images' codec and quality (the input's codec; rate control), then the model written with it.
  const std::vector<TextureSource> sources = texture_sources(planned.mesh);
  EncodingChoice choice = choose_encoding(bytes_request(line), planned.mesh, sources, result.output);
  nlohmann::json budgets;
  if (budget_follows_target(line, choice)) budgets = smallest_reaching_target(line, planned.mesh, sources, opt, result, choice);
  CommandLine encoded_line = line;
  encoded_line.encoding = choice.encoding;
  const std::string name = fs::path(line.input).stem().string();
  WrittenAndMeasured written = write_and_measure(encoded_line, planned.mesh, result.output, name, timings);
  // The surface PSNR of the files as written (a lossy codec's images decoded back), the bake's beside it.
  if (choice.written_psnr_db) written.metrics.surface_psnr_bake = std::exchange(written.metrics.surface_psnr, *choice.written_psnr_db);
  const Metrics& metrics = written.metrics;
  const std::vector<std::string>& removed = written.removed;
  if (printing) print_not_carried(line, planned.mesh, read_stats, removed);
  const double wall_seconds = seconds_since(t0);
  add_cli_figures(result.report, metrics, timings, wall_seconds, read_stats,
                  OutputFiles{line.outdir, output_model_name(line), line.no_html ? "" : kHtmlName, removed});
  result.report["bytes"] = bytes_json(planned.mesh, sources, result.output, choice, metrics.surface_psnr);
  result.report["bytes"]["surface_psnr_bake_db"] = metrics.surface_psnr_bake.value_or(metrics.surface_psnr);
  if (!budgets.is_null()) result.report["bytes"]["budgets_tried"] = budgets;
  if (!line.preview_path.empty()) write_preview(line.preview_path, planned.mesh, result.output);
  const fs::path report_path = write_reports(line, result.report, written.html_data);
  if (printing) {
    print_summary(line, result.output, result.report["preparation"]["components"].get<size_t>(), metrics, result.report["bytes"],
                  wall_seconds);
    fmt::print("tightex: report: {}\n", report_path.string());
  }
  return result.report;
}

double estimate_memory_bytes(const CommandLine& line) {
  const TexturedMesh geometry = read_geometry(line, nullptr);
  const int size = texture_side(line, geometry);
  CommandLine as_atlas = line;
  as_atlas.layout = Layout::kAtlas;
  as_atlas.max_memory_mib = std::numeric_limits<double>::max();
  return check_memory(as_atlas, geometry, size).estimate;
}

Result optimize_mesh(const CommandLine& line, const TexturedMesh& mesh, const ProgressCallback& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  check_texture_headers(memory_guard(line), mesh);
  const int size = texture_side(line, mesh);
  const MemoryGuard checked = check_memory(line, mesh, size);
  Options opt = library_options(line, size, progress);
  const Plan plan = plan_charts(mesh, opt);
  if (line.layout != Layout::kAtlas) check_per_component_memory(checked, plan);
  opt.measure = true;
  Result result = bake_plan(plan, mesh, opt);
  result.report["wall_seconds"] = seconds_since(t0);
  result.report["peak_rss_mib"] = peak_rss_mib();
  return result;
}

}  // namespace tightex::cli
