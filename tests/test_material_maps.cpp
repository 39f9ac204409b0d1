// Every map a material binds: the maps re-baked through the new layout, one image in two
// slots kept as one, tangent-space normals re-expressed in the output's frame, and the tangent frames
// compatible with the TANGENT an exporter writes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>

#include <fmt/format.h>
#include "bake/bake.hpp"
#include "core/raster.hpp"
#include "core/tangents.hpp"
#include "report/report.hpp"

#include "genus_surfaces.hpp"
#include "pipeline/bake_material_maps.hpp"
#include "pipeline/output_model.hpp"
#include "pipeline/plan_state.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

/// An object-space normal field: the surface normal n tilted by 25 degrees towards a direction that
/// turns with the position.
Vec3 tilted(const Vec3& p, const Vec3& n) {
  const Vec3 u = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized(), v = n.cross(u);
  const double turn = 1.7 * p.x() + 1.3 * p.y() + 0.9 * p.z(), tilt = 25 * M_PI / 180;
  return (std::cos(tilt) * n + std::sin(tilt) * (std::cos(turn) * u + std::sin(turn) * v)).normalized();
}

/// A 3D pattern for the plate's maps: `contrast` levels either side of mid-grey, about 4 * 190 / frequency
/// input texels a period.
uint8_t fine_pattern(const Vec3& p, double contrast, double frequency = 190) {
  return uint8_t(std::lround(128 + contrast * std::sin(frequency * p.x()) * std::sin(frequency * p.y())));
}

/// The perforated plate of the genus tests (each triangle its own chart, turned as its first edge) with
/// a tangent-space normal map of `tilted` through its own frames, and one image bound as both
/// metallic-roughness and occlusion (a hard metallic mask in blue). With `occlusion`, the red of that
/// image is occlusion(p) and its green and blue flat; with `grey`, the base colour is grey(p).
TexturedMesh plate_with_maps(const std::function<uint8_t(const Vec3&)>& occlusion = {},
                             const std::function<uint8_t(const Vec3&)>& grey = {}) {
  TexturedMesh m = testing::perforated_plate(1);
  const Image& colour = m.textures[0].image;
  const int W = colour.width, H = colour.height;
  Image normal(W, H, Rgba8{128, 128, 255, 255}), orm(W, H, Rgba8{255, 128, 0, 255});
  const std::vector<Vec4> tg = compute_corner_tangents(m);
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    Vec2 px[3];
    for (int k = 0; k < 3; ++k) px[k] = Vec2(m.corner_uv[3 * t + size_t(k)].x() * W, (1 - m.corner_uv[3 * t + size_t(k)].y()) * H);
    // Over the whole cell (extrapolated), as the colour: 16 texels a side from the triangle's corner.
    const int cx = int(std::floor(std::min({px[0].x(), px[1].x(), px[2].x()}) / 16)) * 16;
    const int cy = int(std::floor(std::min({px[0].y(), px[1].y(), px[2].y()}) / 16)) * 16;
    const Vec3 n = frame_normal(m, t, 0), T = tg[3 * t].head<3>(), B = tg[3 * t].w() * n.cross(T);
    const double det = (px[1] - px[0]).x() * (px[2] - px[0]).y() - (px[1] - px[0]).y() * (px[2] - px[0]).x();
    for (int y = cy; y < cy + 16; ++y)
      for (int x = cx; x < cx + 16; ++x) {
        const Vec2 d = Vec2(x + 0.5, y + 0.5) - px[0];
        const double b1 = (d.x() * (px[2] - px[0]).y() - d.y() * (px[2] - px[0]).x()) / det;
        const double b2 = ((px[1] - px[0]).x() * d.y() - (px[1] - px[0]).y() * d.x()) / det;
        const Vec3 p =
            (1 - b1 - b2) * m.positions[m.triangles[t][0]] + b1 * m.positions[m.triangles[t][1]] + b2 * m.positions[m.triangles[t][2]];
        const Vec3 o = tilted(p, n);
        auto q = [](double c) { return uint8_t(std::lround(std::clamp((c + 1) * 127.5, 0.0, 255.0))); };
        normal.at(x, y) = {q(o.dot(T)), q(o.dot(B)), q(o.dot(n)), 255};
        orm.at(x, y) = {uint8_t(200 + 40 * std::sin(p.x())), 128, uint8_t(std::sin(2 * p.x()) * std::sin(2 * p.y()) > 0 ? 255 : 0), 255};
        if (occlusion) orm.at(x, y) = {occlusion(p), 128, 0, 255};
        if (grey) m.textures[0].image.at(x, y) = {grey(p), grey(p), grey(p), 255};
      }
  }
  m.textures.push_back(Texture{"normal", std::move(normal)});
  m.textures.push_back(Texture{"orm", std::move(orm)});
  m.materials[0].maps[size_t(MaterialSlot::kNormal)] = 1;
  m.materials[0].maps[size_t(MaterialSlot::kMetallicRoughness)] = 2;
  m.materials[0].maps[size_t(MaterialSlot::kOcclusion)] = 2;
  return m;
}

