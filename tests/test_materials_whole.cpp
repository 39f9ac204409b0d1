// Every material comes out whole: its scalars, every slot it binds (the KHR_materials_* ones and OBJ's
// map statements), one output image per input image role, nothing bound that it did not have; and the
// report's figures are those `tightex measure` computes from the files as written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "command_line.hpp"
#include "gltf_builder.hpp"
#include "io/gltf_document.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"
#include "vertex_coloured.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json read_json(const fs::path& p) {
  std::ifstream f(p);
  return json::parse(f);
}

/// The grid (tests/gltf_builder.hpp) with a second material on half of its triangles: the same base
/// colour image, no metallic-roughness texture and factors of glass (metallic 0, roughness 0.1); the
/// first material's metallic-roughness image, its emissive the base colour's own image and a
/// KHR_materials_specular colour texture.
testing::GridGltf two_material_grid() {
  testing::GridGltf g = testing::grid_gltf(6);
  json& doc = g.doc;
  json& first = doc["materials"][0];
  first["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
  first["pbrMetallicRoughness"]["metallicFactor"] = 0.5;
  first["emissiveTexture"] = {{"index", 0}};
  first["emissiveFactor"] = {1.0, 0.5, 0.25};
  first["extensions"] = {{"KHR_materials_specular", {{"specularColorTexture", {{"index", 1}}}, {"specularFactor", 0.75}}}};
  doc["extensionsUsed"] = {"KHR_materials_specular"};
  json glass = {{"name", "glass"},
                {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.1}}}};
  doc["materials"].push_back(glass);
  // The triangles' second half as a primitive of its own with the glass material.
  json& primitives = doc["meshes"][0]["primitives"];
  const json& indices = doc["accessors"][primitives[0]["indices"].get<size_t>()];
  const size_t count = indices["count"].get<size_t>(), half = count / 6 * 3;
  json second = primitives[0];
  second["material"] = 1;
  const size_t a = primitives[0]["indices"].get<size_t>();
  json first_half = doc["accessors"][a], second_half = doc["accessors"][a];
  first_half["count"] = half;
  second_half["count"] = count - half;
  second_half["byteOffset"] = half * 2;
  doc["accessors"][a] = first_half;
  doc["accessors"].push_back(second_half);
  second["indices"] = doc["accessors"].size() - 1;
  primitives.insert(primitives.begin() + 1, second);
  return g;
}

