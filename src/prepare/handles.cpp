#include "prepare/handles.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"
#include "cut/cut_along_edges.hpp"
#include "cut/graph.hpp"

namespace tightex {

namespace {

struct Loop {
  std::vector<uint32_t> edges;
  std::vector<uint32_t> vertices;                         // in order along the loop
  double length = 0;                                      // 3D
  double cost = std::numeric_limits<double>::infinity();  // g.cost: what the search minimises
};

/// The shortest generator loop through `root`: the leftover edge with the smallest loop cost, with
/// the two tree paths trimmed where they share a prefix (so the loop is a simple cycle). Searches only
/// within `radius` of the root (see tree_cotree): a loop costing up to twice that is found. Empty
/// (cost infinite) when there is none: the surface has genus 0, or every loop through root costs more.
/// `scratch` and `tc`: tree_cotree's arrays, reused from root to root.
Loop shortest_loop_through(const Surface& s, const EdgeGraph& g, uint32_t root, const std::vector<std::vector<uint32_t>>& loops,
                           double radius, TreeCotreeScratch& scratch, TreeCotree& tc) {
  tree_cotree(s, g, {root}, loops, radius, scratch, tc);
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
/// Candidate roots taken from the ends of the global tree-cotree's leftover edges.
constexpr size_t kCandidateRoots = 8;

/// A fixed pseudo-random order (splitmix64).
uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The search for the cheapest non-separating loop of one surface: the best loop so far, and the
/// radius a root's search needs to find a cheaper one.
class LoopSearch {
 public:
  LoopSearch(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops)
      : s_(s), g_(g), loops_(loops), longest_edge_(g.cost.empty() ? 0.0 : *std::max_element(g.cost.begin(), g.cost.end())) {
    keep_fixed_arrays(s, g, loops, scratch_);
  }

  /// Searches the loops through `root`; keeps the cheapest (ties to the earlier root). A loop through
  /// the root cheaper than the best reaches no vertex farther than half the best's cost plus half its
  /// leftover edge: that is the radius searched.
  void try_root(uint32_t root) {
    Loop l = shortest_loop_through(s_, g_, root, loops_, (best_.cost + longest_edge_) / 2, scratch_, tree_);
    if (l.cost < best_.cost * (1 - 1e-12)) best_ = std::move(l);
  }
  const Loop& best() const { return best_; }

 private:
  const Surface& s_;
  const EdgeGraph& g_;
  const std::vector<std::vector<uint32_t>>& loops_;
  const double longest_edge_;
  Loop best_;
  TreeCotreeScratch scratch_;
  TreeCotree tree_;
};

/// Candidate roots: a global tree-cotree from one vertex; its leftover edges sit on the handles, so
/// roots at their ends find each handle's own short loop. Empty where there is no handle.
std::vector<uint32_t> candidate_roots(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops) {
  const TreeCotree global = tree_cotree(s, g, {s.triangles[0][0]}, loops);
  std::vector<uint32_t> roots;
  for (uint32_t e : global.leftover) {
    for (uint32_t v : {s.from(g.edge_halfedge[e]), s.to(g.edge_halfedge[e])})
      if (std::find(roots.begin(), roots.end(), v) == roots.end()) roots.push_back(v);
    if (roots.size() >= kCandidateRoots) break;
  }
  return roots;
}

/// Tightening, two moves per round while the loop gets cheaper. (1) The shortest non-separating loop
/// through a vertex of the best loop is at most as long as it, and shorter where the loop found from a
/// root off the handle bends towards that root: roots spread along the loop. (2) A loop may sit on a
/// slope (a tube narrowing towards a waist), where every loop through its own vertices is no shorter:
/// roots spread over the band within a quarter of its cost on either side let it slide down, a band's
/// width per round.
void tighten(const Surface& s, const EdgeGraph& g, LoopSearch& search) {
  for (int round = 0; round < kTightenRounds; ++round) {
    const Loop& best = search.best();
    std::vector<uint32_t> tries;
    const std::vector<uint32_t>& along = best.vertices;
    for (size_t i = 0, n = std::min(kTightenRoots, along.size()); i < n; ++i) tries.push_back(along[i * along.size() / n]);
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    const double band = best.cost / 4;
    dijkstra(g, s.num_vertices(), along, g.cost, dist, pred, band);
    std::vector<uint32_t> outer;
    for (uint32_t v = 0; v < s.num_vertices(); ++v)
      if (dist[v] > band / 2 && dist[v] <= band) outer.push_back(v);
    // A fixed pseudo-random pick (vertex ids follow the mesh's own order, which may put one side of the
    // loop at every other index): both sides, spread around.
    std::sort(outer.begin(), outer.end(), [](uint32_t a, uint32_t b) { return splitmix64(a) < splitmix64(b); });
    for (size_t i = 0; i < std::min(kTightenRoots, outer.size()); ++i) tries.push_back(outer[i]);
    const double before = best.cost;
    for (uint32_t r : tries) search.try_root(r);
    if (!(search.best().cost < before * (1 - kTightenGain))) break;
  }
}

}  // namespace

Surface remove_handles(const Surface& component, std::vector<double>* loop_lengths, std::span<const char> seams) {
  Surface cur = with_identity_parents(component);
  const long genus = topology_of(cur).genus();
  for (long k = 0; k < genus; ++k) {
    const EdgeGraph g(cur, seams);
    const auto loops = boundary_loops(cur);
    const std::vector<uint32_t> roots = candidate_roots(cur, g, loops);
    if (roots.empty()) break;
    LoopSearch search(cur, g, loops);
    for (uint32_t r : roots) search.try_root(r);
    if (search.best().edges.empty()) break;
    tighten(cur, g, search);
    // Cut along the loop: its two sides become boundary loops.
    const Loop& best = search.best();
    std::vector<char> on_loop(g.num_edges(), 0);
    for (uint32_t e : best.edges) on_loop[e] = 1;
    Surface cut = cut_along_edges(cur, g, on_loop);
    for (uint32_t& p : cut.vertex_parent) p = cur.vertex_parent[p];
    for (uint32_t& p : cut.face_parent) p = cur.face_parent[p];
    if (topology_of(cut).genus() >= topology_of(cur).genus())
      fail_internal("remove_handles: cutting a loop of {} edges did not lower the genus", best.edges.size());
    if (loop_lengths) loop_lengths->push_back(best.length);
    cur = std::move(cut);
  }
  inherit_input_map(cur, component);
  return cur;
}

}  // namespace tightex