Options small_options() {
  Options opt;
  opt.size = 128;
  opt.aspect = 1.0;
  return opt;
}

const MaterialMapFigures* figures_of(const std::vector<MaterialMapFigures>& all, MaterialSlot slot) {
  for (const MaterialMapFigures& f : all)
    if (f.slot == slot) return &f;
  return nullptr;
}

/// optimize() with the options' size as tightex's own budget (TextureBudget::is_default), under which
/// a map may be baked larger than the base colour.
Result at_default_budget(const TexturedMesh& in, const Options& o) {
  return bake_plan(plan_charts(in, o, TextureBudget{o.size, true}), in, o);
}

TEST(MaterialMaps, EverySlotIsRebakedAndOneImageInTwoSlotsStaysOne) {
  const TexturedMesh in = plate_with_maps();
  const Result r = optimize(in, small_options());
  const TexturedMesh& out = r.output;
  const Material& mat = out.materials[0];
  ASSERT_GE(mat.maps[size_t(MaterialSlot::kNormal)], 0);
  ASSERT_GE(mat.maps[size_t(MaterialSlot::kMetallicRoughness)], 0);
  EXPECT_EQ(mat.maps[size_t(MaterialSlot::kOcclusion)], mat.maps[size_t(MaterialSlot::kMetallicRoughness)]);
  EXPECT_NE(mat.maps[size_t(MaterialSlot::kNormal)], mat.texture);
  EXPECT_EQ(out.corner_tangent.size(), 3 * out.num_triangles());
  ASSERT_TRUE(report_json(r.report).contains("maps"));
  EXPECT_EQ(report_json(r.report)["maps"].size(), 2u);  // metallic-roughness with occlusion, and normal
  const std::vector<MaterialMapFigures> figures = measure_material_maps(in, out);
  const MaterialMapFigures* mr = figures_of(figures, MaterialSlot::kMetallicRoughness);
  ASSERT_NE(mr, nullptr);
  EXPECT_GT(mr->surface_psnr, 25.0);  // the hard mask where it belongs
}

TEST(MaterialMaps, NormalsAreReexpressedInTheNewFrameWhereCopiedTexelsFail) {
  const TexturedMesh in = plate_with_maps();
  const Plan plan = plan_charts(in, small_options());
  OutputModel om = build_output_model(plan_state(plan), in);
  const OutputModel plain = om;
  bake_material_maps(in, small_options(), om);
  const MaterialMapFigures* ours = nullptr;
  const std::vector<MaterialMapFigures> figures = measure_material_maps(in, om.mesh);
  ours = figures_of(figures, MaterialSlot::kNormal);
  ASSERT_NE(ours, nullptr);
  EXPECT_LT(ours->angle_median, 2.0);
  EXPECT_LT(ours->angle_p95, 8.0);
  // The same layout with the tangent-space texels carried as data: the frames of the new charts differ
  // from the input's, so the decoded normals turn away.
  OutputModel copied = plain;
  MaterialMapSource as_data;
  as_data.encoding = SlotEncoding::kData;
  as_data.texture_of_material = {1};
  std::vector<Image> pages;
  for (int p = 0; p < copied.new_images; ++p)
    pages.emplace_back(copied.mesh.textures[size_t(p)].image.width, copied.mesh.textures[size_t(p)].image.height);
  bake_material_map(in, as_data, copied.bake_triangles, copied.rects, pages, nullptr);
  for (int p = 0; p < copied.new_images; ++p) {
    copied.mesh.materials[size_t(p)].maps[size_t(MaterialSlot::kNormal)] = int(copied.mesh.textures.size());
    copied.mesh.textures.push_back(Texture{"copied", std::move(pages[size_t(p)])});
  }
  copied.mesh.corner_tangent = compute_corner_tangents(copied.mesh);
  const std::vector<MaterialMapFigures> copied_figures = measure_material_maps(in, copied.mesh);
  const MaterialMapFigures* copy = figures_of(copied_figures, MaterialSlot::kNormal);
  ASSERT_NE(copy, nullptr);
  EXPECT_GT(copy->angle_median, 2.0);
}

