#include "run/run_warnings.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "io/output_files.hpp"
#include "pipeline/output_model.hpp"
#include "report/report.hpp"

namespace tightex {

namespace {

struct Lines {
  std::vector<std::string> warnings, notes;
};

/// The plan's lines: components kept as they were (Plan::kept_components), triangles with nothing to
/// bake, exact repeats, and the default budget grown to hold every component.
void add_plan_warnings(const Plan& plan, const nlohmann::json& report, Lines& out) {
  const nlohmann::json& prep = report["preparation"];
  if (prep["already_tight"].get<bool>())
    out.notes.push_back(fmt::format("{}: written with its own texture coordinates and texture(s)", plan.first_kept_reason()));
  else if (const size_t kept_components = plan.kept_components(); kept_components > 0)
    out.warnings.push_back(
        fmt::format("{} component(s), {} triangles, could not be re-parameterized and keep their original texture "
                    "coordinates and texture(s) ({}); see \"kept_original_uvs\" in the report",
                    kept_components, plan.kept_triangles(), plan.first_kept_reason()));
  if (const size_t one_after_another = report["pages"]["large_maps_one_after_another"].get<size_t>(); one_after_another > 0)
    out.notes.push_back(
        fmt::format("{} components of a million triangles or more were mapped one after another: the memory limit "
                    "(--max-memory, default 90% of this machine's) leaves no room for all of them at once",
                    one_after_another));
  if (const size_t untextured = prep["untextured_kept"].get<size_t>(); untextured > 0)
    out.warnings.push_back(
        fmt::format("{} triangles have no texture to bake from (no texture, no vertex colours) and are written as they came", untextured));
  if (const size_t repeats = prep["exact_repeats_copied"].get<size_t>(); repeats > 0)
    out.warnings.push_back(
        fmt::format("{} triangles repeat another of their mesh exactly (positions, texture coordinates, material): "
                    "each is written as a copy of the one it repeats",
                    repeats));
  if (const auto& grown = report["options"]["size_grown_from"]; !grown.is_null())
    out.notes.push_back(
        fmt::format("{} components need a 4x4 texel rectangle each: the texture grew from {}^2 to {}^2 texels (--size sets it)",
                    prep["components"].get<size_t>(), grown.get<int>(), report["options"]["size"].get<int>()));
}

/// The input's textured materials whose colour factor is not white (read from glTF: the factor a
/// glTF output keeps in its material), where `format` loses it: PLY has no place for it, and OBJ's Kd,
/// where it is written, is not multiplied into map_Kd by most OBJ viewers (docs/metrics.md).
size_t tinted_textures(const TexturedMesh& input, ModelFormat format) {
  if (!input.gltf || format == ModelFormat::kGltf || format == ModelFormat::kGlb) return 0;
  size_t n = 0;
  for (const Material& m : input.materials) n += m.texture >= 0 && (m.kd[0] != 1.0 || m.kd[1] != 1.0 || m.kd[2] != 1.0);
  return n;
}

/// What the output does not carry: the input's parts the reader left as they were (written back only to
/// glTF), what the glTF writer removed (texture slots that cannot follow the new texture coordinates;
/// one line), and each map slot OBJ or PLY cannot bind (one line each).
void add_not_carried(const TexturedMesh& input, const ModelReadStats& read_stats, ModelFormat format,
                     const std::vector<std::string>& removed, Lines& out) {
  const bool gltf = format == ModelFormat::kGltf || format == ModelFormat::kGlb;
  const std::string_view name = to_string(format);
  if (read_stats.instances_flattened > 0)
    out.notes.push_back(fmt::format("the glTF scene's {} mesh instances are written in world space ({} has no scene graph)",
                                    read_stats.instances_flattened, name));
  if (const size_t tinted = tinted_textures(input, format); tinted > 0)
    out.warnings.push_back(
        fmt::format("{} textured material(s) have a colour factor (glTF baseColorFactor) that {} and the new "
                    "texture does not hold; --output-format glb keeps it",
                    tinted,
                    format == ModelFormat::kObj ? "obj writes as Kd, which most OBJ viewers do not multiply into map_Kd,"
                                                : fmt::format("{} cannot carry", name)));
  if (!gltf && !read_stats.not_read.empty())
    out.warnings.push_back(fmt::format("{} {} of the input {} not written ({} has no place for them; --output-format glb keeps them): {}",
                                       read_stats.not_read.size(), read_stats.not_read.size() == 1 ? "part" : "parts",
                                       read_stats.not_read.size() == 1 ? "is" : "are", name, fmt::join(read_stats.not_read, ", ")));
  if (gltf && !removed.empty())
    out.warnings.push_back(
        fmt::format("removed from the output, as they cannot follow the new texture coordinates: {}", fmt::join(removed, ", ")));
  if (!gltf) out.warnings.insert(out.warnings.end(), removed.begin(), removed.end());
}

}  // namespace

void add_warnings(const Plan& plan, const TexturedMesh& input, const ModelReadStats& read_stats, std::optional<ModelFormat> written,
                  const std::vector<std::string>& removed, nlohmann::json& report) {
  Lines lines;
  lines.warnings = read_stats.warnings;
  add_plan_warnings(plan, report, lines);
  if (written) add_not_carried(input, read_stats, *written, removed, lines);
  report["warnings"] = lines.warnings;
  report["notes"] = lines.notes;
}

void add_rate_warnings(const Options& options, nlohmann::json& report) {
  const nlohmann::json& bytes = report.at("bytes");
  const double written = bytes.value("surface_psnr_written_db", 0.0), baked = bytes.value("surface_psnr_bake_db", 0.0);
  const uint64_t total = bytes.at("output").at("total").get<uint64_t>();
  if (options.target_psnr_db > 0 && written < options.target_psnr_db)
    report["warnings"].push_back(fmt::format(
        "--target-psnr {} dB not reached: {:.2f} dB as written; {}", options.target_psnr_db, written,
        baked < options.target_psnr_db
            ? fmt::format("the bake itself reads {:.2f} dB at this texel budget: more texels (--size, --texels) reach further", baked)
            : fmt::format("the bake reads {:.2f} dB, the codec stops below: another --format (a lossless one) reaches further", baked)));
  if (options.max_bytes > 0 && total > options.max_bytes)
    report["warnings"].push_back(fmt::format("--max-bytes {} not met: the images as written take {} bytes", options.max_bytes, total));
}

}  // namespace tightex
