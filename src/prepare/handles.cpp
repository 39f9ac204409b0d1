// Topological denoising (paper §4.1, Fig. 5): every handle of a component is cut along a short
// non-separating loop until the component has genus 0. Each cut leaves two boundary loops, which the
// hole stage then treats like any hole (capped with scaffolding when small, opened into the seam
// otherwise). The loops become seam; no triangle is added to the output or removed from it.
#include <algorithm>
#include <limits>

#include "core/error.hpp"
#include "cut/graph.hpp"
#include "prepare/handles.hpp"

namespace tightex {

namespace {

struct Loop {
  std::vector<uint32_t> edges;
  std::vector<uint32_t> vertices;  // in order along the loop
  double length = 0;               // 3D
  double cost = std::numeric_limits<double>::infinity();  // g.cost: what the search minimises
};

/// The shortest generator loop through `root`: the leftover edge with the smallest loop cost, with
/// the two tree paths trimmed where they share a prefix (so the loop is a simple cycle). Searches only
/// within `radius` of the root (see tree_cotree): a loop costing up to twice that is found. Empty
/// (cost infinite) when there is none: the surface has genus 0, or every loop through root costs more.
Loop shortest_loop_through(const Surface& s, const EdgeGraph& g, uint32_t root, const std::vector<std::vector<uint32_t>>& loops,
                           double radius) {
  const TreeCotree tc = tree_cotree(s, g, {root}, loops, radius);
  Loop loop;
  if (tc.leftover.empty()) return loop;
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
  loop.edges.push_back(e);
  for (const auto* path : {&pu, &pv})
    for (size_t i = 0; i + 1 < path->size(); ++i) loop.edges.push_back(tc.pred[(*path)[i]]);
  loop.vertices = pu;  // u .. branching vertex, then back along pv to v
  loop.vertices.insert(loop.vertices.end(), pv.rbegin() + 1, pv.rend());
  loop.length = loop.cost = 0;
  for (uint32_t pe : loop.edges) loop.length += g.length[pe], loop.cost += g.cost[pe];
  return loop;
}

/// Loop tightening: roots per move and round, rounds at most, and the least gain for another round.
constexpr size_t kTightenRoots = 8;
constexpr int kTightenRounds = 16;
constexpr double kTightenGain = 0.002;

}  // namespace

Surface remove_handles(const Surface& component, std::vector<double>* loop_lengths, const std::vector<char>& seams) {
  Surface cur = with_identity_parents(component);
  const long genus = topology_of(cur).genus();
  for (long k = 0; k < genus; ++k) {
    const EdgeGraph g(cur, seams);
    const auto loops = boundary_loops(cur);
    // Candidate roots: a global tree-cotree from one vertex; the leftover edges sit on the handles, so
    // roots at their ends find each handle's own short loop. The cheapest loop over a few candidates
    // wins, ties to the earlier root. Once a loop is known, a root's search covers only the ball in
    // which a cheaper loop could lie (tree_cotree's radius).
    const TreeCotree global = tree_cotree(cur, g, {cur.triangles[0][0]}, loops);
    if (global.leftover.empty()) break;
    std::vector<uint32_t> roots;
    for (uint32_t e : global.leftover) {
      for (uint32_t v : {cur.from(g.edge_halfedge[e]), cur.to(g.edge_halfedge[e])})
        if (std::find(roots.begin(), roots.end(), v) == roots.end()) roots.push_back(v);
      if (roots.size() >= 8) break;
    }
    // A loop through the root cheaper than the best reaches no vertex farther than half the best's
    // cost plus half its leftover edge: that is the radius to search.
    const double longest_edge = g.cost.empty() ? 0.0 : *std::max_element(g.cost.begin(), g.cost.end());
    Loop best;
    auto try_root = [&](uint32_t root) {
      Loop l = shortest_loop_through(cur, g, root, loops, (best.cost + longest_edge) / 2);
      if (!(l.cost < best.cost * (1 - 1e-12))) return false;
      best = std::move(l);
      return true;
    };
    for (uint32_t r : roots) try_root(r);
    if (best.edges.empty()) break;
    // Tightening, two moves per round while the loop gets cheaper. (1) The shortest non-separating
    // loop through a vertex of the best loop is at most as long as it, and shorter where the loop
    // found from a root off the handle bends towards that root: roots spread along the loop. (2) A
    // loop may sit on a slope (a tube narrowing towards a waist), where every loop through its own
    // vertices is no shorter: roots spread over the band within a quarter of its cost on either side
    // let it slide down, a band's width per round.
    for (int round = 0; round < kTightenRounds; ++round) {
      std::vector<uint32_t> tries;
      const std::vector<uint32_t>& along = best.vertices;
      for (size_t i = 0, n = std::min(kTightenRoots, along.size()); i < n; ++i) tries.push_back(along[i * along.size() / n]);
      std::vector<double> dist;
      std::vector<uint32_t> pred;
      const double band = best.cost / 4;
      dijkstra(g, cur.num_vertices(), along, g.cost, dist, pred, band);
      std::vector<uint32_t> outer;
      for (uint32_t v = 0; v < cur.num_vertices(); ++v)
        if (dist[v] > band / 2 && dist[v] <= band) outer.push_back(v);
      // A fixed pseudo-random pick (vertex ids follow the mesh's own order, which may put one side of
      // the loop at every other index): both sides, spread around.
      auto hash = [](uint64_t x) {  // splitmix64
        x += 0x9e3779b97f4a7c15ull;
        x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
        x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
        return x ^ (x >> 31);
      };
      std::sort(outer.begin(), outer.end(), [&](uint32_t a, uint32_t b) { return hash(a) < hash(b); });
      for (size_t i = 0; i < std::min(kTightenRoots, outer.size()); ++i) tries.push_back(outer[i]);
      const double before = best.cost;
      for (uint32_t r : tries) try_root(r);
      if (!(best.cost < before * (1 - kTightenGain))) break;
    }
    // Cut along the loop and cap the new boundary with centroid fans (scaffolding).
    std::vector<char> on_loop(g.num_edges(), 0);
    for (uint32_t e : best.edges) on_loop[e] = 1;
    uint32_t groups = 0;
    const auto corner_vertex = group_corners(cur, [&](uint32_t h) { return !on_loop[g.halfedge_edge[h]]; }, &groups);
    Surface cut = regroup(cur, corner_vertex, groups);
    for (uint32_t& p : cut.vertex_parent) p = cur.vertex_parent[p];
    for (uint32_t& p : cut.face_parent) p = cur.face_parent[p];
    if (topology_of(cut).genus() >= topology_of(cur).genus())
      fail_internal("remove_handles: cutting a loop of {} edges did not lower the genus", best.edges.size());
    cur = std::move(cut);
    if (loop_lengths) loop_lengths->push_back(best.length);
  }
  inherit_input_map(cur, component);
  return cur;
}

}  // namespace tightex