TEST(MaterialMaps, ObjMapsAreReadRebakedAndWritten) {
  TexturedMesh m = plate_with_maps();
  // As an OBJ scan's MTL binds them: a normal map (norm), a specular colour and a height map.
  m.materials[0].maps = unbound_slots();
  m.materials[0].maps[size_t(MaterialSlot::kNormal)] = 1;
  m.materials[0].maps[size_t(MaterialSlot::kSpecular)] = m.materials[0].maps[size_t(MaterialSlot::kBump)] = 2;
  const fs::path dir = fs::temp_directory_path() / fmt::format("tightex_maps_obj_{}", ::getpid());
  fs::remove_all(dir);
  write_obj(m, (dir / "in").string(), "plate", ImageFormat::kPng);
  ModelReadStats stats;
  const TexturedMesh in = read_obj((dir / "in" / "plate.obj").string(), {}, &stats);
  EXPECT_TRUE(stats.not_read.empty());
  ASSERT_EQ(in.materials.size(), 1u);
  EXPECT_EQ(in.textures.size(), 3u);  // map_Ks and map_Bump name one file: one texture
  EXPECT_GE(in.materials[0].maps[size_t(MaterialSlot::kNormal)], 0);
  EXPECT_EQ(in.materials[0].maps[size_t(MaterialSlot::kSpecular)], in.materials[0].maps[size_t(MaterialSlot::kBump)]);
  const Result r = optimize(in, small_options());
  write_obj(r.output, (dir / "out").string(), "plate", ImageFormat::kPng);
  const TexturedMesh back = read_obj((dir / "out" / "plate.obj").string());
  for (const MaterialSlot slot : {MaterialSlot::kNormal, MaterialSlot::kSpecular, MaterialSlot::kBump})
    EXPECT_GE(back.materials[0].maps[size_t(slot)], 0) << material_slot_name(slot);
  const std::vector<MaterialMapFigures> figures = measure_material_maps(in, back);
  const MaterialMapFigures* normal = figures_of(figures, MaterialSlot::kNormal);
  ASSERT_NE(normal, nullptr);  // OBJ has no TANGENT: both sides take the computed frames
  EXPECT_LT(normal->angle_median, 2.0);
  fs::remove_all(dir);
}

