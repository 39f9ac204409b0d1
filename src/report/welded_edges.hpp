// A model's edges as the report's figures see a surface: its vertices welded by position, so that a
// model written with its vertices split along its charts is one surface, and its half-edges grouped by
// their two welded ends. The charts (metrics.hpp) and the page's seams (html_report.hpp) both read it.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/mesh.hpp"

namespace tightex {

/// The bits of a coordinate, with -0.0 as 0.0: equal bits, equal positions.
inline uint64_t position_bits(double d) {
  if (d == 0.0) d = 0.0;
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}

struct WeldedEdges {
  std::vector<uint32_t> vertex;   // per vertex, its welded id: the same for bit-equal positions (0.0 and -0.0 alike)
  std::vector<uint32_t> by_ends;  // half-edges (3t + k: triangle t's corner k to corner k + 1) by (lower end, higher end, half-edge)

  /// The welded ends of half-edge h of `m` (the model this was made from): its start (k 0) and end (k 1).
  uint32_t end_of(const TexturedMesh& m, uint32_t h, int k) const { return vertex[m.triangles[h / 3][(h % 3 + uint32_t(k)) % 3]]; }
  uint32_t lower(const TexturedMesh& m, uint32_t h) const { return std::min(end_of(m, h, 0), end_of(m, h, 1)); }
  uint32_t higher(const TexturedMesh& m, uint32_t h) const { return std::max(end_of(m, h, 0), end_of(m, h, 1)); }

  /// Calls f(i, j) for each run by_ends[i, j) of the half-edges that join the same two welded vertices.
  template <class F>
  void for_each_edge(const TexturedMesh& m, F&& f) const {
    for (size_t i = 0; i < by_ends.size();) {
      const uint32_t a = lower(m, by_ends[i]), b = higher(m, by_ends[i]);
      size_t j = i + 1;
      while (j < by_ends.size() && lower(m, by_ends[j]) == a && higher(m, by_ends[j]) == b) ++j;
      f(i, j);
      i = j;
    }
  }
};

/// The welded edges of `m`, on every core. Requires a valid mesh (as read_model returns it).
WeldedEdges welded_edges(const TexturedMesh& m);

}  // namespace tightex
