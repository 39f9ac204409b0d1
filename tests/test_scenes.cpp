// Whole glTF scenes as users bring them, kept whole: two meshes with the same geometry stay two
// surfaces (nothing welded across meshes, no triangle lost), instances placed in world space when the
// output format has no scene graph, untextured parts passed through, nothing to bake refused, and what
// the output validates; with the readers' and writers' smaller promises (KTX2 fallbacks, PLY pages, the
// tile payloads), and the lost count with multiplicity.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "command_line.hpp"
#include "core/error.hpp"
#include "core/image.hpp"
#include "gltf_builder.hpp"
#include "gltf_checks.hpp"
#include "io/gltf_document.hpp"
#include "mesh_catalogue.hpp"
#include "prepare/repair.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::read_whole;
using testing::run_tightex;
using testing::write_whole;

constexpr size_t kGridTriangles = 32;  // grid_gltf(4)'s mesh

fs::path scene_glb(const fs::path& dir, bool untextured_part) {
  const testing::GridGltf g = testing::scene_gltf(untextured_part);
  const fs::path p = dir / "scene.glb";
  write_whole(p, testing::make_glb(g.doc, g.bin));
  return p;
}

/// `tightex IN -o OUT --quiet OPTIONS`, its stderr into OUT.stderr; the exit status.
int run_quietly(const fs::path& in, const fs::path& out, const std::string& options = "") {
  return run_tightex("'" + in.string() + "' -o '" + out.string() + "' --quiet --size 64 " + options + " 2> '" + out.string() + ".stderr'");
}

// ---- 1. Every triangle of every mesh kept and re-textured ----

TEST(Scenes, TwoMeshesWithTheSameGeometryStayTwoSurfaces) {
  const fs::path dir = testing::scratch_folder("scene_two_meshes");
  const TexturedMesh in = read_gltf(scene_glb(dir, false).string());
  ASSERT_EQ(in.num_triangles(), 2 * kGridTriangles);
  ASSERT_EQ(in.source_mesh.size(), in.num_triangles());
  EXPECT_EQ(std::set<uint32_t>(in.source_mesh.begin(), in.source_mesh.end()), (std::set<uint32_t>{0, 1}));
  RepairStats rs;
  const Surface s = prepare_surface(in, &rs);
  EXPECT_EQ(s.num_faces(), in.num_triangles());  // nothing welded across the meshes, nothing dropped
  EXPECT_EQ(rs.repeated_triangles, 0u);
  Options opt;
  opt.size = 64;
  const Result r = optimize(in, opt);
  EXPECT_EQ(r.output.num_triangles(), in.num_triangles());
  EXPECT_EQ(report_json(r.report)["preparation"]["components"], 2);
  EXPECT_EQ(report_json(r.report)["metrics"]["lost_triangles"], 0);
  // Each mesh's triangles keep their own source mesh, and the two copies own different texels.
  std::map<uint32_t, std::set<std::pair<double, double>>> uvs;
  for (size_t t = 0; t < r.output.num_triangles(); ++t)
    for (size_t k = 0; k < 3; ++k)
      uvs[r.output.source_mesh[t]].insert({r.output.corner_uv[3 * t + k].x(), r.output.corner_uv[3 * t + k].y()});
  ASSERT_EQ(uvs.size(), 2u);
  std::vector<std::pair<double, double>> shared;
  std::set_intersection(uvs[0].begin(), uvs[0].end(), uvs[1].begin(), uvs[1].end(), std::back_inserter(shared));
  EXPECT_TRUE(shared.empty());
}

TEST(Scenes, ExactRepeatsAreCopiedAndOtherLayersKept) {
  // Triangle 0 twice more: once exactly (copied with its twin's new texture coordinates), once with
  // other texture coordinates (a layer of its own).
  TexturedMesh in = testing::sphere();
  for (int copy = 0; copy < 2; ++copy) {
    in.triangles.push_back(in.triangles[0]);
    in.face_material.push_back(in.face_material[0]);
    for (size_t k = 0; k < 3; ++k) in.corner_uv.push_back(in.corner_uv[k] + Vec2(0, 0.3 * copy));
  }
  const uint32_t exact = uint32_t(in.num_triangles() - 2), layered = exact + 1;
  RepairStats rs;
  std::vector<std::pair<uint32_t, uint32_t>> repeats;
  const Surface s = prepare_surface(in, &rs, &repeats);
  EXPECT_EQ(repeats, (std::vector<std::pair<uint32_t, uint32_t>>{{exact, 0}}));
  EXPECT_EQ(rs.layered_triangles, 1u);
  EXPECT_EQ(s.num_faces(), in.num_triangles() - 1);
  EXPECT_EQ(s.num_vertices(), in.num_vertices() + 3);  // the layer's own corners
  Options opt;
  opt.size = 64;
  const Result r = optimize(in, opt);
  ASSERT_EQ(r.output.num_triangles(), in.num_triangles());
  EXPECT_EQ(measure(in, r.output, 20000).lost_triangles, 0u);
  EXPECT_EQ(report_json(r.report)["preparation"]["exact_repeats_copied"], 1);
  std::map<uint32_t, size_t> output_of;
  for (size_t o = 0; o < r.output.num_triangles(); ++o) output_of[r.output.input_triangle[o]] = o;
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(r.output.corner_uv[3 * output_of[exact] + k], r.output.corner_uv[3 * output_of[0] + k]);
}