TEST(MaterialMaps, AMapShortOfItsCheckIsBakedLargerWhereItsTexelsPay) {
  // The occlusion has detail (8 input texels a period) that the input's density holds and the base
  // colour's size (half the input's side) does not; the base colour is flat, so that its own texels
  // remove no error and the map's added texels pay.
  const TexturedMesh in = plate_with_maps([](const Vec3& p) { return fine_pattern(p, 90, 95); }, [](const Vec3&) { return uint8_t(150); });
  Options defaulted = small_options();
  defaulted.size = 64;  // as tightex's own budget (at_default_budget), which maps may exceed
  Options unsized = defaulted;
  unsized.material_map_budget_db = 0;  // every map at the base colour's size
  const Result plain = at_default_budget(in, unsized), sized = at_default_budget(in, defaulted);
  auto image_of = [](const TexturedMesh& out, MaterialSlot slot) -> const Image& {
    return out.textures[size_t(out.materials[0].maps[size_t(slot)])].image;
  };
  const Image& base = sized.output.textures[size_t(sized.output.materials[0].texture)].image;
  const Image& before = image_of(plain.output, MaterialSlot::kMetallicRoughness);
  const Image& after = image_of(sized.output, MaterialSlot::kMetallicRoughness);
  const Image& input = in.textures[size_t(in.materials[0].maps[size_t(MaterialSlot::kMetallicRoughness)])].image;
  EXPECT_EQ(before.width, base.width);
  ASSERT_GT(after.width, before.width);
  EXPECT_EQ(int64_t(after.width) * base.height, int64_t(after.height) * base.width);  // the same texture coordinates
  EXPECT_LE(int64_t(after.width) * after.height, int64_t(input.width) * input.height);
  EXPECT_EQ(image_of(sized.output, MaterialSlot::kNormal).width, base.width);  // judged against itself: never larger
  const std::vector<MaterialMapFigures> figures_before = measure_material_maps(in, plain.output),
                                        figures_after = measure_material_maps(in, sized.output);
  EXPECT_GT(figures_of(figures_after, MaterialSlot::kOcclusion)->surface_psnr,
            figures_of(figures_before, MaterialSlot::kOcclusion)->surface_psnr + 0.5);
  EXPECT_GT(report_json(sized.report)["maps"][0]["scale"].get<double>(), 1.0);
  EXPECT_EQ(report_json(sized.report)["maps"][0]["sizes"][0][0].get<int>(), after.width);
  Options capped = defaulted;
  capped.max_page_side = base.width;  // no page side beyond the base colour's
  const Result at_cap = at_default_budget(in, capped);
  EXPECT_EQ(image_of(at_cap.output, MaterialSlot::kMetallicRoughness).width, base.width);
  const Result chosen = optimize(in, small_options());  // a budget the caller chose (--size): kept by every map
  EXPECT_EQ(image_of(chosen.output, MaterialSlot::kMetallicRoughness).width,
            chosen.output.textures[size_t(chosen.output.materials[0].texture)].image.width);
}

TEST(MaterialMaps, AMapNoFinerThanTheBaseColourKeepsItsSize) {
  // The same occlusion below the budget, beside a base colour with the same detail at more contrast: the
  // base colour's texels remove more error than the map's added texels would, and the check asks the
  // map no more than the base colour's size gives. (Growing while any step gained 0.25 dB took it larger.)
  const TexturedMesh in =
      plate_with_maps([](const Vec3& p) { return fine_pattern(p, 60); }, [](const Vec3& p) { return fine_pattern(p, 120); });
  const Options opt = small_options();
  const Result r = at_default_budget(in, opt);
  const Material& mat = r.output.materials[0];
  EXPECT_EQ(r.output.textures[size_t(mat.maps[size_t(MaterialSlot::kOcclusion)])].image.width,
            r.output.textures[size_t(mat.texture)].image.width);
  const std::vector<MaterialMapFigures> measured = measure_material_maps(in, r.output);
  const MaterialMapFigures* occlusion = figures_of(measured, MaterialSlot::kOcclusion);  // points into `measured`
  ASSERT_NE(occlusion, nullptr);
  EXPECT_LT(occlusion->surface_psnr, opt.material_map_budget_db);  // below the budget: not held there by it
}

/// The report's entry of the map named `name`, or nullptr.
const nlohmann::json* map_entry(const Result& r, const std::string& name) {
  for (const nlohmann::json& m : report_json(r.report)["maps"])
    if (m["name"] == name) return &m;
  return nullptr;
}

TEST(MaterialMaps, APackedImageIsJudgedByItsWorstSlot) {
  // One image for metallic-roughness (green and blue, flat here) and occlusion (red, with detail): the
  // size is chosen by the occlusion's own PSNR, not by the mean over the three channels, which the flat
  // channels would lift by about 4.8 dB.
  TexturedMesh in = plate_with_maps();
  Image& orm = in.textures[2].image;
  for (int y = 0; y < orm.height; ++y)
    for (int x = 0; x < orm.width; ++x) orm.at(x, y).g = 128, orm.at(x, y).b = 0;
  const Options opt = small_options();
  Options unsized = opt;
  unsized.material_map_budget_db = 0;  // every map at the base colour's size
  const Result r = at_default_budget(in, opt), full = at_default_budget(in, unsized);
  ASSERT_NE(map_entry(r, "metallic_roughness"), nullptr);
  const std::vector<MaterialMapFigures> measured = measure_material_maps(in, r.output), at_full = measure_material_maps(in, full.output);
  const MaterialMapFigures* occlusion = figures_of(measured, MaterialSlot::kOcclusion);  // points into `measured`
  const MaterialMapFigures* occlusion_full = figures_of(at_full, MaterialSlot::kOcclusion);
  ASSERT_NE(occlusion, nullptr);
  ASSERT_NE(occlusion_full, nullptr);
  // Reduced only as far as the occlusion itself allows (a mean over the three channels would allow more).
  EXPECT_GE(occlusion->surface_psnr, std::min(opt.material_map_budget_db, occlusion_full->surface_psnr - 0.25) - 0.5);
}

