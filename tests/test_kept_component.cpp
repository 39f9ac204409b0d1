// The last resort of the pipeline: a component that neither the full method nor the plain
// fallback can map is output as it came, with its input texture coordinates and a copy of its input
// material(s) and texture(s), and reported; no triangle of the input is ever lost. The failure is forced
// with the pipeline's test hook (PlanHooks), on meshes of the catalogue.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include <fmt/format.h>

#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "mesh_catalogue.hpp"
#include "pipeline/plan_state.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/tightex.hpp"

namespace fs = std::filesystem;
using namespace tightex;

namespace {

/// Input triangles of component c of a plan.
std::set<uint32_t> triangles_of(const Plan& plan, size_t c) {
  std::set<uint32_t> s;
  for (uint32_t t : plan_state(plan).components[c].input_face) s.insert(t);
  return s;
}

bool same_pixels(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) return false;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    if (a.pixels[i].r != b.pixels[i].r || a.pixels[i].g != b.pixels[i].g || a.pixels[i].b != b.pixels[i].b ||
        a.pixels[i].a != b.pixels[i].a)
      return false;
  return true;
}

/// Every triangle of `kept` is in `out` with its input corners, its input texture coordinates bit for bit
/// and a material that samples the same texture the same way (-s/-o included).
void expect_kept_as_input(const TexturedMesh& in, const TexturedMesh& out, const std::set<uint32_t>& kept) {
  std::map<Tri, uint32_t> out_of;
  for (uint32_t t = 0; t < out.num_triangles(); ++t) out_of[out.triangles[t]] = t;
  for (uint32_t t : kept) {
    SCOPED_TRACE("input triangle " + std::to_string(t));
    const auto it = out_of.find(in.triangles[t]);
    ASSERT_NE(it, out_of.end());
    const uint32_t o = it->second;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(out.corner_uv[3 * o + size_t(k)], in.corner_uv[3 * t + size_t(k)]);
      EXPECT_EQ(out.sampled_uv(o, k), in.sampled_uv(t, k));
    }
    const Material& om = out.materials[size_t(out.face_material[o])];
    const int32_t im = in.face_material[t];
    // Its material's name as it was, made safe as an MTL token ("none" without one), with a number
    // where the name is taken.
    std::string name = im >= 0 ? in.materials[size_t(im)].name : std::string("none");
    std::replace(name.begin(), name.end(), ' ', '_');
    EXPECT_EQ(om.name.rfind(name, 0), 0u) << om.name;
    if (im < 0 || in.materials[size_t(im)].texture < 0) {
      EXPECT_EQ(om.texture, -1);
      continue;
    }
    ASSERT_GE(om.texture, 0);
    EXPECT_TRUE(same_pixels(out.textures[size_t(om.texture)].image, in.textures[size_t(in.materials[size_t(im)].texture)].image));
  }
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

