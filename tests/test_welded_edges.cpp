// The report's welded edges (report/welded_edges.hpp): vertices welded by position, half-edges grouped
// by their welded ends, which the measure's charts and the page's seams both read.
#include <gtest/gtest.h>

#include <vector>

#include "mesh_catalogue.hpp"
#include "report/html_report.hpp"
#include "report/metrics.hpp"
#include "report/welded_edges.hpp"

namespace tightex {
namespace {

/// Two triangles of a unit square written as separate pieces (six vertices), as a model split along its
/// charts is: the shared edge's ends are two pairs of vertices at equal positions, one corner at -0.0
/// where its twin is at 0.0.
TexturedMesh split_square() {
  TexturedMesh m = testing::make_textured(
      "square", {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {-0.0, 1.0, 0.0}, {1.0, 0.0, 0.0}, {1.0, 1.0, 0.0}},
      {{0, 1, 2}, {3, 4, 5}});
  m.corner_uv = {{0, 0}, {1, 0}, {0, 1}, {0, 1}, {1, 0}, {1, 1}};
  return m;
}

TEST(WeldedEdges, EqualPositionsAreOneVertexAndTheirEdgeOneRun) {
  const TexturedMesh m = split_square();
  const WeldedEdges e = welded_edges(m);
  ASSERT_EQ(e.vertex.size(), 6u);
  EXPECT_EQ(e.vertex[1], e.vertex[4]);
  EXPECT_EQ(e.vertex[2], e.vertex[3]);  // 0.0 and -0.0
  EXPECT_NE(e.vertex[0], e.vertex[5]);
  EXPECT_NE(e.vertex[0], e.vertex[1]);
  ASSERT_EQ(e.by_ends.size(), 6u);
  // Five edges: the shared one (triangle 0's edge 1, triangle 1's edge 0) a run of two, in half-edge
  // order; the four borders runs of one. Every half-edge once.
  std::vector<std::vector<uint32_t>> runs;
  e.for_each_edge(m, [&](size_t i, size_t j) { runs.emplace_back(e.by_ends.begin() + long(i), e.by_ends.begin() + long(j)); });
  ASSERT_EQ(runs.size(), 5u);
  size_t pairs = 0, half_edges = 0;
  for (const auto& run : runs) {
    half_edges += run.size();
    if (run.size() != 2) continue;
    ++pairs;
    EXPECT_EQ(run, (std::vector<uint32_t>{1, 3}));
  }
  EXPECT_EQ(pairs, 1u);
  EXPECT_EQ(half_edges, 6u);
}

// The charts and the page's seams read the welded surface: the split square with equal texture
// coordinates on both sides is one chart, the shared edge no seam; moved in texture space, two charts
// and a seam on both sides.
TEST(WeldedEdges, ChartsAndSeamsFollowTheWeldedSurface) {
  TexturedMesh m = split_square();
  EXPECT_EQ(count_charts(m, nullptr), 1u);
  const auto seams = [](const TexturedMesh& model) {
    const nlohmann::json data = nlohmann::json::parse(html_model_data(model, model));
    return data["models"][0]["seams"].get<std::string>();
  };
  // Bits per triangle, edge k from corner k to k + 1 (base64): 0b101 and 0b110, the shared edge clear.
  EXPECT_EQ(seams(m), "BQY=");
  for (size_t k = 3; k < 6; ++k) m.corner_uv[k].x() += 0.5;
  EXPECT_EQ(count_charts(m, nullptr), 2u);
  EXPECT_EQ(count_charts(m, welded_edges(m), nullptr), 2u);
  EXPECT_EQ(seams(m), "Bwc=");  // 0b111 twice
}

}  // namespace
}  // namespace tightex