TEST(MaterialsWhole, GltfSlotsFactorsAndOneImagePerImage) {
  const fs::path dir = testing::scratch_folder("materials_whole_gltf");
  const testing::GridGltf g = two_material_grid();
  testing::write_whole(dir / "grid.glb", testing::make_glb(g.doc, g.bin));
  ASSERT_EQ(
      testing::run_tightex(fmt::format("'{}' -o '{}' --size 64 --quiet --no-html", (dir / "grid.glb").string(), (dir / "out").string())),
      0);
  std::system(fmt::format("rm -rf /tmp/dbg_mw; cp -r {} /tmp/dbg_mw", dir.string()).c_str());
  const TexturedMesh out = read_gltf((dir / "out" / "grid.glb").string());
  const json& doc = out.gltf->json;
  ASSERT_EQ(doc["materials"].size(), 2u);
  const json& first = doc["materials"][0];
  const json& glass = doc["materials"][1];
  // Scalars as they were; the emissive is the base colour's own image, one image for both.
  EXPECT_EQ(first["pbrMetallicRoughness"]["metallicFactor"], 0.5);
  EXPECT_EQ(first["emissiveFactor"], g.doc["materials"][0]["emissiveFactor"]);
  EXPECT_EQ(first["emissiveTexture"]["index"], first["pbrMetallicRoughness"]["baseColorTexture"]["index"]);
  // The specular colour slot re-baked into the new coordinates, its factor kept.
  ASSERT_TRUE(first.contains("extensions") && first["extensions"].contains("KHR_materials_specular"));
  const json& specular = first["extensions"]["KHR_materials_specular"];
  EXPECT_EQ(specular["specularFactor"], 0.75);
  ASSERT_TRUE(specular.contains("specularColorTexture"));
  // The same input image as the metallic-roughness, but read as colour there and as data here: two images.
  EXPECT_NE(specular["specularColorTexture"]["index"], first["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]);
  // Glass: its factors, and no slot it did not bind.
  EXPECT_EQ(glass["name"], "glass");
  EXPECT_EQ(glass["pbrMetallicRoughness"]["roughnessFactor"], 0.1);
  EXPECT_FALSE(glass["pbrMetallicRoughness"].contains("metallicRoughnessTexture"));
  EXPECT_FALSE(glass.contains("emissiveTexture"));
  // Images: the base colour (and emissive), the normal map, the metallic-roughness, the specular colour.
  EXPECT_EQ(doc["images"].size(), 4u);

  // The report's figures are those of the written files (`tightex measure`), to the last digit.
  const json report = read_json(dir / "out" / "report.json");
  const Metrics measured = measure(read_gltf((dir / "grid.glb").string()), out);
  EXPECT_EQ(report["metrics"]["surface_psnr_db"].get<double>(), measured.surface_psnr);
  ASSERT_EQ(report["metrics"]["maps"].size(), measured.maps.size());
  for (size_t i = 0; i < measured.maps.size(); ++i) {
    const json& entry = report["metrics"]["maps"][i];
    EXPECT_EQ(entry["slot"], material_slot_name(measured.maps[i].slot));
    if (entry.contains("surface_psnr_db")) {
      EXPECT_EQ(entry["surface_psnr_db"].get<double>(), measured.maps[i].surface_psnr) << entry["slot"];
      EXPECT_GE(measured.maps[i].surface_psnr, 35.0) << entry["slot"];
    }
  }
  EXPECT_EQ(report["metrics"]["psnr_samples"], kPsnrPoints);
  EXPECT_GE(measured.surface_psnr, 35.0);
}

TEST(MaterialsWhole, SurfacePsnrIsOfUnroundedEffectiveValues) {
  // The same model against itself with one material's colour factor halved: the figure is that of the
  // factor alone, in linear light (an untextured face shows its factor; a textured one texture x factor).
  TexturedMesh in = testing::sphere();
  in.materials[0].kd_multiplies_texture = true;
  EXPECT_EQ(measure(in, in, 20000).surface_psnr, 99.0);
  TexturedMesh darker = in;
  darker.materials[0].kd = {0.5, 0.5, 0.5};
  const double psnr = measure(in, darker, 20000).surface_psnr;
  EXPECT_LT(psnr, 30.0);
  EXPECT_GT(psnr, 5.0);
  // Without kd_multiplies_texture (OBJ: viewers show map_Kd alone) the factor does not count.
  in.materials[0].kd_multiplies_texture = darker.materials[0].kd_multiplies_texture = false;
  EXPECT_EQ(measure(in, darker, 20000).surface_psnr, 99.0);
}

TEST(MaterialsWhole, ObjMaterialsStaySeparateWithTheirStatementsAndMaps) {
  const fs::path dir = testing::scratch_folder("materials_whole_obj");
  TexturedMesh m = testing::sphere();
  // Two materials on one texture, differing in their scalars; the second binds a displacement map.
  m.materials.push_back(m.materials[0]);
  m.materials[0].name = "skin";
  m.materials[1].name = "cloth";
  for (size_t t = 0; t < m.num_triangles(); t += 2) m.face_material[t] = 1;
  write_obj(m, (dir / "in").string(), "sphere", ImageFormat::kPng);
  std::string mtl = testing::read_whole(dir / "in" / "sphere.mtl");
  for (size_t k; (k = mtl.find("Ks 0 0 0\n")) != std::string::npos;) mtl.erase(k, 9);
  const std::string cloth = "newmtl cloth\n";
  const size_t at = mtl.find(cloth) + cloth.size();
  mtl.insert(at, "Ks 0.2 0.2 0.2\nNs 12\nPr 0.7\ndisp sphere_texture.png\n");
  const size_t skin = mtl.find("newmtl skin\n") + std::string("newmtl skin\n").size();
  mtl.insert(skin, "Ks 0.9 0.9 0.9\nNs 250\n");
  testing::write_whole(dir / "in" / "sphere.mtl", mtl);
  fs::path texture;
  for (const auto& e : fs::directory_iterator(dir / "in"))
    if (e.path().extension() == ".png") texture = e.path();
  ASSERT_FALSE(texture.empty());
  if (texture.filename() != "sphere_texture.png") fs::copy_file(texture, dir / "in" / "sphere_texture.png");

  ASSERT_EQ(testing::run_tightex(
                fmt::format("'{}' -o '{}' --size 64 --quiet --no-html", (dir / "in" / "sphere.obj").string(), (dir / "out").string())),
            0);
  const std::string out = testing::read_whole(dir / "out" / "sphere.mtl");
  for (const char* line : {"newmtl skin\n", "newmtl cloth\n", "Ks 0.2 0.2 0.2\n", "Ns 12\n", "Pr 0.7\n", "Ks 0.9 0.9 0.9\n", "Ns 250\n"})
    EXPECT_NE(out.find(line), std::string::npos) << line << " in\n" << out;
  EXPECT_EQ(out.find("Ks 1 1 1"), std::string::npos) << out;
  const size_t cloth_at = out.find("newmtl cloth\n"), disp_at = out.find("\ndisp ");
  ASSERT_NE(disp_at, std::string::npos) << out;
  const size_t next = out.find("newmtl", cloth_at + 1);
  EXPECT_TRUE(disp_at > cloth_at && (next == std::string::npos || disp_at < next)) << "disp belongs to cloth only:\n" << out;
  const TexturedMesh back = read_obj((dir / "out" / "sphere.obj").string());
  ASSERT_EQ(back.materials.size(), 2u);
  for (const Material& mat : back.materials) EXPECT_EQ(mat.texture, back.materials[0].texture) << "one atlas for both";
  const TexturedMesh in = read_obj((dir / "in" / "sphere.obj").string());
  const Metrics figures = measure(in, back);
  EXPECT_EQ(figures.lost_triangles, 0u);
  bool displacement = false;
  for (const MaterialMapFigures& f : figures.maps) {
    EXPECT_GE(f.surface_psnr, 35.0) << material_slot_name(f.slot);
    displacement = displacement || f.slot == MaterialSlot::kDisplacement;
  }
  EXPECT_TRUE(displacement);
}

TEST(MaterialsWhole, AVertexColouredObjWithoutItsMtlIsReadWithAWarning) {
  const fs::path dir = testing::scratch_folder("materials_whole_vc");
  const TexturedMesh coloured = testing::vertex_coloured(testing::sphere());
  testing::write_vertex_coloured_obj(coloured, (dir / "model.obj").string());
  std::string obj = testing::read_whole(dir / "model.obj");
  testing::write_whole(dir / "model.obj", "mtllib missing.mtl\nusemtl paint\n" + obj);
  ModelReadStats stats;
  const TexturedMesh m = read_model((dir / "model.obj").string(), {}, &stats);
  EXPECT_EQ(m.num_triangles(), coloured.num_triangles());
  ASSERT_EQ(stats.warnings.size(), 1u);
  EXPECT_NE(stats.warnings[0].find("missing.mtl"), std::string::npos) << stats.warnings[0];
  EXPECT_EQ(stats.vertex_coloured_triangles, m.num_triangles());
  // Without vertex colours the missing library is still an error naming it.
  testing::write_whole(dir / "plain.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  try {
    read_model((dir / "plain.obj").string());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.mtl"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tightex
