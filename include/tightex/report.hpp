// What a run did and measured: the main figures as fields (docs/metrics.md defines each), the
// warnings a user should read, and the whole report as report.json holds it.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace tightex {

struct ReportDetail;  // tightex's own: the report's every figure, from which `json` is written

struct Report {
  size_t input_triangles = 0, output_triangles = 0;
  size_t components = 0;  // connected surfaces after the repair
  /// docs/metrics.md figures; measured only where Options::measure (run() always measures), else 0.
  size_t charts = 0, lost_triangles = 0, flipped_triangles = 0;
  double input_texels_used = 0, output_texels_used = 0;  // fractions of each model's texels
  /// Surface PSNR against the input (dB): of the images as written (decoded back; run() with a lossy
  /// codec), and of the bake before any encoding.
  double surface_psnr_db = 0, surface_psnr_bake_db = 0;
  std::vector<std::pair<int, int>> texture_sizes;  // width, height of each new texture
  /// run(): the texture images' bytes, as every material binds them (0 elsewhere), and their codec.
  uint64_t input_texture_bytes = 0, output_texture_bytes = 0;
  std::string texture_format;
  /// run(): the files written: the model, and the report a reader opens (report.html, or report.json).
  std::string model_path, report_path;
  double wall_seconds = 0, peak_rss_mib = 0;
  /// run(), optimize(): one line each where the result is not what was asked or the output cannot carry
  /// a part of the input (as the command prints them, after "warning: " or "note: ").
  std::vector<std::string> warnings, notes;
  /// The whole report, as report.json holds it (JSON text).
  std::string json;

  /// tightex's own access to every figure (the stages and the tests); empty for a default Report.
  std::shared_ptr<const ReportDetail> detail;
};

}  // namespace tightex
