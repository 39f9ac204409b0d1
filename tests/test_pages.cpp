// Texture pages (Options::max_page_side): a budget larger than a page goes on several pages, a component
// too large for one page is split into pieces (split_into_parts), and every other property holds.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "mesh_catalogue.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

TEST(SplitIntoParts, PiecesAreConnectedManifoldAndCoverEveryFaceOnce) {
  const std::vector<Surface> comps = split_components(prepare_surface(cat::torus(), nullptr));
  ASSERT_EQ(comps.size(), 1u);
  const Surface& torus = comps[0];
  for (int parts : {1, 2, 5, 9}) {
    const std::vector<Surface> pieces = split_into_parts(torus, parts);
    EXPECT_LE(pieces.size(), size_t(parts));
    EXPECT_GE(pieces.size(), parts > 1 ? 2u : 1u);
    std::multiset<uint32_t> faces;
    for (const Surface& piece : pieces) {
      EXPECT_EQ(split_components(piece).size(), 1u) << "a piece is one connected surface";
      const Topology t = topology_of(piece);
      EXPECT_EQ(t.faces, piece.num_faces());
      for (uint32_t f = 0; f < piece.num_faces(); ++f) {
        const uint32_t parent = piece.face_parent[f];
        faces.insert(parent);
        EXPECT_EQ(piece.input_face[f], torus.input_face[parent]);
        for (int k = 0; k < 3; ++k)
          EXPECT_EQ(piece.positions[piece.triangles[f][size_t(k)]], torus.positions[piece.vertex_parent[piece.triangles[f][size_t(k)]]]);
      }
      if (parts > 1) EXPECT_GE(t.boundary_loops, 1u) << "a piece of a closed surface has a border";
    }
    EXPECT_EQ(faces.size(), torus.num_faces());
    EXPECT_EQ(std::set<uint32_t>(faces.begin(), faces.end()).size(), torus.num_faces()) << "each face in one piece";
  }
}

/// The torus and its fragments optimized at a 512 x 512 budget with pages of at most `max_side`.
Result optimized_with_pages(int max_side) {
  Options opt;
  opt.size = 512;
  opt.aspect = 1.0;
  opt.max_page_side = max_side;
  return optimize(cat::multi_component(), opt);
}

TEST(Pages, ABudgetBeyondThePageGoesOnSeveralPagesWithEveryPropertyKept) {
  const TexturedMesh in = cat::multi_component();
  const Result r = optimized_with_pages(200);
  const nlohmann::json& pages = report_json(r.report)["pages"];
  EXPECT_GE(pages["count"].get<size_t>(), 7u);  // 512^2 texels in pages of at most 200^2
  EXPECT_EQ(pages["count"].get<size_t>(), r.output.textures.size());
  EXPECT_GE(pages["components_split"].get<size_t>(), 1u) << "the torus alone holds more than a page";
  EXPECT_TRUE(pages["reason"].is_string());
  size_t texels = 0;
  for (const Texture& t : r.output.textures) {
    EXPECT_LE(t.image.width, 200);
    EXPECT_LE(t.image.height, 200);
    texels += size_t(t.image.width) * size_t(t.image.height);
  }
  EXPECT_GE(double(texels), 0.95 * 512 * 512) << "the pages hold the budget";
  const Metrics m = measure(in, r.output, 20000);
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  EXPECT_EQ(m.charts, report_json(r.report)["preparation"]["components"].get<size_t>()) << "one chart per component or piece";
  for (double u : m.output.image_utilization) EXPECT_GE(u, 0.99);
  // The same model without a cap below its budget: one page, nothing split.
  const Result one = optimized_with_pages(kDefaultMaxPageSide);
  EXPECT_EQ(report_json(one.report)["pages"]["count"], 1);
  EXPECT_EQ(report_json(one.report)["pages"]["components_split"], 0);
  EXPECT_TRUE(report_json(one.report)["pages"]["reason"].is_null());
  // Colour kept: each piece's border is a seam more, so the split model loses a little to the one-page
  // one (57.7 dB), but stays far above what the eye sees.
  EXPECT_GT(m.surface_psnr, 45.0);
}

TEST(Pages, AComponentOfMoreTrianglesThanAPieceMayHoldIsSplitInEitherLayout) {
  const TexturedMesh in = cat::multi_component();  // a torus of 1024 triangles, a disk, two floaters
  Options opt;
  opt.size = 512;
  opt.aspect = 1.0;
  opt.max_page_side = 0;  // no page cap: the split is the triangles' alone
  opt.max_piece_faces = 300;
  const Result r = optimize(in, opt);
  const nlohmann::json& pages = report_json(r.report)["pages"];
  EXPECT_EQ(pages["count"], 1);
  EXPECT_EQ(pages["max_piece_faces"], 300);
  EXPECT_GE(pages["components_split"].get<size_t>(), 1u) << "the torus holds more than 300 triangles";
  EXPECT_GE(pages["pieces"].get<size_t>(), 3u) << "1024 triangles in pieces of at most 300: four pieces or more";
  size_t triangles = 0;
  for (const nlohmann::json& c : report_json(r.report)["components"]) {
    EXPECT_LE(c["triangles"].get<size_t>(), 300u);
    triangles += c["triangles"].get<size_t>();
  }
  EXPECT_EQ(triangles, in.num_triangles());
  const Metrics m = measure(in, r.output, 20000);
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  EXPECT_EQ(m.charts, report_json(r.report)["preparation"]["components"].get<size_t>()) << "one chart per component or piece";
  for (double u : m.output.image_utilization) EXPECT_GE(u, 0.99);
  EXPECT_GT(m.surface_psnr, 45.0);
  // Per component: each piece its own chart and texture.
  Options per_component = opt;
  per_component.layout = Layout::kPerComponent;
  const Result each = optimize(in, per_component);
  EXPECT_GE(report_json(each.report)["pages"]["components_split"].get<size_t>(), 1u);
  const Metrics me = measure(in, each.output, 20000);
  EXPECT_EQ(me.lost_triangles, 0u);
  EXPECT_EQ(me.flipped, 0u);
  EXPECT_EQ(me.charts, each.output.textures.size()) << "one texture per component or piece";
  EXPECT_EQ(me.charts, report_json(each.report)["preparation"]["components"].get<size_t>());
  // No cap: the torus stays one chart.
  opt.max_piece_faces = 0;
  const Result whole = optimize(in, opt);
  EXPECT_EQ(report_json(whole.report)["pages"]["components_split"], 0);
  EXPECT_TRUE(report_json(whole.report)["pages"]["max_piece_faces"].is_null());
}

TEST(PagesCli, ANegativePieceCapIsRefusedAndNothingIsWritten) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tightex_piece_cap_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  write_obj(cat::multi_component(), (dir / "in").string(), "multi", ImageFormat::kPng);
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + (dir / "in" / "multi.obj").string() + "' -o '" + (dir / "out").string() +
                          "' --quiet --max-piece-faces -5 2> '" + (dir / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
  std::ifstream err(dir / "err");
  const std::string text((std::istreambuf_iterator<char>(err)), {});
  EXPECT_NE(text.substr(0, text.find('\n')).find("--max-piece-faces"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tightex