TEST(Scenes, TheCommandKeepsEveryMeshOfTheSceneAsGlb) {
  const fs::path dir = testing::scratch_folder("scene_glb");
  const fs::path in_path = scene_glb(dir, false);
  ASSERT_EQ(run_quietly(in_path, dir / "out"), 0) << read_whole(dir / "out.stderr");
  const json report = json::parse(read_whole(dir / "out" / "report.json"));
  EXPECT_EQ(report["metrics"]["lost_triangles"], 0);
  EXPECT_EQ(report["metrics"]["flipped"], 0);
  const TexturedMesh in = read_gltf(in_path.string()), out = read_gltf((dir / "out" / "scene.glb").string());
  EXPECT_EQ(out.num_triangles(), in.num_triangles());
  const Metrics m = measure(in, out, 20000);
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_NEAR(m.surface_psnr, report["metrics"]["surface_psnr_db"].get<double>(), 0.3);
  // Every triangle textured by tightex's own image: one base colour image in the output.
  std::set<int> base_colour;
  for (const int32_t m : out.face_material) base_colour.insert(out.materials[size_t(m)].texture);
  EXPECT_EQ(base_colour, std::set<int>{0});
  testing::expect_valid_and_loading(dir / "out" / "scene.glb", 3 * kGridTriangles);
}

// ---- 2. The scene flattened where the format has no scene graph ----

TEST(Scenes, ObjAndPlyHoldEveryInstanceInWorldSpace) {
  const fs::path dir = testing::scratch_folder("scene_flat");
  const fs::path in_path = scene_glb(dir, false);
  ModelReadOptions flat;
  flat.flatten_scene = true;
  ModelReadStats stats;
  const TexturedMesh world = read_gltf(in_path.string(), flat, &stats);
  EXPECT_EQ(stats.instances_flattened, 3u);
  ASSERT_EQ(world.num_triangles(), 3 * kGridTriangles);
  // The mirrored copy's triangles face the way its normals do (glTF turns a mirrored node's front faces).
  for (size_t t = 0; t < world.num_triangles(); ++t) {
    const Tri& f = world.triangles[t];
    const Vec3 n = (world.positions[f[1]] - world.positions[f[0]]).cross(world.positions[f[2]] - world.positions[f[0]]);
    EXPECT_GT(n.dot(world.corner_normal[3 * t]), 0) << "triangle " << t;
  }
  // Node 2 places mesh 1 at x' = 3 - x: its first vertex (0.1, 0, 0) lands at (2.9, 0, 0).
  EXPECT_TRUE(std::any_of(world.positions.begin(), world.positions.end(),
                          [](const Vec3& p) { return (p - Vec3(3.0 - double(0.1f), 0, 0)).norm() < 1e-12; }));
  for (const char* format : {"obj", "ply"}) {
    SCOPED_TRACE(format);
    const fs::path out = dir / format;
    ASSERT_EQ(run_quietly(in_path, out, std::string("--output-format ") + format), 0) << read_whole(fs::path(out.string() + ".stderr"));
    const json report = json::parse(read_whole(out / "report.json"));
    EXPECT_EQ(report["input"]["instances_flattened"], 3);
    EXPECT_EQ(report["metrics"]["lost_triangles"], 0);
    const TexturedMesh written = read_model((out / (std::string("scene.") + format)).string());
    EXPECT_EQ(written.num_triangles(), 3 * kGridTriangles);
    EXPECT_EQ(measure(world, written, 20000).lost_triangles, 0u);
    // `tightex measure` compares a glTF scene with an OBJ or PLY in world space.
    ASSERT_EQ(run_tightex("measure '" + in_path.string() + "' '" + (out / (std::string("scene.") + format)).string() + "' > '" +
                          (dir / "measured.json").string() + "'"),
              0);
    const json measured = json::parse(read_whole(dir / "measured.json"));
    EXPECT_EQ(measured["lost_triangles"], 0);
    // The grid's material has a base colour factor of 0.5, which a glTF viewer multiplies into the
    // texture and an OBJ or PLY viewer does not: what they show differs by that much, and the run says so.
    EXPECT_GT(measured["surface_psnr_db"].get<double>(), 10);
    EXPECT_NE(report.dump().find("colour factor"), std::string::npos);
  }
}

