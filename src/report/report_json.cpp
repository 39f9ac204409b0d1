// report.json's schema: every key the report holds is written here and nowhere else.
#include <cmath>
#include <string>

#include "report/report.hpp"
#include "tightex/version.hpp"

namespace tightex {

namespace {

using nlohmann::json;

/// An aspect as asked: the number, or "auto" for 0.
json aspect_json(double aspect) { return aspect > 0 ? json(aspect) : json("auto"); }

json input_json(const InputSummary& in) {
  json j = {
      {"file", in.file}, {"vertices", in.vertices}, {"triangles", in.triangles}, {"materials", in.materials}, {"textures", in.textures}};
  if (in.reader) j.update(reader_json(*in.reader));
  return j;
}

json options_json(const OptionsUsed& o) {
  return {{"size", o.size},
          {"size_grown_from", o.size_grown_from > 0 ? json(o.size_grown_from) : json(nullptr)},
          {"layout", std::string(to_string(o.layout))},
          {"holes", std::string(to_string(o.holes))},
          {"map", std::string(to_string(o.map))},
          {"balance", o.balance},
          {"fit", o.fit},
          {"fine_fit", o.fine_fit},
          {"corners", std::string(to_string(o.corners))},
          {"aspect", aspect_json(o.aspect)},
          {"material_map_budget_db", o.material_map_budget_db}};
}

json aspect_choice_json(const AspectChoice& a) {
  json probes = json::array();
  for (const AspectProbe& p : a.probes)
    probes.push_back(
        {{"aspect", p.aspect},
         {"width", p.width},
         {"height", p.height},
         {"estimated_psnr_db", estimated_psnr_db(p.estimated_mse)},
         {"full_map_estimated_psnr_db", p.full_map_estimated_mse < 0 ? json(nullptr) : json(estimated_psnr_db(p.full_map_estimated_mse))}});
  return {{"requested", aspect_json(a.requested)},
          {"chosen", a.chosen},
          {"probed_component", a.probed_component == kNone ? json(nullptr) : json(a.probed_component)},
          {"probes", probes},
          {"square_texel_stretch", a.square_texel_stretch < 0 ? json(nullptr) : json(a.square_texel_stretch)}};
}

json preparation_json(const Preparation& p, size_t listed) {
  const RepairStats& rs = p.repair;
  return {{"input_vertices", rs.input_vertices},
          {"welded_vertices", rs.welded_vertices},
          {"zero_area_dropped", rs.zero_area_triangles},
          {"exact_repeats_copied", rs.repeated_triangles},
          {"layered_triangles", rs.layered_triangles},
          {"untextured_kept", p.untextured_kept},
          {"non_manifold_edges_sliced", rs.non_manifold_edges},
          {"inconsistent_edges_sliced", rs.inconsistent_edges},
          {"reoriented_triangles", rs.reoriented_triangles},
          {"vertices_sliced", rs.sliced_vertices},
          {"slits_closed", rs.slits_closed},
          {"components", p.components},
          {"holes_filled", p.holes_filled},
          {"holes_cut", p.holes_cut},
          {"components_with_fallback", p.components_with_fallback},
          {"components_longest_hole_capped", p.components_longest_hole_capped},
          {"components_listed", listed},
          {"components_kept_original_uvs", p.components_kept_original_uvs},
          {"already_tight", p.already_tight}};
}

/// The estimated PSNR of the cuts a small longest hole was tried with (kept as the boundary, capped);
/// null where it was not tried.
json compared_cuts_json(const std::vector<double>& mse) {
  if (mse.empty()) return json(nullptr);
  json db = json::array();
  for (double m : mse) db.push_back(estimated_psnr_db(m));
  return db;
}

/// The cut's half of a component entry (CutStats and what the component was).
json cut_json(const ComponentEntry& e) {
  const CutStats& cs = e.cut;
  return {{"index", e.index},
          {"triangles", e.triangles},
          {"area", e.area},
          {"euler", cs.before.euler()},
          {"boundary_loops", cs.before.boundary_loops},
          {"genus", cs.before.genus()},
          {"holes_filled", cs.holes_filled},
          {"holes_cut", cs.holes_cut},
          {"cut", cs.method},
          {"longest_hole_edges", cs.longest_loop_edges},
          {"longest_hole_capped", cs.longest_loop_capped},
          {"longest_hole_kept_capped_estimated_psnr_db", compared_cuts_json(cs.compared_mse)},
          {"slits", cs.slits},
          {"fallback", cs.fallback_reason},
          {"cap_budget", cs.fill_budget},
          {"kept_original_uvs", !e.kept_reason.empty()},
          {"kept_reason", e.kept_reason},
          {"handle_loops", cs.handle_loops},
          {"cut_edges", cs.cut_edges},
          {"cut_length", cs.cut_length},
          {"seam_length", cs.seam_length},
          {"seam_on_input_seams", cs.seam_on_input_seams}};
}

/// A multilevel map's figures (all 0 for a map at full resolution).
json multilevel_json(const SquareMapStats& ms) {
  return {{"coarse_vertices", ms.coarse_vertices}, {"fine_reweighting", ms.fine_reweighting}, {"fine_steps", ms.fine_steps}};
}

/// The map's half of a component entry (SquareMapStats) and its rectangle.
json map_json(const ComponentEntry& e) {
  const SquareMapStats& ms = e.map;
  const Rect& r = e.rect;
  return {{"weights", ms.weights},
          {"negative_cotangent_weights", ms.negative_weights},
          {"bumped_boundary_vertices", ms.bumped_vertices},
          {"flipped_in_map", ms.flipped},
          {"folds_per_weighting", ms.folds_per_attempt},
          {"density_iterations", ms.iterations},
          {"density_stopped", ms.stopped},
          {"density_correction_rounds", ms.correction_rounds},
          {"density_error_log2_before", json::array({ms.spread_before_p5, ms.spread_before_p95})},
          {"density_error_log2", json::array({ms.spread_p5, ms.spread_p95})},
          {"refine_iterations", ms.refine_iterations},
          {"flow_steps", ms.flow_steps},
          {"flow_lead_steps", ms.flow_lead_steps},
          {"flow_shape_steps", ms.flow_shape_steps},
          {"flow_stopped", ms.flow_stopped},
          {"refine_energy", json::array({ms.refine_energy_before, ms.refine_energy})},
          {"refine_stopped", ms.refine_stopped},
          {"multilevel", multilevel_json(ms)},
          {"float_coordinates", {{"vertices_moved", ms.float_moved}, {"triangles_unfixed", ms.float_unfixed}}},
          {"rect", {{"image", r.image}, {"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h}}}};
}

json bake_json(const BakeStats& bs) {
  return {{"texels_filled", bs.texels_filled},
          {"texels_dilated", bs.texels_dilated},
          {"texels_footprint_filtered", bs.texels_footprint_filtered},
          {"tiles_fitted", bs.tiles_fitted},
          {"tiles", bs.tiles}};
}

}  // namespace

double estimated_psnr_db(double mse) { return mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : mse == 0 ? 99.0 : -1.0; }

json to_json(const StageTiming& timing) {
  json j = {{"stage", timing.stage}, {"seconds", timing.seconds}};
  if (timing.peak_rss_mib) j["peak_rss_mib"] = *timing.peak_rss_mib;
  if (timing.user_seconds) j["user_seconds"] = *timing.user_seconds;
  if (timing.sys_seconds) j["sys_seconds"] = *timing.sys_seconds;
  return j;
}

json to_json(const OutputFiles& files) {
  json j = {{"directory", files.directory}, {"model", files.model}};
  if (!files.html.empty()) j["html"] = files.html;
  if (!files.not_written.empty()) j["not_written"] = files.not_written;
  return j;
}

json reader_json(const ModelReadStats& stats) {
  json j = {{"polygons_triangulated", stats.polygons_triangulated},
            {"paths_found", stats.paths_found},
            {"vertex_coloured_triangles", stats.vertex_coloured_triangles}};
  if (!stats.not_read.empty()) j["not_read"] = stats.not_read;  // glTF points and lines, kept as they were
  if (stats.instances_flattened > 0) j["instances_flattened"] = stats.instances_flattened;
  if (!stats.warnings.empty()) j["warnings"] = stats.warnings;
  return j;
}

json to_json(const ReportData& report) {
  json j;
  j["tightex_version"] = version();  // the build that wrote it (include/tightex/version.hpp)
  j["input"] = input_json(report.input);
  j["options"] = options_json(report.options);
  j["aspect"] = aspect_choice_json(report.aspect);
  const Pages& pages = report.pages;
  j["pages"] = {{"max_side", pages.max_side > 0 ? json(pages.max_side) : json(nullptr)},
                {"max_piece_faces", pages.max_piece_faces > 0 ? json(pages.max_piece_faces) : json(nullptr)},
                {"count", pages.count},
                {"components_split", pages.components_split},
                {"pieces", pages.pieces},
                {"reason", pages.reason.empty() ? json(nullptr) : json(pages.reason)},
                {"large_maps_one_after_another", pages.large_maps_one_after_another}};
  j["preparation"] = preparation_json(report.preparation, report.components.size());
  json components = json::array();
  for (const ComponentEntry& e : report.components) {
    json entry = cut_json(e);
    entry.update(map_json(e));
    components.push_back(std::move(entry));
  }
  j["components"] = std::move(components);
  json timings = json::array();
  for (const StageTiming& t : report.timings) timings.push_back(to_json(t));
  j["timings"] = std::move(timings);
  if (report.bake) j["bake"] = bake_json(*report.bake);
  if (!report.maps.empty()) {
    json maps = json::array();
    for (const MaterialMapEntry& m : report.maps)
      maps.push_back(
          {{"name", m.name}, {"slots", m.slots}, {"encoding", m.encoding}, {"sizes", m.sizes}, {"scale", m.scale}, {"seconds", m.seconds}});
    j["maps"] = std::move(maps);
  }
  if (report.metrics) j["metrics"] = to_json(*report.metrics);
  if (report.peak_rss_mib) j["peak_rss_mib"] = *report.peak_rss_mib;
  if (report.wall_seconds) j["wall_seconds"] = *report.wall_seconds;
  if (report.output) j["output"] = to_json(*report.output);
  return j;
}

}  // namespace tightex

namespace tightex {

namespace {

/// The value at `path` (keys, each into an object) of `j`, or `fallback` where a key is absent or null.
template <typename T>
T value_at(const json& j, std::initializer_list<const char*> path, T fallback) {
  const json* at = &j;
  for (const char* key : path) {
    if (!at->is_object() || !at->contains(key) || (*at)[key].is_null()) return fallback;
    at = &(*at)[key];
  }
  return at->get<T>();
}

}  // namespace

Report public_report(json j, const TexturedMesh& output, size_t new_textures) {
  Report r;
  r.output_triangles = output.num_triangles();
  for (size_t i = 0; i < new_textures && i < output.textures.size(); ++i)
    r.texture_sizes.emplace_back(output.textures[i].image.width, output.textures[i].image.height);
  r.input_triangles = value_at<size_t>(j, {"input", "triangles"}, 0);
  r.components = value_at<size_t>(j, {"preparation", "components"}, 0);
  r.charts = value_at<size_t>(j, {"metrics", "charts"}, 0);
  r.lost_triangles = value_at<size_t>(j, {"metrics", "lost_triangles"}, 0);
  r.flipped_triangles = value_at<size_t>(j, {"metrics", "flipped"}, 0);
  r.input_texels_used = value_at<double>(j, {"metrics", "input", "utilization"}, 0);
  r.output_texels_used = value_at<double>(j, {"metrics", "output", "utilization"}, 0);
  r.surface_psnr_db = value_at<double>(j, {"metrics", "surface_psnr_db"}, 0);
  r.surface_psnr_bake_db = value_at<double>(j, {"metrics", "surface_psnr_bake_db"}, r.surface_psnr_db);
  r.input_texture_bytes = value_at<uint64_t>(j, {"bytes", "input", "total"}, 0);
  r.output_texture_bytes = value_at<uint64_t>(j, {"bytes", "output", "total"}, 0);
  r.texture_format = value_at<std::string>(j, {"bytes", "encoding", "format"}, "");
  r.wall_seconds = value_at<double>(j, {"wall_seconds"}, 0);
  r.warnings = value_at<std::vector<std::string>>(j, {"warnings"}, {});
  r.notes = value_at<std::vector<std::string>>(j, {"notes"}, {});
  r.peak_rss_mib = value_at<double>(j, {"peak_rss_mib"}, 0);
  r.json = j.dump(2) + "\n";
  r.detail = std::make_shared<const ReportDetail>(ReportDetail{std::move(j)});
  return r;
}

json& report_json(const Report& report) {
  thread_local json empty;
  if (report.detail) return report.detail->json;
  return empty = json::object();
}

}  // namespace tightex
