// The typed report's JSON: every key of report.json's schema, with the value of the field it comes from.
#include <gtest/gtest.h>

#include <time.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include "mesh_catalogue.hpp"
#include "pipeline/stage_clock.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"

namespace tightex {
namespace {

std::set<std::string> keys_of(const nlohmann::json& j) {
  std::set<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.insert(k);
  return keys;
}

/// A report as a CLI run fills it: two listed components, one of them kept, one probed shape.
ReportData filled_report() {
  ReportData r;
  r.input = {"in/model.obj", 502, 1000, 1, 1, std::nullopt};
  ModelReadStats read;
  read.polygons_triangulated = 3;
  read.paths_found = {"A.PNG -> a.png"};
  read.lines = 99;
  r.input.reader = read;
  r.options.size = 368;
  r.options.size_grown_from = 0;
  r.options.layout = Layout::kPerComponent;
  r.options.holes = HoleMode::kCut;
  r.options.map = MapKind::kArea;
  r.options.balance = 0.5;
  r.options.fit = true;
  r.options.fine_fit = true;
  r.options.corners = CornerRule::kTurningAngle;
  r.options.aspect = 0;
  r.aspect.requested = 0;
  r.aspect.chosen = 2.0;
  r.aspect.probed_component = 1;
  r.aspect.probes = {{1.0, 368, 368, 100.0, 50.0}, {2.0, 520, 264, -1.0}};
  r.aspect.square_texel_stretch = 2.5;
  r.preparation.repair.input_vertices = 502;
  r.preparation.repair.welded_vertices = 500;
  r.preparation.repair.zero_area_triangles = 1;
  r.preparation.repair.repeated_triangles = 2;
  r.preparation.repair.reoriented_triangles = 3;
  r.preparation.repair.non_manifold_edges = 4;
  r.preparation.repair.inconsistent_edges = 5;
  r.preparation.repair.sliced_vertices = 6;
  r.preparation.repair.slits_closed = 7;
  r.preparation.components = 3;
  r.preparation.holes_filled = 8;
  r.preparation.holes_cut = 9;
  r.preparation.components_with_fallback = 1;
  r.preparation.components_longest_hole_capped = 1;
  r.preparation.components_kept_original_uvs = 1;

  ComponentEntry mapped;
  mapped.index = 0;
  mapped.triangles = 900;
  mapped.area = 0.25;
  mapped.cut.before = Topology{10, 27, 18, 1};  // euler 1, genus 0
  mapped.cut.holes_filled = 8;
  mapped.cut.holes_cut = 9;
  mapped.cut.method = "path";
  mapped.cut.longest_loop_edges = 5;
  mapped.cut.longest_loop_capped = true;
  mapped.cut.compared_mse = {0.0, 65025.0};
  mapped.cut.slits = 2;
  mapped.cut.fill_budget = 0.02;
  mapped.cut.handle_loops = {1.5};
  mapped.cut.cut_edges = 29;
  mapped.cut.cut_length = 0.75;
  mapped.cut.seam_length = 0.8;
  mapped.cut.seam_on_input_seams = 0.125;
  mapped.map.weights = "cotangent";
  mapped.map.negative_weights = 100;
  mapped.map.bumped_vertices = 1;
  mapped.map.flipped = 0;
  mapped.map.folds_per_attempt = {3, 0};
  mapped.map.iterations = 13;
  mapped.map.stopped = "stalled";
  mapped.map.correction_rounds = 2;
  mapped.map.spread_before_p5 = -2, mapped.map.spread_before_p95 = 1.5;
  mapped.map.spread_p5 = -1, mapped.map.spread_p95 = 1;
  mapped.map.refine_iterations = 4;
  mapped.map.flow_steps = 5, mapped.map.flow_lead_steps = 6, mapped.map.flow_shape_steps = 7;
  mapped.map.flow_stopped = "converged";
  mapped.map.refine_energy_before = 8.5, mapped.map.refine_energy = 5.25;
  mapped.map.refine_stopped = "converged";
  mapped.rect = Rect{0, 4, 8, 368, 360};
  r.components.push_back(mapped);
  ComponentEntry kept;
  kept.index = 2;
  kept.triangles = 100;
  kept.cut.fallback_reason = "the cut did not give a disk";
  kept.kept_reason = "the map folds";
  r.components.push_back(kept);

  r.timings = {{"repair", 0.5, 14.0, 0.75, 0.125}, {"read geometry", 0.25, std::nullopt, std::nullopt, std::nullopt}};
  BakeStats bake;
  bake.texels_filled = 10, bake.texels_dilated = 11, bake.texels_footprint_filtered = 12, bake.tiles_fitted = 13, bake.tiles = 14;
  r.bake = bake;
  Metrics metrics;
  metrics.charts = 2;
  metrics.surface_psnr = 41.5;
  r.metrics = metrics;
  r.peak_rss_mib = 18.5;
  r.wall_seconds = 0.875;
  r.output = OutputFiles{"out", "model.obj"};
  return r;
}

TEST(Report, HasEveryKeyOfTheSchema) {
  const nlohmann::json j = to_json(filled_report());
  EXPECT_EQ(keys_of(j), (std::set<std::string>{"input", "options", "aspect", "pages", "preparation", "components", "timings", "bake",
                                               "metrics", "peak_rss_mib", "wall_seconds", "output", "tightex_version"}));
  EXPECT_EQ(keys_of(j["input"]), (std::set<std::string>{"file", "vertices", "triangles", "materials", "textures", "polygons_triangulated",
                                                        "paths_found", "vertex_coloured_triangles"}));
  EXPECT_EQ(keys_of(j["options"]), (std::set<std::string>{"size", "size_grown_from", "layout", "holes", "map", "balance", "fit", "fine_fit",
                                                          "corners", "aspect", "material_map_budget_db"}));
  EXPECT_EQ(keys_of(j["aspect"]), (std::set<std::string>{"requested", "chosen", "probed_component", "probes", "square_texel_stretch"}));
  EXPECT_EQ(keys_of(j["pages"]), (std::set<std::string>{"max_side", "max_piece_faces", "count", "components_split", "pieces", "reason",
                                                        "large_maps_one_after_another"}));
  EXPECT_EQ(keys_of(j["aspect"]["probes"][0]),
            (std::set<std::string>{"aspect", "width", "height", "estimated_psnr_db", "full_map_estimated_psnr_db"}));
  EXPECT_EQ(
      keys_of(j["preparation"]),
      (std::set<std::string>{"input_vertices", "welded_vertices", "zero_area_dropped", "exact_repeats_copied", "layered_triangles",
                             "untextured_kept", "non_manifold_edges_sliced", "inconsistent_edges_sliced", "reoriented_triangles",
                             "vertices_sliced", "slits_closed", "components", "holes_filled", "holes_cut", "components_with_fallback",
                             "components_longest_hole_capped", "components_listed", "components_kept_original_uvs", "already_tight"}));
  const std::set<std::string> component_keys{"index",
                                             "triangles",
                                             "area",
                                             "euler",
                                             "boundary_loops",
                                             "genus",
                                             "holes_filled",
                                             "holes_cut",
                                             "cut",
                                             "longest_hole_edges",
                                             "longest_hole_capped",
                                             "longest_hole_kept_capped_estimated_psnr_db",
                                             "slits",
                                             "fallback",
                                             "cap_budget",
                                             "kept_original_uvs",
                                             "kept_reason",
                                             "handle_loops",
                                             "cut_edges",
                                             "cut_length",
                                             "seam_length",
                                             "seam_on_input_seams",
                                             "weights",
                                             "negative_cotangent_weights",
                                             "bumped_boundary_vertices",
                                             "flipped_in_map",
                                             "folds_per_weighting",
                                             "density_iterations",
                                             "density_stopped",
                                             "density_correction_rounds",
                                             "density_error_log2_before",
                                             "density_error_log2",
                                             "refine_iterations",
                                             "flow_steps",
                                             "flow_lead_steps",
                                             "flow_shape_steps",
                                             "flow_stopped",
                                             "refine_energy",
                                             "refine_stopped",
                                             "multilevel",
                                             "float_coordinates",
                                             "rect"};
  ASSERT_EQ(j["components"].size(), 2u);
  for (const auto& c : j["components"]) EXPECT_EQ(keys_of(c), component_keys);
  EXPECT_EQ(keys_of(j["components"][0]["rect"]), (std::set<std::string>{"image", "x", "y", "w", "h"}));
  EXPECT_EQ(keys_of(j["components"][0]["multilevel"]), (std::set<std::string>{"coarse_vertices", "fine_reweighting", "fine_steps"}));
  EXPECT_EQ(keys_of(j["timings"][0]), (std::set<std::string>{"stage", "seconds", "peak_rss_mib", "user_seconds", "sys_seconds"}));
  EXPECT_EQ(keys_of(j["timings"][1]), (std::set<std::string>{"stage", "seconds"}));
  EXPECT_EQ(keys_of(j["bake"]),
            (std::set<std::string>{"texels_filled", "texels_dilated", "texels_footprint_filtered", "tiles_fitted", "tiles"}));
  EXPECT_EQ(j["metrics"], to_json(*filled_report().metrics));
  EXPECT_EQ(keys_of(j["output"]), (std::set<std::string>{"directory", "model"}));
}

TEST(Report, WritesEachFieldsValue) {
  const nlohmann::json j = to_json(filled_report());
  EXPECT_EQ(j["input"]["file"], "in/model.obj");
  EXPECT_EQ(j["input"]["triangles"], 1000);
  EXPECT_EQ(j["input"]["polygons_triangulated"], 3);
  EXPECT_EQ(j["input"]["paths_found"], nlohmann::json::array({"A.PNG -> a.png"}));
  EXPECT_EQ(j["options"]["size"], 368);
  EXPECT_TRUE(j["options"]["size_grown_from"].is_null());
  EXPECT_EQ(j["options"]["layout"], "per-component");
  EXPECT_EQ(j["options"]["holes"], "cut");
  EXPECT_EQ(j["options"]["map"], "area");
  EXPECT_EQ(j["options"]["corners"], "turning");
  EXPECT_EQ(j["options"]["balance"], 0.5);
  EXPECT_EQ(j["options"]["fine_fit"], true);
  EXPECT_EQ(j["options"]["aspect"], "auto");
  EXPECT_EQ(j["aspect"]["requested"], "auto");
  EXPECT_EQ(j["aspect"]["chosen"], 2.0);
  EXPECT_EQ(j["aspect"]["probed_component"], 1);
  EXPECT_DOUBLE_EQ(j["aspect"]["probes"][0]["estimated_psnr_db"].get<double>(), 10 * std::log10(255.0 * 255.0 / 100.0));
  EXPECT_EQ(j["aspect"]["probes"][1]["estimated_psnr_db"], -1.0);  // not mapped
  EXPECT_DOUBLE_EQ(j["aspect"]["probes"][0]["full_map_estimated_psnr_db"].get<double>(), 10 * std::log10(255.0 * 255.0 / 50.0));
  EXPECT_TRUE(j["aspect"]["probes"][1]["full_map_estimated_psnr_db"].is_null());  // no own map made
  EXPECT_EQ(j["aspect"]["square_texel_stretch"], 2.5);
  EXPECT_TRUE(to_json(ReportData{})["aspect"]["square_texel_stretch"].is_null());
  EXPECT_EQ(j["aspect"]["probes"][1]["width"], 520);
  EXPECT_EQ(j["preparation"]["zero_area_dropped"], 1);
  EXPECT_EQ(j["preparation"]["vertices_sliced"], 6);
  EXPECT_EQ(j["preparation"]["components_listed"], 2);  // the entries, not all components
  EXPECT_EQ(j["preparation"]["components"], 3);

  const nlohmann::json& c = j["components"][0];
  EXPECT_EQ(c["euler"], 1);
  EXPECT_EQ(c["genus"], 0);
  EXPECT_EQ(c["boundary_loops"], 1);
  EXPECT_EQ(c["cut"], "path");
  EXPECT_EQ(c["longest_hole_kept_capped_estimated_psnr_db"], nlohmann::json::array({99.0, 0.0}));
  EXPECT_EQ(c["fallback"], "");
  EXPECT_EQ(c["cap_budget"], 0.02);
  EXPECT_EQ(c["kept_original_uvs"], false);
  EXPECT_EQ(c["handle_loops"], nlohmann::json::array({1.5}));
  EXPECT_EQ(c["folds_per_weighting"], nlohmann::json::array({3, 0}));
  EXPECT_EQ(c["density_error_log2_before"], nlohmann::json::array({-2.0, 1.5}));
  EXPECT_EQ(c["density_error_log2"], nlohmann::json::array({-1.0, 1.0}));
  EXPECT_EQ(c["refine_energy"], nlohmann::json::array({8.5, 5.25}));
  EXPECT_EQ(c["flow_lead_steps"], 6);
  EXPECT_EQ(c["rect"], (nlohmann::json{{"image", 0}, {"x", 4}, {"y", 8}, {"w", 368}, {"h", 360}}));
  const nlohmann::json& k = j["components"][1];
  EXPECT_EQ(k["index"], 2);
  EXPECT_EQ(k["kept_original_uvs"], true);
  EXPECT_EQ(k["kept_reason"], "the map folds");
  EXPECT_EQ(k["fallback"], "the cut did not give a disk");
  EXPECT_TRUE(k["longest_hole_kept_capped_estimated_psnr_db"].is_null());

  EXPECT_EQ(j["timings"][0]["stage"], "repair");
  EXPECT_EQ(j["timings"][0]["peak_rss_mib"], 14.0);
  EXPECT_EQ(j["timings"][0]["user_seconds"], 0.75);
  EXPECT_EQ(j["timings"][0]["sys_seconds"], 0.125);
  EXPECT_EQ(j["bake"]["tiles"], 14);
  EXPECT_EQ(j["peak_rss_mib"], 18.5);
  EXPECT_EQ(j["wall_seconds"], 0.875);
  EXPECT_EQ(j["output"]["model"], "model.obj");
}

TEST(Report, NumbersKeepTheirTypes) {
  // Counts are written as integers and figures as floating point, so the text of report.json does not
  // change with the way a field is filled ("used_texels": 132776.0, "tiles": 36).
  const nlohmann::json j = to_json(filled_report());
  EXPECT_TRUE(j["input"]["vertices"].is_number_unsigned());
  EXPECT_TRUE(j["options"]["size"].is_number_integer());
  EXPECT_TRUE(j["aspect"]["chosen"].is_number_float());
  EXPECT_TRUE(j["components"][0]["euler"].is_number_integer());
  EXPECT_TRUE(j["components"][0]["area"].is_number_float());
  EXPECT_TRUE(j["components"][0]["density_iterations"].is_number_integer());
  EXPECT_EQ(j["components"][0]["cap_budget"].dump(), "0.02");
  EXPECT_EQ(j["aspect"]["chosen"].dump(), "2.0");
}

TEST(Report, LeavesOutWhatWasNotFilled) {
  ReportData r;
  r.options.aspect = 1.5;
  r.aspect.requested = 1.5;
  r.options.size_grown_from = 256;
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(keys_of(j),
            (std::set<std::string>{"input", "options", "aspect", "pages", "preparation", "components", "timings", "tightex_version"}));
  EXPECT_FALSE(j["input"].contains("paths_found"));
  EXPECT_EQ(j["options"]["aspect"], 1.5);
  EXPECT_EQ(j["options"]["size_grown_from"], 256);
  EXPECT_EQ(j["aspect"]["requested"], 1.5);
  EXPECT_TRUE(j["aspect"]["probed_component"].is_null());
  EXPECT_EQ(j["aspect"]["probes"], nlohmann::json::array());
  EXPECT_EQ(j["components"], nlohmann::json::array());
  EXPECT_EQ(j["timings"], nlohmann::json::array());
  EXPECT_EQ(j["options"]["map"], "detail");
  EXPECT_EQ(j["options"]["corners"], "arcs");
  EXPECT_EQ(j["options"]["layout"], "atlas");
  EXPECT_EQ(j["options"]["holes"], "fill");
}

TEST(Report, EstimatedPsnrOfNoErrorAndOfNoEstimate) {
  EXPECT_EQ(estimated_psnr_db(0.0), 99.0);
  EXPECT_EQ(estimated_psnr_db(-1.0), -1.0);
  EXPECT_DOUBLE_EQ(estimated_psnr_db(255.0 * 255.0), 0.0);
}

using namespace tightex::testing;

/// `input` as a writer might give it back: each triangle's corners rotated, the vertices numbered
/// backwards, the same corner texture coordinates; the triangles in reverse order where `reverse`.
TexturedMesh rewritten(const TexturedMesh& input, bool reverse) {
  TexturedMesh output = input;
  const size_t n = input.num_triangles(), nv = input.num_vertices();
  for (size_t t = 0; t < n; ++t) {
    const size_t from = reverse ? n - 1 - t : t;
    const Tri& f = input.triangles[from];
    output.triangles[t] = {uint32_t(nv - 1 - f[1]), uint32_t(nv - 1 - f[2]), uint32_t(nv - 1 - f[0])};
    for (size_t k = 0; k < 3; ++k) output.corner_uv[3 * t + k] = input.corner_uv[3 * from + (k + 1) % 3];
  }
  for (size_t v = 0; v < nv; ++v) output.positions[nv - 1 - v] = input.positions[v];
  return output;
}

/// `m` with `copies` more copies of triangle t at its end, each sampling another part of the texture.
TexturedMesh with_copies(TexturedMesh m, size_t t, int copies) {
  for (int c = 1; c <= copies; ++c) {
    m.triangles.push_back(m.triangles[t]);
    m.face_material.push_back(m.face_material[t]);
    for (size_t k = 0; k < 3; ++k) m.corner_uv.push_back(m.corner_uv[3 * t + k] + Vec2(0, 0.2 * c));
  }
  return m;
}

TEST(Metrics, TrianglesCorrespondByTheirCornerPositions) {
  // Found whatever the order of the triangles, their corners and the vertices: the same colours.
  const Metrics same = measure(sphere(), rewritten(sphere(), true), 20000);
  EXPECT_EQ(same.lost_triangles, 0u);
  EXPECT_EQ(same.surface_psnr, 99.0);
  // Copies of a triangle match the output's copies in triangle order, the k-th the k-th.
  const TexturedMesh input = with_copies(sphere(), 5, 2);
  const TexturedMesh output = rewritten(input, false);
  EXPECT_EQ(measure(input, output, 20000).surface_psnr, 99.0);
  TexturedMesh crossed = output;  // the last two copies in the other order
  const size_t n = crossed.num_triangles();
  std::swap(crossed.triangles[n - 2], crossed.triangles[n - 1]);
  for (size_t k = 0; k < 3; ++k) std::swap(crossed.corner_uv[3 * (n - 2) + k], crossed.corner_uv[3 * (n - 1) + k]);
  EXPECT_EQ(measure(input, crossed, 20000).lost_triangles, 0u);
  EXPECT_LT(measure(input, crossed, 20000).surface_psnr, 99.0);
  // Fewer copies in the output: each output triangle matches one input triangle, so the input copy
  // beyond the output's is lost.
  const Metrics fewer = measure(input, rewritten(with_copies(sphere(), 5, 1), true), 20000);
  EXPECT_EQ(fewer.lost_triangles, 1u);
  EXPECT_LT(fewer.surface_psnr, 99.0);
  // Two meshes of a scene with the same geometry: told apart by their source mesh where both models
  // have them; an output holding one mesh's triangles twice loses the other's.
  TexturedMesh two = with_copies(sphere(), 5, 1);
  two.source_mesh.assign(two.num_triangles(), 0);
  two.source_mesh.back() = 1;
  two.positions.push_back(two.positions[two.triangles.back()[0]]);  // meshes share no vertex
  two.triangles.back()[0] = uint32_t(two.positions.size() - 1);
  TexturedMesh twice = two;
  twice.source_mesh.back() = 0;
  EXPECT_EQ(measure(two, two, 20000).lost_triangles, 0u);
  EXPECT_EQ(measure(two, twice, 20000).lost_triangles, 1u);
  // A moved vertex loses the triangles around it, and only those.
  TexturedMesh moved = rewritten(sphere(), true);
  moved.positions[0] += Vec3(1e-9, 0, 0);
  const auto around = size_t(
      std::count_if(moved.triangles.begin(), moved.triangles.end(), [](const Tri& f) { return f[0] == 0 || f[1] == 0 || f[2] == 0; }));
  ASSERT_GT(around, 2u);
  EXPECT_EQ(measure(sphere(), moved, 20000).lost_triangles, around);
}

// The judge a search asks of many encodings (SurfacePsnrOfImages) reads what the images do not change
// once: its figure is surface_psnr's, bit for bit, for any image swapped in, of any size, a lost
// triangle included.
TEST(Metrics, SurfacePsnrOfImagesIsSurfacePsnrForEveryImage) {
  const TexturedMesh input = sphere();
  TexturedMesh output = rewritten(input, true);
  output.positions[0] += Vec3(1e-9, 0, 0);  // the triangles around vertex 0 lost: black in both figures
  output.materials[0].kd = {0.5, 0.75, 1.0};
  output.materials[0].kd_multiplies_texture = true;
  const SurfacePsnrOfImages judge(input, output, 20000);
  for (const Image& image : {input.textures[0].image, checker_image(64, 64, 3), checker_image(17, 40, 2), Image(5, 7)}) {
    output.textures[0].image = image;
    const double psnr = surface_psnr(input, output, 20000);
    EXPECT_LT(psnr, 99.0);
    EXPECT_EQ(judge(output), psnr) << image.width << "x" << image.height;
  }
}

/// `m` with its texture coordinates turned by `degrees` about the texture's centre (then mirrored in u
/// where `mirror`), its image a `side` x `side` square.
TexturedMesh turned(TexturedMesh m, double degrees, bool mirror = false, int side = 64) {
  const double a = degrees * M_PI / 180;
  for (Vec2& uv : m.corner_uv) {
    const Vec2 d = uv - Vec2(0.5, 0.5);
    uv = Vec2(0.5, 0.5) + Vec2(std::cos(a) * d.x() - std::sin(a) * d.y(), std::sin(a) * d.x() + std::cos(a) * d.y());
    if (mirror) uv.x() = 1 - uv.x();
  }
  m.textures[0].image = Image(side, side);
  return m;
}

// The texture axes angle of one triangle: the turn of the input's texel axes in the output's texels,
// modulo a right angle, whatever the scale; a shear turns one axis and not the other.
TEST(Metrics, TextureAxesAngleIsTheTurnModuloARightAngle) {
  const std::array<Vec2, 3> tri{Vec2(0.1, 0.2), Vec2(0.4, 0.25), Vec2(0.2, 0.6)};
  const Vec2 square(100, 100);
  auto turn = [&](double degrees, double scale, const Vec2& texels) {
    const double a = degrees * M_PI / 180;
    std::array<Vec2, 3> out;
    for (size_t k = 0; k < 3; ++k) {
      const Vec2 p = tri[k].cwiseProduct(square);  // input texels, turned, into `texels`
      out[k] = scale * Vec2(std::cos(a) * p.x() - std::sin(a) * p.y(), std::sin(a) * p.x() + std::cos(a) * p.y()).cwiseQuotient(texels);
    }
    return texture_axes_angle(tri, square, out, texels);
  };
  for (const double degrees : {0.0, 90.0, 180.0, 270.0, -90.0}) EXPECT_NEAR(turn(degrees, 0.7, square), 0.0, 1e-9) << degrees;
  EXPECT_NEAR(turn(30, 1, square), 30.0, 1e-9);
  EXPECT_NEAR(turn(-30, 2.5, square), 30.0, 1e-9);
  EXPECT_NEAR(turn(60, 1, square), 30.0, 1e-9);
  EXPECT_NEAR(turn(100, 1, square), 10.0, 1e-9);
  EXPECT_NEAR(turn(45, 1, square), 45.0, 1e-9);
  EXPECT_NEAR(turn(-170, 1, Vec2(512, 64)), 10.0, 1e-9);  // measured in texels, not in uv
  // Stretched along an axis, or mirrored: the axes stay axis-aligned.
  std::array<Vec2, 3> stretched = tri, mirrored = tri;
  for (size_t k = 0; k < 3; ++k) stretched[k].x() *= 3, mirrored[k].y() = 1 - mirrored[k].y();
  EXPECT_NEAR(texture_axes_angle(tri, square, stretched, square), 0.0, 1e-9);
  EXPECT_NEAR(texture_axes_angle(tri, square, mirrored, square), 0.0, 1e-9);
  // A shear by 45 degrees: u stays, v turns by 45; the figure is their mean.
  std::array<Vec2, 3> sheared = tri;
  for (size_t k = 0; k < 3; ++k) sheared[k].x() += sheared[k].y();
  EXPECT_NEAR(texture_axes_angle(tri, square, sheared, square), 22.5, 1e-9);
  // No texture area on one side: no figure.
  EXPECT_TRUE(std::isnan(texture_axes_angle(tri, square, {tri[0], tri[1], tri[1]}, square)));
}

// measure's texture axes angle over a whole model, matched by corner positions: an output whose texture
// coordinates are the input's turned by 30 degrees gives 30 on every triangle; a quarter turn, a half
// turn or a mirror gives 0.
TEST(Metrics, TextureAxesAngleOfATurnedOutput) {
  const TexturedMesh input = turned(sphere(), 0);
  const Metrics thirty = measure(input, rewritten(turned(input, 30), true), 1000);
  EXPECT_NEAR(thirty.axes_angle_mean, 30.0, 1e-6);
  EXPECT_NEAR(thirty.axes_angle.p5, 30.0, 1e-6);
  EXPECT_NEAR(thirty.axes_angle.p95, 30.0, 1e-6);
  EXPECT_NEAR(measure(input, turned(input, -75), 1000).axes_angle_mean, 15.0, 1e-6);
  for (const double degrees : {0.0, 90.0, 180.0}) {
    const Metrics m = measure(input, turned(input, degrees, degrees == 180.0), 1000);
    EXPECT_NEAR(m.axes_angle_mean, 0.0, 1e-6) << degrees;
    EXPECT_NEAR(m.axes_angle.p95, 0.0, 1e-6) << degrees;
  }
  const nlohmann::json j = to_json(thirty);
  EXPECT_NEAR(j["texture_axes_angle_deg"]["mean"].get<double>(), 30.0, 1e-6);
  EXPECT_NEAR(j["texture_axes_angle_deg"]["p50"].get<double>(), 30.0, 1e-6);
}

// The used texels are the texel centres inside some UV triangle (wrapped as a renderer repeats), each
// counted once however many triangles cover it: thousands of overlapping triangles, many beyond [0, 1],
// against a point-in-triangle test of every centre in each triangle's box.
TEST(Metrics, UsedTexelsAreTheCentresInsideSomeTriangle) {
  const int W = 96, H = 40;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> corner(-0.4, 1.4), step(-0.08, 0.08);
  TexturedMesh m = sphere();
  m.textures[0].image = Image(W, H);
  m.corner_uv.clear();
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    const Vec2 a(corner(rng), corner(rng));
    m.corner_uv.insert(m.corner_uv.end(), {a, a + Vec2(step(rng), step(rng)), a + Vec2(step(rng), step(rng))});
  }
  std::vector<char> covered(size_t(W) * size_t(H), 0);
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    Vec2 p[3];
    for (int k = 0; k < 3; ++k) p[k] = Vec2(m.corner_uv[3 * t + size_t(k)].x() * W, (1 - m.corner_uv[3 * t + size_t(k)].y()) * H);
    const auto side = [](const Vec2& a, const Vec2& b, const Vec2& c) { return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x(); };
    const double x0 = std::min({p[0].x(), p[1].x(), p[2].x()}), x1 = std::max({p[0].x(), p[1].x(), p[2].x()});
    const double y0 = std::min({p[0].y(), p[1].y(), p[2].y()}), y1 = std::max({p[0].y(), p[1].y(), p[2].y()});
    for (long y = long(std::floor(y0)) - 1; y <= long(std::ceil(y1)); ++y)
      for (long x = long(std::floor(x0)) - 1; x <= long(std::ceil(x1)); ++x) {
        const Vec2 c(x + 0.5, y + 0.5);
        const double s0 = side(p[0], p[1], c), s1 = side(p[1], p[2], c), s2 = side(p[2], p[0], c);
        if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0))
          covered[size_t(((y % H) + H) % H) * size_t(W) + size_t(((x % W) + W) % W)] = 1;
      }
  }
  const double expected = double(std::count(covered.begin(), covered.end(), 1));
  ASSERT_GT(expected, 0.3 * W * H);
  ASSERT_LT(expected, 0.95 * W * H);
  const ModelFigures f = measure_texture_space(m);
  EXPECT_EQ(f.used_texels, expected);
  EXPECT_EQ(f.texels, size_t(W) * size_t(H));
  EXPECT_DOUBLE_EQ(f.utilization, expected / (W * H));
}

/// The calling thread's CPU time so far, in seconds.
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// A stage's CPU time is the process's while it ran: at least what one of its threads spent in it, and
// none of what came before it.
TEST(StageClock, AStagesCpuTimeIsTheProcesssWhileItRan) {
  std::vector<StageTiming> timings;
  StageClock clock(timings);
  volatile double sink = 0;
  const double start = thread_cpu_seconds();
  while (thread_cpu_seconds() - start < 0.05) sink = sink + std::sqrt(sink + 1.0);
  const double spent = thread_cpu_seconds() - start;
  clock.done("work");
  clock.done("nothing");
  ASSERT_EQ(timings.size(), 2u);
  ASSERT_TRUE(timings[0].user_seconds && timings[0].sys_seconds);
  EXPECT_GE(*timings[0].user_seconds + *timings[0].sys_seconds, spent - 0.002);
  EXPECT_GE(*timings[0].sys_seconds, 0.0);
  EXPECT_GT(timings[0].seconds, 0.0);
  ASSERT_TRUE(timings[1].user_seconds && timings[1].sys_seconds);
  EXPECT_LT(*timings[1].user_seconds + *timings[1].sys_seconds, spent / 2);
}

}  // namespace
}  // namespace tightex