// ---- 3. Nothing to bake ----

/// How many triangles of `baked` (the written model of the glTF at `in_path`, in world space) lie
/// where the input's untextured ones lie, each checked to show `factor` at its centre as an sRGB texel.
size_t plain_triangle_colours(const fs::path& in_path, const TexturedMesh& baked, const std::array<double, 3>& factor) {
  ModelReadOptions world;
  world.flatten_scene = true;
  const TexturedMesh in = read_gltf(in_path.string(), world);
  auto centroid = [](const TexturedMesh& m, size_t t) {
    return Vec3((m.positions[m.triangles[t][0]] + m.positions[m.triangles[t][1]] + m.positions[m.triangles[t][2]]) / 3);
  };
  size_t found = 0;
  for (size_t t = 0; t < in.num_triangles(); ++t) {
    if (in.face_material[t] < 0 || in.materials[size_t(in.face_material[t])].texture >= 0) continue;
    for (size_t b = 0; b < baked.num_triangles(); ++b) {
      if ((centroid(baked, b) - centroid(in, t)).norm() > 1e-5) continue;
      ++found;
      const Vec2 centre = (baked.corner_uv[3 * b] + baked.corner_uv[3 * b + 1] + baked.corner_uv[3 * b + 2]) / 3;
      const Image& page = baked.textures[size_t(baked.materials[size_t(baked.face_material[b])].texture)].image;
      const std::array<float, 4> texel = sample_bilinear(page, centre.x(), centre.y());
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(texel[size_t(k)], 255 * linear_to_srgb(factor[size_t(k)]), 1.5) << k;
    }
  }
  return found;
}

TEST(Scenes, UntexturedPartsAreWrittenAsTheyCame) {
  const fs::path dir = testing::scratch_folder("scene_untextured");
  const fs::path in_path = scene_glb(dir, true);
  ASSERT_EQ(run_tightex("'" + in_path.string() + "' -o '" + (dir / "out").string() + "' --size 64 2> '" + (dir / "err").string() + "'"), 0);
  const std::string err = read_whole(dir / "err");
  EXPECT_NE(err.find("warning: 2 triangles have no texture to bake from"), std::string::npos) << err;
  const json report = json::parse(read_whole(dir / "out" / "report.json"));
  EXPECT_EQ(report["preparation"]["untextured_kept"], 2);
  EXPECT_EQ(report["metrics"]["lost_triangles"], 0);
  const TexturedMesh out = read_gltf((dir / "out" / "scene.glb").string());
  EXPECT_EQ(out.num_triangles(), 2 * kGridTriangles + 2);
  size_t plain = 0;
  for (size_t t = 0; t < out.num_triangles(); ++t) {
    const Material& m = out.materials[size_t(out.face_material[t])];
    if (m.texture >= 0) continue;
    ++plain;
    EXPECT_EQ(m.name, "plain");
  }
  EXPECT_EQ(plain, 2u);
  testing::expect_valid_and_loading(dir / "out" / "scene.glb", 3 * kGridTriangles + 2);
  // OBJ keeps the factor as the same number in Kd (as Blender and assimp convert the two).
  const std::array<double, 3> factor{0.2, 0.4, 0.6};
  ASSERT_EQ(run_quietly(in_path, dir / "obj", "--output-format obj"), 0) << read_whole(dir / "obj.stderr");
  const TexturedMesh obj = read_obj((dir / "obj" / "scene.obj").string());
  size_t plain_in_obj = 0;
  for (const Material& m : obj.materials) plain_in_obj += m.texture < 0 && m.kd == factor;
  EXPECT_EQ(plain_in_obj, 1u);
  // PLY has no material for their colour: it is baked into the new texture with the rest, as the
  // texel that shows the factor (sRGB-encoded).
  ASSERT_EQ(run_quietly(in_path, dir / "ply", "--output-format ply"), 0) << read_whole(dir / "ply.stderr");
  const json ply_report = json::parse(read_whole(dir / "ply" / "report.json"));
  EXPECT_EQ(ply_report["preparation"]["untextured_kept"], 0);
  EXPECT_EQ(ply_report["metrics"]["lost_triangles"], 0);
  TexturedMesh ply = read_ply((dir / "ply" / "scene.ply").string());
  EXPECT_EQ(ply.num_triangles(), 3 * kGridTriangles + 2);
  for (const int32_t m : ply.face_material) EXPECT_GE(ply.materials[size_t(m)].texture, 0);
  ply.textures = load_texture_pixels(ply);
  EXPECT_EQ(plain_triangle_colours(in_path, ply, factor), 2u);
}

