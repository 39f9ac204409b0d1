// What a run writes and measures once the bake is done: the model in its format, its metrics and
// report.html's model data side by side, the reports and the preview, each file renamed into place
// only once written whole.
#pragma once
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/progress.hpp"
#include "core/resources.hpp"
#include "io/obj_reader.hpp"
#include "io/output_files.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/io.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// Seconds from t0 to now.
double seconds_since(std::chrono::steady_clock::time_point t0);

/// The output model's file name inside the output folder: the input's stem and the format's extension.
std::string output_model_name(const std::string& input, ModelFormat format);

/// Refuses an input that is a folder, an output folder that cannot be created or written into (before
/// the work, not after it), and an output folder that is the input's own: the outputs are named after
/// the input, so written there they would replace it or lie among its files. Throws InputError.
void check_paths(const std::string& input, const std::string& outdir, ModelFormat format);

/// How long the run's own stages took, in seconds (read_s, textures_s from the start), and the
/// process's CPU time while they ran (read: from the start; measure and the page's data: each from
/// the start of the two to its own end; write: its own).
struct RunTimings {
  double read_s = 0, textures_s = 0, encode_s = 0, write_s = 0, measure_s = 0, html_s = 0;
  CpuTimes read_cpu, encode_cpu, write_cpu, measure_cpu, html_cpu;
};

/// What the run's last stage gives: the output's metrics, what the writer left out, and report.html's
/// model data (empty without the page).
struct WrittenAndMeasured {
  Metrics metrics;
  std::vector<std::string> removed;
  std::string html_data;
};

/// Where and how the output model is written.
struct ModelTarget {
  std::string outdir, name;  // the folder, and the model's file stem
  ModelFormat format = ModelFormat::kObj;
  ImageEncoding encoding;
  const EncodedImages* images = nullptr;  // the textures as `encoding` gives them, encoded already (or null)
  bool html = true;                       // gather report.html's model data
  bool input_gltf = false;                // the input is glTF (the written model is read back as `tightex measure` reads it)
};

/// Writes the output model, its files renamed into place, then measures the model as written (read
/// back from its files, as `tightex measure` reads it) beside gathering report.html's model data (the
/// models' decimated views, their textures as JPEG). Tells `progress` "write" and "measure" as each
/// begins: a cancel at "write" finds nothing written, one at "measure" removes what was written. The
/// times go to `timings`.
WrittenAndMeasured write_and_measure(const ModelTarget& target, const TexturedMesh& input, const TexturedMesh& output, RunTimings& timings,
                                     const StageProgress& progress);

/// Adds what the run knows beyond the library's report: the metrics, its own stages' times (reading
/// first, writing and measuring last), wall time, peak RSS, the reader's figures and the output files.
void add_run_figures(nlohmann::json& report, const Metrics& metrics, const RunTimings& timings, double wall_seconds,
                     const ModelReadStats& read_stats, const OutputFiles& files);

/// The report page's file name in the output folder.
constexpr const char* kHtmlName = "report.html";

/// Writes the report as `json_path` and, where `model_data` is given (html_model_data's), OUTDIR/report.html
/// showing the same report, renamed into place together, the JSON last. Returns the report a reader
/// opens: the page, or the JSON. Throws InputError naming a file that cannot be written.
std::filesystem::path write_reports(const std::filesystem::path& json_path, const std::string& outdir, const std::string& report_text,
                                    const std::string* model_data);

/// Writes the preview picture under a temporary name, then renames it into place.
void write_preview(const std::string& preview_path, const TexturedMesh& input, const TexturedMesh& output);

}  // namespace tightex
