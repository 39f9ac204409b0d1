// The tightex command as a library: its options (one CLI11 definition parses and checks them) and the
// run from an input file to the written model, report and figures. The tightex executable and the
// Python module both call it, so they take the same options with the same defaults and checks.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "tightex/tightex.hpp"

namespace tightex::cli {

/// The kinds of model the command writes.
enum class ModelFormat { kObj, kPly, kGltf, kGlb };

/// The model format a file's extension names (without case): .ply, .gltf, .glb, else OBJ.
ModelFormat model_format_of(const std::string& path);

/// What the command line asks for.
struct CommandLine {
  std::string input, outdir;
  std::string report_path;             // empty: OUTDIR/report.json
  std::string preview_path;            // empty: no preview
  int size = 0;                        // 0: from --texels or the input's used texels
  bool size_given = false;             // --size was given (a promise of a side: a square unless --aspect)
  double texels = 0;                   // 0: not given
  std::string aspect;                  // empty, "auto" or a number
  int max_size = kDefaultMaxPageSide;  // --max-size: the largest side of a texture page (0: no cap)
  size_t max_piece_faces = kDefaultMaxPieceFaces;  // --max-piece-faces: the most triangles a chart holds (0: no cap)
  double balance = 1.0;
  Layout layout = Layout::kAtlas;
  HoleMode holes = HoleMode::kFill;
  MapKind map = MapKind::kDetail;
  CornerRule corners = CornerRule::kEqualArcs;
  ImageEncoding encoding;  // --png-level, --jpeg-quality, --webp-quality, --webp-lossless: how every texture image of the model is written
  std::optional<ImageFormat> image_format;  // --format; nullopt: the input's base colour codec (texture_bytes.hpp)
  bool quality_given = false;               // --jpeg-quality or --webp-quality given: no rate control
  std::vector<std::string> codec_options;   // the codec options given (--png-level ...): each checked against the codec written
  double target_psnr_db = 0;                // --target-psnr (0: none)
  uint64_t max_bytes = 0;                   // --max-bytes (0: none)
  ModelFormat output_format = ModelFormat::kObj;  // --output-format, else the input's kind
  bool quiet = false, verbose = false, force = false, no_fit = false, fine_fit = false, linear_light_colour = false;
  double map_budget_db = 51;  // Options::map_budget_db
  bool no_html = false;       // --no-html: no OUTDIR/report.html
  double max_memory_mib = 0;  // 0: 90% of RAM
};

/// Parses the main command's arguments, as the command line has them after the program's name (e.g.
/// {"in.obj", "-o", "out", "--size", "512"}).
/// Guarantees: every value passed the command's checks (ranges, names, exclusions).
/// Throws InputError with CLI11's one-line message for an unknown option, a missing or bad value, and
/// for --help (there is no terminal to print it to).
CommandLine parse_arguments(const std::vector<std::string>& args);

/// parse_arguments for main(): nullopt where the command ends here (--help printed, or a parse error
/// CLI11 has printed), with the exit code in `exit_code`.
std::optional<CommandLine> parse_command_line(int argc, char** argv, int& exit_code);

/// What a caller of run_command adds to the command line.
struct CommandHooks {
  /// Progress and cancellation (ProgressCallback). Empty: the terminal's progress line, where stderr is
  /// a terminal, printing is on and --quiet is not given.
  ProgressCallback progress;
  /// Notes and the summary line on stderr / stdout (the executable); --quiet turns them off too.
  bool print = true;
};

/// Runs the main command: reads the model, checks its estimated memory, plans, bakes, writes the model
/// (atomically), measures it, writes the report (and the preview). Returns the report as written.
/// Requires: a line from parse_arguments / parse_command_line.
/// Throws InputError (bad input, a run above --max-memory, an output folder that is the input's),
/// Cancelled (hooks.progress returned false; nothing is written), InternalError (a bug).
nlohmann::json run_command(const CommandLine& line, const CommandHooks& hooks = {});

/// The memory in bytes the command's guard estimates for this line's run (decoded input textures, the
/// mesh and its stages, the atlas texture at the side the run will use), from the model's geometry and
/// its images' headers alone: what a scheduler reserves for the run. The per-component layout's
/// textures are not known before the plan and are estimated as one atlas of the same side.
/// Throws InputError for a model that cannot be read, as run_command would.
double estimate_memory_bytes(const CommandLine& line);

/// The library's run on an in-memory mesh with the command's options (line.input and line.outdir
/// unused): the texture side from --size / --texels / the input's used texels, the memory guard, the
/// metrics measured into report["metrics"], the wall time and peak RSS. Nothing is written.
/// Requires: a mesh whose textures are loaded. Throws as run_command does.
Result optimize_mesh(const CommandLine& line, const TexturedMesh& mesh, const ProgressCallback& progress);

}  // namespace tightex::cli