/// The Kd of the first material of an MTL file.
std::array<double, 3> first_kd(const fs::path& obj) { return read_obj(obj.string()).materials.at(0).kd; }

TEST(Scenes, ObjOutputsKeepTheFactorTheTexturesShare) {
  // An OBJ whose textured material has Kd 0.6 (as Meshroom writes): the output OBJ keeps it (viewers
  // that multiply map_Kd by Kd show the output as they showed the input), from the command and from the
  // library; a glTF output stays white.
  const fs::path dir = testing::scratch_folder("scene_texture_factor");
  TexturedMesh grey = testing::disk();
  grey.materials.at(0).kd = {0.6, 0.6, 0.6};
  write_obj(grey, (dir / "obj_in").string(), "disk", ImageEncoding(ImageFormat::kPng));
  ASSERT_EQ(run_quietly(dir / "obj_in" / "disk.obj", dir / "obj_out"), 0) << read_whole(dir / "obj_out.stderr");
  EXPECT_EQ(first_kd(dir / "obj_out" / "disk.obj"), grey.materials[0].kd);
  ASSERT_EQ(run_quietly(dir / "obj_in" / "disk.obj", dir / "glb_out", "--output-format glb"), 0);
  EXPECT_EQ(read_gltf((dir / "glb_out" / "disk.glb").string()).materials.at(0).kd, (std::array<double, 3>{1, 1, 1}));
  // The library's own path (optimize, then write_obj) keeps it too.
  Options small;
  small.size = 64;
  const Result lib = optimize(grey, small);
  write_obj(lib.output, (dir / "lib_out").string(), "disk", ImageEncoding(ImageFormat::kPng));
  EXPECT_EQ(first_kd(dir / "lib_out" / "disk.obj"), grey.materials[0].kd);
  // A glTF's tinted texture: OBJ carries the factor as Kd and says that its viewers mostly do not
  // multiply it; PLY cannot carry it, and says so.
  testing::GridGltf tinted = testing::grid_gltf();
  tinted.doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {0.5, 0.25, 1.0, 1.0};
  const fs::path glb = dir / "tinted.glb";
  write_whole(glb, testing::make_glb(tinted.doc, tinted.bin));
  ASSERT_EQ(run_quietly(glb, dir / "tinted_obj", "--output-format obj"), 0);
  EXPECT_EQ(first_kd(dir / "tinted_obj" / "tinted.obj"), (std::array<double, 3>{0.5, 0.25, 1.0}));
  auto warnings = [&](const char* out) { return json::parse(read_whole(dir / out / "report.json"))["warnings"].dump(); };
  EXPECT_NE(warnings("tinted_obj").find("obj writes as Kd"), std::string::npos) << warnings("tinted_obj");
  ASSERT_EQ(run_quietly(glb, dir / "tinted_ply", "--output-format ply"), 0);
  EXPECT_NE(warnings("tinted_ply").find("1 textured material(s) have a colour factor"), std::string::npos) << warnings("tinted_ply");
}

TEST(Scenes, NothingToBakeIsRefusedWithNothingWritten) {
  const fs::path dir = testing::scratch_folder("scene_nothing");
  testing::GridGltf g = testing::scene_gltf(false);
  for (json& m : g.doc["materials"]) m.erase("pbrMetallicRoughness");
  const fs::path in_path = dir / "plain.glb";
  write_whole(in_path, testing::make_glb(g.doc, g.bin));
  EXPECT_EQ(run_quietly(in_path, dir / "out"), 1);
  const std::string err = read_whole(dir / "out.stderr");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("plain.glb: nothing to bake"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "out" / "plain.glb"));
}

// ---- 4. What the output validates, whatever the input's faults ----