// Atlas: component 1 of multi_component (its own material, texture and -s/-o) keeps its UVs; the others
// are mapped as usual. Written, read back and measured: nothing lost, the kept part exactly as input.
TEST(KeptComponent, KeepsInputUvsMaterialAndTextureAndLosesNothing) {
  TexturedMesh in = tightex::testing::multi_component();
  in.textures[0].path = "/scans/albedo.png";
  Options opt;
  opt.size = 256;
  const Plan normal = plan_charts(in, opt);
  ASSERT_GE(plan_state(normal).components.size(), 3u);
  for (const std::string& k : plan_state(normal).kept) EXPECT_TRUE(k.empty());
  // Component 1 gets a material of its own, with a tiled and shifted texture of its own.
  const std::set<uint32_t> kept_tris = triangles_of(normal, 1);
  Material skin;
  skin.name = "skin 2";
  skin.kd = {0.5, 0.25, 1.0};
  skin.texture = 1;
  skin.uv_scale = {2.0, 1.0};
  skin.uv_offset = {0.25, 0.0};
  in.materials.push_back(skin);
  in.textures.push_back(Texture{"textures/skin.jpg", tightex::testing::checker_image(32, 16, 4)});
  for (uint32_t t : kept_tris) in.face_material[t] = 1;

  const Plan plan = plan_charts(in, opt, PlanHooks{{1}});
  ASSERT_EQ(plan_state(plan).kept.size(), plan_state(plan).components.size());
  for (size_t c = 0; c < plan_state(plan).kept.size(); ++c) EXPECT_EQ(plan_state(plan).kept[c].empty(), c != 1) << c;
  EXPECT_EQ(triangles_of(plan, 1), kept_tris);
  const Result r = bake_plan(plan, in, opt);
  const auto& comp = report_json(r.report)["components"][1];
  EXPECT_TRUE(comp["kept_original_uvs"].get<bool>());
  EXPECT_NE(comp["kept_reason"].get<std::string>().find("forced"), std::string::npos);
  EXPECT_FALSE(report_json(r.report)["components"][0]["kept_original_uvs"].get<bool>());
  EXPECT_EQ(report_json(r.report)["preparation"]["components_kept_original_uvs"].get<size_t>(), 1u);

  const TexturedMesh& out = r.output;
  EXPECT_EQ(out.num_triangles(), in.num_triangles());
  const Metrics m = measure(in, out, 20000);
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  expect_kept_as_input(in, out, kept_tris);
  // The mapped triangles use the new texture only, inside [0,1].
  for (uint32_t t = 0; t < out.num_triangles(); ++t)
    if (out.materials[size_t(out.face_material[t])].texture == 0)  // the new image
      for (int k = 0; k < 3; ++k)
        EXPECT_TRUE(out.corner_uv[3 * t + size_t(k)].minCoeff() >= 0 && out.corner_uv[3 * t + size_t(k)].maxCoeff() <= 1);
  ASSERT_EQ(out.materials.size(), 2u);
  EXPECT_EQ(out.materials[1].name, "skin_2");
  ASSERT_EQ(out.textures.size(), 2u);
  EXPECT_EQ(out.textures[1].path, "kept_skin");

  // On disk: the MTL names the copied texture with its -s/-o, the texture loads, and the model reads
  // back with the kept part exactly as the input had it.
  TempDir dir("tightex_kept");
  write_obj(out, dir.path.string(), "model", ImageFormat::kPng);
  for (const char* f : {"model.obj", "model.mtl", "multi_component_tightex.png", "kept_skin.png"})
    EXPECT_TRUE(fs::is_regular_file(dir.path / f)) << f;
  const std::string mtl = slurp(dir.path / "model.mtl");
  EXPECT_NE(mtl.find("newmtl skin_2\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("Kd 0.5 0.25 1\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("map_Kd -s 2 1 1 -o 0.25 0 0 kept_skin.png\n"), std::string::npos) << mtl;
  EXPECT_TRUE(same_pixels(load_image((dir.path / "kept_skin.png").string()), in.textures[1].image));
  const TexturedMesh back = read_obj((dir.path / "model.obj").string());
  expect_kept_as_input(in, back, kept_tris);
  const Metrics mb = measure(in, back, 20000);
  EXPECT_EQ(mb.lost_triangles, 0u);
}

// Per-component layout: the kept component's own image would stay empty and is not written; the other
// images keep their order, renumbered densely.
TEST(KeptComponent, PerComponentLayoutWritesNoEmptyImage) {
  const TexturedMesh in = tightex::testing::multi_component();
  Options opt;
  opt.size = 128;
  opt.layout = Layout::kPerComponent;
  const Plan plan = plan_charts(in, opt, PlanHooks{{0}});
  const size_t nc = plan_state(plan).components.size();
  const Result r = bake_plan(plan, in, opt);
  const TexturedMesh& out = r.output;
  // nc - 1 new images and the input's texture, copied once.
  ASSERT_EQ(out.textures.size(), nc);
  for (size_t i = 0; i + 1 < nc; ++i) EXPECT_EQ(out.textures[i].path, fmt::format("multi_component_tightex_{}", i));
  EXPECT_EQ(out.textures.back().path, "kept_multi_component");  // the catalogue's texture is "multi_component.png"
  for (const Texture& t : out.textures) EXPECT_FALSE(t.image.empty());
  EXPECT_EQ(measure(in, out, 20000).lost_triangles, 0u);
  expect_kept_as_input(in, out, triangles_of(plan, 0));
}

// Every component kept, some triangles without a material: no new texture at all, a white material for
// the triangles that had none, and the model still writes and reads back whole.
// Every component kept, and triangles without a material (nothing to bake: written as they came, beside
// the kept component).
TEST(KeptComponent, AllKeptAndNoMaterial) {
  TexturedMesh in = tightex::testing::sphere();
  // The triangles around the first vertex (a pole): the sphere's rest stays one component without them.
  std::vector<uint32_t> untextured;
  for (uint32_t t = 0; t < in.num_triangles(); ++t)
    if (in.triangles[t][0] == 0 || in.triangles[t][1] == 0 || in.triangles[t][2] == 0) in.face_material[t] = -1, untextured.push_back(t);
  ASSERT_GE(untextured.size(), 3u);
  ASSERT_LE(untextured.size(), in.num_triangles() / 4);
  Options opt;
  opt.size = 64;
  const Plan plan = plan_charts(in, opt, PlanHooks{{0}});
  ASSERT_EQ(plan_state(plan).components.size(), 1u);
  EXPECT_EQ(plan_state(plan).set_aside.untextured, untextured);
  const Result r = bake_plan(plan, in, opt);
  const TexturedMesh& out = r.output;
  ASSERT_EQ(out.materials.size(), 2u);
  EXPECT_EQ(out.textures.size(), 1u);  // the input's, copied; no empty new image
  EXPECT_EQ(report_json(r.report)["preparation"]["untextured_kept"], untextured.size());
  EXPECT_EQ(measure(in, out, 20000).lost_triangles, 0u);
  expect_kept_as_input(in, out, triangles_of(plan, 0));
  expect_kept_as_input(in, out, std::set<uint32_t>(untextured.begin(), untextured.end()));
  TempDir dir("tightex_kept_all");
  write_obj(out, dir.path.string(), "sphere", ImageFormat::kJpeg);
  EXPECT_TRUE(fs::is_regular_file(dir.path / "kept_sphere.jpg"));
  EXPECT_FALSE(fs::exists(dir.path / "sphere_tightex.jpg"));
  const TexturedMesh back = read_obj((dir.path / "sphere.obj").string());
  EXPECT_EQ(back.num_triangles(), in.num_triangles());
  EXPECT_EQ(measure(in, back, 20000).lost_triangles, 0u);
}

// tightex's own output given back: one chart per component filling its texture already. Mapped again it
// could only be resampled, so every component keeps its coordinates and image (the pixels as they
// were, nothing lost); a budget asked for maps it as any input.
TEST(KeptComponent, AnOutputGivenBackIsKeptAsItCame) {
  const TexturedMesh in = tightex::testing::multi_component();
  const Result first = optimize(in, Options{});
  const TexturedMesh& once = first.output;
  ASSERT_FALSE(report_json(first.report)["preparation"]["already_tight"].get<bool>());  // the catalogue's atlas is fragmented
  const Plan plan = plan_charts(once, Options{});
  const size_t nc = plan_state(plan).components.size();
  EXPECT_EQ(plan.kept_components(), nc);
  const Result again = bake_plan(plan, once, Options{});
  EXPECT_TRUE(report_json(again.report)["preparation"]["already_tight"].get<bool>());
  ASSERT_EQ(again.output.textures.size(), once.textures.size());
  for (size_t i = 0; i < once.textures.size(); ++i) EXPECT_TRUE(same_pixels(again.output.textures[i].image, once.textures[i].image));
  const Metrics m = measure(once, again.output, 20000);
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  EXPECT_GE(m.surface_psnr, 99.0);
  Options sized;
  sized.size = 64;
  const Plan remapped = plan_charts(once, sized);
  EXPECT_EQ(remapped.kept_components(), 0u);
  // Prepared for the default budget (so not cut), then planned with one: each component cut as it is mapped.
  const Plan prepared_then_sized = plan_charts(once, sized, prepare_mesh(once, Options{}));
  EXPECT_EQ(prepared_then_sized.kept_components(), 0u);
  EXPECT_EQ(measure(once, bake_plan(prepared_then_sized, once, sized).output, 20000).lost_triangles, 0u);
}
