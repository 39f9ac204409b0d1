#include "run/run_output.hpp"

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include <chrono>
#include <fstream>
#include <set>

#include "core/error.hpp"
#include "io/output_files.hpp"
#include "report/html_report.hpp"
#include "report/preview.hpp"
#include "report/welded_edges.hpp"

namespace fs = std::filesystem;

namespace tightex {

namespace {

fs::path temporary_beside(const fs::path& path) { return path.parent_path() / fmt::format(".{}.tmp", path.filename().string()); }

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

/// Writes the output model in the target's format. Returns what the writer left out: what the glTF
/// writer removed, or the map slots OBJ or PLY cannot bind.
std::vector<std::string> write_model(const ModelTarget& target, const TexturedMesh& output) {
  static const EncodedImages kNone;
  const EncodedImages& images = target.images != nullptr ? *target.images : kNone;
  switch (target.format) {
    case ModelFormat::kPly:
      return write_ply(output, target.outdir, target.name, target.encoding, images);
    case ModelFormat::kGltf:
      return write_gltf(output, target.outdir, target.name, target.encoding, GltfContainer::kGltf, images);
    case ModelFormat::kGlb:
      return write_gltf(output, target.outdir, target.name, target.encoding, GltfContainer::kGlb, images);
    case ModelFormat::kObj:
      break;
  }
  return write_obj(output, target.outdir, target.name, target.encoding, images);
}

/// The page's links to the full-size images: the output's texture files beside it (none inside a GLB),
/// the input's where they are files, relative to the output folder.
HtmlReportOptions page_links(const ModelTarget& target, const TexturedMesh& input, const TexturedMesh& output) {
  HtmlReportOptions options;
  for (size_t i = 0; i < output.textures.size(); ++i)
    options.output_links.push_back(target.format == ModelFormat::kGlb || output.textures[i].path.empty()
                                       ? std::string()
                                       : texture_file_name(output.textures[i], target.encoding.of_texture(i).format));
  std::error_code ec;
  const fs::path outdir = fs::absolute(target.outdir, ec);
  for (const Texture& t : input.textures) {
    std::string link;
    if (!t.from_vertex_colours && !t.path.empty() && t.path != input.source && fs::is_regular_file(t.path, ec))
      link = fs::relative(fs::absolute(t.path, ec), outdir, ec).generic_string();
    options.input_links.push_back(ec ? std::string() : link);
  }
  return options;
}

}  // namespace

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string output_model_name(const std::string& input, ModelFormat format) {
  return fs::path(input).stem().string() + "." + std::string(to_string(format));
}

void check_paths(const std::string& input, const std::string& outdir, ModelFormat format) {
  if (fs::is_directory(input)) fail_input("{}: is a directory, not a model file", input);
  check_output_folder(outdir);
  std::error_code ec;
  const fs::path in_dir = fs::absolute(fs::path(input)).parent_path();
  if (fs::exists(outdir, ec) && fs::exists(in_dir, ec) && fs::equivalent(outdir, in_dir, ec)) {
    const std::string model = output_model_name(input, format);
    const bool replaces = model == fs::path(input).filename().string();
    fail_input("{}: the output folder {} is the input's own folder; {} would {} (choose another -o)", input, outdir, model,
               replaces ? "replace the input" : "be written among the input's files");
  }
}

namespace {

/// The output model as its files give it back (textures decoded from the bytes written), read as
/// `tightex measure` reads it: a glTF output of a glTF input each mesh in its own space, a glTF output
/// of another format in world space.
TexturedMesh read_written(const ModelTarget& target) {
  const bool gltf = target.format == ModelFormat::kGltf || target.format == ModelFormat::kGlb;
  ModelReadOptions options;
  options.flatten_scene = gltf && !target.input_gltf;
  return read_model((fs::path(target.outdir) / fmt::format("{}.{}", target.name, to_string(target.format))).string(), options);
}

}  // namespace

namespace {

/// The names of the plain files in `folder` (none where it does not exist yet).
std::set<std::string> files_in(const std::string& folder) {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec))
    if (e.is_regular_file(ec)) names.insert(e.path().filename().string());
  return names;
}

/// Removes the files of `folder` that are not in `before`: what a cancelled run wrote.
void remove_new_files(const std::string& folder, const std::set<std::string>& before) {
  std::error_code ec;
  for (const std::string& name : files_in(folder))
    if (!before.count(name)) fs::remove(fs::path(folder) / name, ec);
}

}  // namespace