TEST(MaterialMaps, AReducedMapIsJudgedAtItsOwnTextureCoordinates) {
  // An emissive map with nothing a smaller image loses (one colour): halved it reads back as it was,
  // so it is reduced, and the reduced map, read at its own texture coordinates, holds it. A map with
  // detail is not reduced (a halving that loses more than 0.25 dB of its figure keeps its size).
  TexturedMesh in = plate_with_maps();
  Image emissive = in.textures[2].image;
  for (int y = 0; y < emissive.height; ++y)
    for (int x = 0; x < emissive.width; ++x) emissive.at(x, y) = {200, 128, 64, 255};
  in.materials[0].maps[size_t(MaterialSlot::kEmissive)] = int(in.textures.size());
  in.materials[0].factor[size_t(MaterialSlot::kEmissive)] = {1, 1, 1, 1};  // glTF's default 0 would show no emission
  in.textures.push_back(Texture{"emissive", std::move(emissive)});
  const Result r = optimize(in, small_options());
  const nlohmann::json* entry = map_entry(r, "emissive");
  ASSERT_NE(entry, nullptr);
  EXPECT_LT((*entry)["scale"].get<double>(), 1.0);
  const std::vector<MaterialMapFigures> measured = measure_material_maps(in, r.output);
  const MaterialMapFigures* figures = figures_of(measured, MaterialSlot::kEmissive);  // points into `measured`
  ASSERT_NE(figures, nullptr);
  EXPECT_GE(figures->surface_psnr, 45.0);
}

// The rate search's second bake (rescale_plan) bakes each map at the side over the base colour's that
// the first bake sized it to, enlarged or reduced, instead of sizing it again: the search judged every
// image shrunk alike.
TEST(MaterialMaps, ARescaledPlanKeepsEachMapsSizeOverTheBaseColour) {
  TexturedMesh in = plate_with_maps([](const Vec3& p) { return fine_pattern(p, 90, 95); }, [](const Vec3&) { return uint8_t(150); });
  Image emissive = in.textures[2].image;  // one colour: reduced
  for (int y = 0; y < emissive.height; ++y)
    for (int x = 0; x < emissive.width; ++x) emissive.at(x, y) = {200, 128, 64, 255};
  in.materials[0].maps[size_t(MaterialSlot::kEmissive)] = int(in.textures.size());
  in.materials[0].factor[size_t(MaterialSlot::kEmissive)] = {1, 1, 1, 1};
  in.textures.push_back(Texture{"emissive", std::move(emissive)});
  Options opt = small_options();
  opt.size = 64;
  Plan plan = plan_charts(in, opt, TextureBudget{opt.size, true});
  const Result first = bake_plan(plan, in, opt);
  std::map<std::string, double> scales;
  for (const nlohmann::json& m : report_json(first.report)["maps"]) scales[m["name"]] = m["scale"].get<double>();
  ASSERT_GT(scales["metallic_roughness"], 1.0);
  ASSERT_LT(scales["emissive"], 1.0);
  ASSERT_TRUE(rescale_plan(plan, 0.5, scales));
  const Result again = bake_plan(plan, in, opt);
  const int base = again.output.textures[size_t(again.output.materials[0].texture)].image.width;
  EXPECT_EQ(base, first.output.textures[size_t(first.output.materials[0].texture)].image.width / 2);
  for (const auto& [name, scale] : scales) {
    const nlohmann::json* entry = map_entry(again, name);
    ASSERT_NE(entry, nullptr) << name;
    EXPECT_DOUBLE_EQ((*entry)["scale"].get<double>(), scale) << name;
    EXPECT_EQ((*entry)["sizes"][0][0].get<int>(), int(std::lround(base * scale))) << name;
  }
  EXPECT_EQ(again.report.flipped_triangles, 0u);
}

