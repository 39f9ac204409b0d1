#include "report/welded_edges.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>

namespace tightex {

namespace {

/// Vertex ids by bit-equal position: sorted by the coordinates' bits (a sort on every core, where a
/// hash map's inserts miss the cache one by one), each run of equal positions one id.
std::vector<uint32_t> weld_positions(const TexturedMesh& m) {
  struct Keyed {
    std::array<uint64_t, 3> key;
    uint32_t vertex;
  };
  std::vector<Keyed> keyed(m.num_vertices());
  tbb::parallel_for(size_t(0), keyed.size(), [&](size_t v) {
    const Vec3& p = m.positions[v];
    keyed[v] = {{position_bits(p.x()), position_bits(p.y()), position_bits(p.z())}, uint32_t(v)};
  });
  tbb::parallel_sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) { return a.key < b.key; });
  std::vector<uint32_t> id(m.num_vertices());
  uint32_t next = 0;
  for (size_t i = 0; i < keyed.size(); ++i) {
    if (i > 0 && keyed[i].key != keyed[i - 1].key) ++next;
    id[keyed[i].vertex] = next;
  }
  return id;
}

}  // namespace

WeldedEdges welded_edges(const TexturedMesh& m) {
  WeldedEdges e;
  e.vertex = weld_positions(m);
  const auto nh = uint32_t(3 * m.num_triangles());
  const uint32_t welded = e.vertex.empty() ? 0 : *std::max_element(e.vertex.begin(), e.vertex.end()) + 1;
  // Bucketed by the lower end (a counting sort, half-edges ascending in each bucket), each bucket then
  // ordered by the higher end: the order a sort of (lower, higher, half-edge) gives, without sorting
  // all 3 x triangles.
  std::vector<uint32_t> start(size_t(welded) + 1, 0);
  for (uint32_t h = 0; h < nh; ++h) ++start[size_t(e.lower(m, h)) + 1];
  for (uint32_t v = 0; v < welded; ++v) start[v + 1] += start[v];
  e.by_ends.resize(nh);
  {
    std::vector<uint32_t> next(start.begin(), start.end() - 1);
    for (uint32_t h = 0; h < nh; ++h) e.by_ends[next[e.lower(m, h)]++] = h;
  }
  tbb::parallel_for(uint32_t(0), welded, [&](uint32_t v) {
    std::stable_sort(e.by_ends.begin() + start[v], e.by_ends.begin() + start[v + 1],
                     [&](uint32_t x, uint32_t y) { return e.higher(m, x) < e.higher(m, y); });
  });
  return e;
}

}  // namespace tightex
