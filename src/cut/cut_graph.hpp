// The cut graph (paper §4.2): which edges of a surface to cut so that it becomes a topological disk.
#pragma once
#include <string>
#include <vector>

#include "core/graph.hpp"
#include "core/surface.hpp"

namespace tightex {

/// The edges to cut, per edge of the EdgeGraph they were computed on (1 = cut), and how they were found.
struct CutGraph {
  std::vector<char> cut_edge;
  /// "disk": nothing to cut; "path": the single seam of a closed genus-0 surface; "cut-graph": tree-cotree,
  /// with " (real-first)" when the dual tree had to join the real faces before entering a cap.
  std::string method;
};

/// Computes a cut graph of a connected manifold surface (paper §4.2): nothing for a disk; for a closed
/// genus-0 surface the shortest path (g.cost, so it follows the input's seams where that costs little)
/// between two far-apart vertices (double Dijkstra sweep: the paper's single seam); otherwise a cut
/// graph by tree-cotree (shortest-path tree rooted on the longest boundary loop, or near the middle of a
/// diameter on a closed surface, plus a greedy dual tree; Erickson & Whittlesey 2005), pruned of
/// dangling branches. Where the surface holds scaffolding (caps: face_parent == kNone) and the cut
/// graph would leave the caps as the only link between some real faces, the dual tree is rebuilt to
/// join the real faces before it enters any cap (the cut then runs through the caps).
/// Requires: `s` connected and manifold, `g` = EdgeGraph(s, seams).
/// Guarantees: cutting `s` along the result (cut_along_edges) gives one boundary loop and Euler
/// characteristic 1; boundary edges are never in it. The real faces may still fall apart where the caps
/// leave no other way (real_faces_apart tells).
/// Throws: InternalError if `s` is not manifold (boundary_loops).
CutGraph compute_cut_graph(const Surface& s, const EdgeGraph& g);

/// Index of the longest of `loops` by 3D length (the first of equal ones; 0 where there are none).
size_t longest_loop(const Surface& s, const std::vector<std::vector<uint32_t>>& loops);

/// Whether the real faces of `s` (face_parent != kNone; caps are scaffolding) fall apart into more than
/// one group through the interior edges that are not cut. `cut_edge`: per edge of `g` = EdgeGraph(s).
bool real_faces_apart(const Surface& s, const EdgeGraph& g, const std::vector<char>& cut_edge);

}  // namespace tightex