/// The warning lines of `stderr_file` that name `slot`'s map.
size_t warnings_naming(const fs::path& stderr_file, MaterialSlot slot) {
  std::ifstream f(stderr_file);
  size_t n = 0;
  for (std::string line; std::getline(f, line);)
    n += line.starts_with("tightex: warning: ") && line.find(fmt::format("the {} map", material_slot_name(slot))) != std::string::npos;
  return n;
}

TEST(MaterialMaps, PlyAndObjOutputsNameEachMapSlotTheyCannotBind) {
  const TexturedMesh in = plate_with_maps();  // normal, and one image as metallic-roughness and occlusion
  const fs::path dir = fs::temp_directory_path() / fmt::format("tightex_maps_unbound_{}", ::getpid());
  fs::remove_all(dir);
  const Result r = optimize(in, small_options());
  const std::vector<std::string> ply = write_ply(r.output, (dir / "ply").string(), "plate", ImageFormat::kPng);
  EXPECT_EQ(ply.size(), 3u);  // PLY binds no map
  const std::vector<std::string> obj = write_obj(r.output, (dir / "obj").string(), "plate", ImageFormat::kPng);
  ASSERT_EQ(obj.size(), 1u);  // MTL has no occlusion statement; the others have one
  EXPECT_NE(obj[0].find("occlusion"), std::string::npos);
  TexturedMesh normal_only = in;
  normal_only.materials[0].maps = unbound_slots();
  normal_only.materials[0].maps[size_t(MaterialSlot::kNormal)] = 1;
  EXPECT_TRUE(write_obj(normal_only, (dir / "obj_normal").string(), "plate", ImageFormat::kPng).empty());

  // The command line: one warning line per slot, and the report lists them.
  write_gltf(in, (dir / "in").string(), "plate", ImageFormat::kPng, GltfContainer::kGlb);
  const std::string input = (dir / "in" / "plate.glb").string();
  for (const auto& [format, unbound] : {std::pair{"ply", 3u}, std::pair{"obj", 1u}}) {
    const fs::path out = dir / format, err = dir / (std::string(format) + ".err");
    const std::string cmd = fmt::format("{} '{}' -o '{}' --size 128 --output-format {} --no-html > /dev/null 2> '{}'", TIGHTEX_CLI, input,
                                        out.string(), format, err.string());
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    EXPECT_EQ(warnings_naming(err, MaterialSlot::kOcclusion), 1u) << format;
    EXPECT_EQ(warnings_naming(err, MaterialSlot::kNormal), unbound == 3u ? 1u : 0u) << format;
    std::ifstream report_file(out / "report.json");
    const nlohmann::json report = nlohmann::json::parse(report_file);
    EXPECT_EQ(report["output"]["not_written"].size(), unbound) << format;
  }
  fs::remove_all(dir);
}

TEST(MaterialMaps, ComputedTangentsAgreeWithAnExportersTangentAttribute) {
  const fs::path file = fs::path(TIGHTEX_SHARED_DATA) / "khronos_waterbottle" / "WaterBottle.glb";
  if (!fs::exists(file)) GTEST_SKIP() << file << " is absent";
  ModelReadOptions ro;
  ro.load_textures = false;
  const TexturedMesh m = read_gltf(file.string(), ro);
  ASSERT_EQ(m.corner_tangent.size(), 3 * m.num_triangles());
  const std::vector<Vec4> ours = compute_corner_tangents(m);
  std::vector<double> angle;
  size_t same_sign = 0;
  for (size_t c = 0; c < ours.size(); ++c) {
    const Vec3 a = ours[c].head<3>(), b = m.corner_tangent[c].head<3>().normalized();
    angle.push_back(std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180 / M_PI);
    same_sign += (ours[c].w() > 0) == (m.corner_tangent[c].w() > 0);
  }
  std::sort(angle.begin(), angle.end());
  EXPECT_LT(angle[angle.size() / 2], 1.0);
  EXPECT_GT(double(same_sign), 0.99 * double(ours.size()));
}

}  // namespace
}  // namespace tightex