TEST(Scenes, EmptyArraysOfTheInputAreNotCarriedIntoTheOutput) {
  const fs::path dir = testing::scratch_folder("scene_empty_children");
  testing::GridGltf g = testing::grid_gltf();
  g.doc["nodes"][1]["children"] = json::array();
  g.doc["nodes"][1]["extras"] = {{"list", json::array()}};  // the application's own: kept as it is
  const fs::path in_path = dir / "grid.glb";
  write_whole(in_path, testing::make_glb(g.doc, g.bin));
  ASSERT_EQ(run_quietly(in_path, dir / "out"), 0) << read_whole(dir / "out.stderr");
  const TexturedMesh back = read_gltf((dir / "out" / "grid.glb").string());
  ASSERT_NE(back.gltf, nullptr);
  const json& nodes = back.gltf->json["nodes"];
  ASSERT_EQ(nodes.size(), 2u);
  EXPECT_FALSE(nodes[1].contains("children")) << nodes.dump();
  EXPECT_EQ(nodes[1]["extras"]["list"], json::array());
  testing::expect_valid_and_loading(dir / "out" / "grid.glb", 2 * kGridTriangles);
}

// ---- 5. Images tightex cannot decode ----

TEST(Scenes, Ktx2TexturesAreReadFromTheirFallbackOrRefused) {
  const fs::path dir = testing::scratch_folder("scene_ktx2");
  testing::GridGltf g = testing::grid_gltf();
  g.doc["textures"][0]["extensions"] = {{"KHR_texture_basisu", {{"source", 1}}}};
  g.doc["extensionsUsed"] = {"KHR_texture_basisu"};
  write_whole(dir / "fallback.glb", testing::make_glb(g.doc, g.bin));
  ModelReadStats stats;
  const TexturedMesh in = read_gltf((dir / "fallback.glb").string(), {}, &stats);
  ASSERT_EQ(stats.warnings.size(), 1u);
  EXPECT_NE(stats.warnings[0].find("KHR_texture_basisu"), std::string::npos) << stats.warnings[0];
  ASSERT_EQ(run_quietly(dir / "fallback.glb", dir / "out"), 0) << read_whole(dir / "out.stderr");
  testing::expect_valid_and_loading(dir / "out" / "fallback.glb", 2 * kGridTriangles);
  g.doc["textures"][0].erase("source");
  write_whole(dir / "ktx2_only.glb", testing::make_glb(g.doc, g.bin));
  try {
    read_gltf((dir / "ktx2_only.glb").string());
    ADD_FAILURE() << "a KTX2 image without fallback was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ktx2_only.glb: textures[0]: KHR_texture_basisu"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  EXPECT_EQ(run_quietly(dir / "ktx2_only.glb", dir / "refused"), 1);
  EXPECT_FALSE(fs::exists(dir / "refused" / "ktx2_only.glb"));
}

// ---- 6. PLY pages ----

TEST(Scenes, PlyNamesOnlyItsBaseColourPages) {
  const fs::path dir = testing::scratch_folder("scene_ply_pages");
  write_whole(dir / "grid.glb", testing::make_glb(testing::grid_gltf().doc, testing::grid_gltf().bin));
  ASSERT_EQ(run_tightex("'" + (dir / "grid.glb").string() + "' -o '" + (dir / "out").string() + "' --size 64 --output-format ply 2> '" +
                        (dir / "err").string() + "'"),
            0);
  const std::string ply = read_whole(dir / "out" / "grid.ply");
  const std::string header = ply.substr(0, ply.find("end_header"));
  size_t pages = 0;
  for (size_t at = header.find("comment TextureFile"); at != std::string::npos; at = header.find("comment TextureFile", at + 1)) ++pages;
  EXPECT_EQ(pages, 1u) << header;
  EXPECT_NE(read_whole(dir / "err").find("normal map"), std::string::npos) << read_whole(dir / "err");
  const TexturedMesh back = read_ply((dir / "out" / "grid.ply").string());
  EXPECT_EQ(back.textures.size(), 1u);
}

// ---- 7. Messages ----

TEST(Scenes, TilePayloadsNameTheTileRunner) {
  const fs::path dir = testing::scratch_folder("scene_b3dm");
  for (const char* name : {"tile.b3dm", "tile.i3dm", "tile.pnts", "tile.cmpt"}) {
    write_whole(dir / name, "b3dm\x01\x00\x00\x00 not a model");
    EXPECT_EQ(run_quietly(dir / name, dir / "out"), 1) << name;
    const std::string err = read_whole(dir / "out.stderr");
    EXPECT_NE(err.find(name), std::string::npos) << err;
    EXPECT_NE(err.find("python3 -m tightex.tiles"), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace tightex
