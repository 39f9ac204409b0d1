#include "core/cut_along_edges.hpp"

namespace tightex {

Surface cut_along_edges(const Surface& s, const EdgeGraph& g, const std::vector<char>& cut_edge) {
  uint32_t groups = 0;
  const auto corner_vertex = group_corners(
      s, [&](uint32_t h) { return !cut_edge[g.halfedge_edge[h]]; }, &groups);
  Surface cut = regroup(s, corner_vertex, groups);
  inherit_input_map(cut, s);
  return cut;
}

}  // namespace tightex