WrittenAndMeasured write_and_measure(const ModelTarget& target, const TexturedMesh& input, const TexturedMesh& output, RunTimings& timings,
                                     const StageProgress& progress) {
  // The last point a cancel leaves nothing behind without undoing: the files are written and renamed
  // into place now.
  progress("write", 0);
  const std::set<std::string> before = files_in(target.outdir);
  const auto tw = std::chrono::steady_clock::now();
  const CpuTimes cpu_write = process_cpu_times();
  WrittenAndMeasured r;
  r.removed = write_model(target, output);
  timings.write_s = seconds_since(tw);
  const CpuTimes now = process_cpu_times();
  timings.write_cpu = CpuTimes{now.user - cpu_write.user, now.sys - cpu_write.sys};
  try {
    progress("measure", 0);  // a cancel here removes what was just written: the run leaves nothing
  } catch (const Cancelled&) {
    remove_new_files(target.outdir, before);
    throw;
  }
  const auto tm = std::chrono::steady_clock::now();
  const CpuTimes cpu_before = process_cpu_times();
  const auto cpu_since = [&] {
    const CpuTimes t = process_cpu_times();
    return CpuTimes{t.user - cpu_before.user, t.sys - cpu_before.sys};
  };
  nlohmann::json html_data;
  // The models' welded edges once, for the measure's charts and the page's seams. The measure reads the
  // files as written (what `tightex measure INPUT OUTPUT` gives), not the model in memory: the images as
  // their codec gives them back, the materials as the format holds them.
  WeldedEdges input_edges, output_edges;
  TexturedMesh written;
  // The model in memory's edges serve the page only.
  tbb::parallel_invoke([&] { input_edges = welded_edges(input); },
                       [&] {
                         if (target.html) output_edges = welded_edges(output);
                       },
                       [&] { written = read_written(target); });
  tbb::parallel_invoke(
      [&] {
        r.metrics = measure(input, written, input_edges, welded_edges(written));
        timings.measure_s = seconds_since(tm);
        timings.measure_cpu = cpu_since();
      },
      [&] {
        if (!target.html) return;
        html_data = html_model_data_without_charts(input, output, input_edges, output_edges, page_links(target, input, output));
        timings.html_s = seconds_since(tm);
        timings.html_cpu = cpu_since();
      });
  // The page's chart counts are the measure's.
  if (target.html) r.html_data = html_model_data(std::move(html_data), r.metrics.charts_input, r.metrics.charts);
  return r;
}

void add_run_figures(nlohmann::json& rep, const Metrics& metrics, const RunTimings& t, double wall_seconds,
                     const ModelReadStats& read_stats, const OutputFiles& files) {
  rep["metrics"] = to_json(metrics);
  nlohmann::json& timings = rep["timings"];
  auto timing = [](const char* stage, double seconds, const CpuTimes& cpu) {
    return to_json(StageTiming{stage, seconds, std::nullopt, cpu.user, cpu.sys});
  };
  timings.push_back(timing("encode (codec, quality and, with a rate target, texels chosen)", t.encode_s, t.encode_cpu));
  timings.push_back(timing("write model", t.write_s, t.write_cpu));
  timings.push_back(timing("measure (the files as written, beside report.html data)", t.measure_s, t.measure_cpu));
  if (t.html_s > 0) timings.push_back(timing("report.html data (beside measure)", t.html_s, t.html_cpu));
  timings.insert(timings.begin(), timing("read geometry", t.read_s, t.read_cpu));
  timings.insert(timings.begin() + 1, to_json(StageTiming{"read textures (beside the geometric stages, from start)", t.textures_s,
                                                          std::nullopt, std::nullopt, std::nullopt}));
  rep["wall_seconds"] = wall_seconds;
  rep["peak_rss_mib"] = peak_rss_mib();
  rep["input"].update(reader_json(read_stats));
  rep["output"] = to_json(files);
}

fs::path write_reports(const fs::path& json_path, const std::string& outdir, const std::string& report_text,
                       const std::string* model_data) {
  if (!model_data) {
    write_texts_atomically({{json_path, report_text}});
    return json_path;
  }
  std::string page = html_report_page(report_text, *model_data);
  const fs::path html_path = fs::path(outdir) / kHtmlName;
  write_texts_atomically({{html_path, std::move(page)}, {json_path, report_text}});
  return html_path;
}

void write_preview(const std::string& preview_path, const TexturedMesh& input, const TexturedMesh& output) {
  const fs::path p(preview_path);
  const fs::path tmp = temporary_beside(p);
  save_image(tmp.string(), make_preview(input, output), ImageFormat::kPng);
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) fail_input("{}: cannot write preview ({})", preview_path, ec.message());
}

}  // namespace tightex
