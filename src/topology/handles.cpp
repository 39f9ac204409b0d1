// Topological denoising (paper §4.1, Fig. 5): every handle of a component is cut along a short
// non-separating loop until the component has genus 0. Each cut leaves two boundary loops, which the
// hole stage then treats like any hole (capped with scaffolding when small, opened into the seam
// otherwise). The loops become seam; no triangle is added to the output or removed from it.
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/error.hpp"
#include "topology/graph.hpp"
#include "topology/topology.hpp"

namespace tightex {

namespace {

/// The shortest generator loop through `root`: the leftover edge with the smallest loop cost, with
/// the two tree paths trimmed where they share a prefix (so the loop is a simple cycle). Returns the
/// loop's edges, its 3D length and its cost (g.cost); empty when the surface has genus 0.
std::vector<uint32_t> shortest_loop_through(const Surface& s, const EdgeGraph& g, uint32_t root,
                                            const std::vector<std::vector<uint32_t>>& loops, double* length, double* cost) {
  const TreeCotree tc = tree_cotree(s, g, {root}, loops);
  if (tc.leftover.empty()) return {};
  const uint32_t e = tc.leftover.front();
  const uint32_t h = g.edge_halfedge[e];
  std::vector<uint32_t> pu, pv;  // vertex paths to the root
  for (uint32_t v = s.from(h);; v = other_end(s, g, tc.pred[v], v)) {
    pu.push_back(v);
    if (tc.pred[v] == kNone) break;
  }
  for (uint32_t v = s.to(h);; v = other_end(s, g, tc.pred[v], v)) {
    pv.push_back(v);
    if (tc.pred[v] == kNone) break;
  }
  // Trim the common suffix (shared path near the root) down to the branching vertex.
  while (pu.size() > 1 && pv.size() > 1 && pu[pu.size() - 2] == pv[pv.size() - 2]) pu.pop_back(), pv.pop_back();
  std::vector<uint32_t> edges{e};
  for (const auto* path : {&pu, &pv})
    for (size_t i = 0; i + 1 < path->size(); ++i) edges.push_back(tc.pred[(*path)[i]]);
  *length = *cost = 0;
  for (uint32_t pe : edges) *length += g.length[pe], *cost += g.cost[pe];
  return edges;
}

}  // namespace

Surface remove_handles(const Surface& component, std::vector<double>* loop_lengths, const std::vector<char>& seams) {
  Surface cur = with_identity_parents(component);
  const long genus = topology_of(cur).genus();
  for (long k = 0; k < genus; ++k) {
    const EdgeGraph g(cur, seams);
    const auto loops = boundary_loops(cur);
    // Candidate roots: a global tree-cotree from one vertex; the leftover edges sit on the handles, so
    // roots at their ends find each handle's own short loop. The shortest loop over a few candidates wins.
    const TreeCotree global = tree_cotree(cur, g, {cur.triangles[0][0]}, loops);
    if (global.leftover.empty()) break;
    std::vector<uint32_t> roots;
    for (uint32_t e : global.leftover) {
      for (uint32_t v : {cur.from(g.edge_halfedge[e]), cur.to(g.edge_halfedge[e])})
        if (std::find(roots.begin(), roots.end(), v) == roots.end()) roots.push_back(v);
      if (roots.size() >= 8) break;
    }
    // Roots in parallel; the winner is the cheapest loop, ties to the earlier root (deterministic).
    std::vector<std::vector<uint32_t>> candidate(roots.size());
    std::vector<double> candidate_len(roots.size(), 0.0), candidate_cost(roots.size(), std::numeric_limits<double>::infinity());
    tbb::parallel_for(size_t(0), roots.size(), [&](size_t i) {
      double len = 0, cost = 0;
      candidate[i] = shortest_loop_through(cur, g, roots[i], loops, &len, &cost);
      if (!candidate[i].empty()) candidate_len[i] = len, candidate_cost[i] = cost;
    });
    std::vector<uint32_t> best;
    double best_len = 0, best_cost = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < roots.size(); ++i)
      if (candidate_cost[i] < best_cost) best_cost = candidate_cost[i], best_len = candidate_len[i], best = std::move(candidate[i]);
    if (best.empty()) break;
    // Cut along the loop and cap the new boundary with centroid fans (scaffolding).
    std::vector<char> on_loop(g.num_edges(), 0);
    for (uint32_t e : best) on_loop[e] = 1;
    uint32_t groups = 0;
    const auto corner_vertex = group_corners(cur, [&](uint32_t h) { return !on_loop[g.halfedge_edge[h]]; }, &groups);
    Surface cut = regroup(cur, corner_vertex, groups);
    for (uint32_t& p : cut.vertex_parent) p = cur.vertex_parent[p];
    for (uint32_t& p : cut.face_parent) p = cur.face_parent[p];
    if (topology_of(cut).genus() >= topology_of(cur).genus())
      fail_internal("remove_handles: cutting a loop of {} edges did not lower the genus", best.size());
    cur = std::move(cut);
    if (loop_lengths) loop_lengths->push_back(best_len);
  }
  return cur;
}

}  // namespace tightex
