#include "prepare/handles.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
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

/// The loop of leftover edge e of tree-cotree tc: e and the two tree paths from its ends, trimmed where
/// they share a prefix (so the loop is a simple cycle).
Loop loop_of(const Surface& s, const EdgeGraph& g, const TreeCotree& tc, uint32_t e) {
  Loop loop;
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

/// The shortest generator loop through `root`: the leftover edge with the smallest loop cost
/// (loop_of). Searches only within `radius` of the root (see tree_cotree): a loop costing up to twice
/// that is found. Empty (cost infinite) when there is none: the surface has genus 0, or every loop
/// through root costs more. `scratch` and `tc`: tree_cotree's arrays, reused from root to root.
Loop shortest_loop_through(const Surface& s, const EdgeGraph& g, uint32_t root, const std::vector<std::vector<uint32_t>>& loops,
                           double radius, TreeCotreeScratch& scratch, TreeCotree& tc) {
  tree_cotree(s, g, {root}, loops, radius, scratch, tc);
  if (tc.leftover.empty()) return Loop{};
  return loop_of(s, g, tc, tc.leftover.front());
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

/// Roots searched at once (at most; fewer on fewer cores): each holds tree_cotree's arrays, the size of
/// the surface.
constexpr size_t kParallelRoots = 4;

/// The search for the cheapest non-separating loop of one surface: the best loop so far, and the
/// radius a root's search needs to find a cheaper one.
class LoopSearch {
 public:
  LoopSearch(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops)
      : s_(s),
        g_(g),
        loops_(loops),
        longest_edge_(g.cost.empty() ? 0.0 : *std::max_element(g.cost.begin(), g.cost.end())),
        workers_(std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1, kParallelRoots)) {
    keep_fixed_arrays(s, g, loops, workers_[0].scratch);
    for (size_t k = 1; k < workers_.size(); ++k) workers_[k].scratch = workers_[0].scratch;
  }

  /// The first root, while no loop is known: its whole surface would be searched. Where its loop is
  /// cheaper than `bound` (the cost of some loop of the surface), a search within the radius that bound
  /// gives finds it; only where it is not is the whole surface searched.
  void try_first_root(uint32_t root, double bound) {
    Worker& w = workers_[0];
    Loop l = shortest_loop_through(s_, g_, root, loops_, (bound + longest_edge_) / 2, w.scratch, w.tree);
    if (!(l.cost < bound)) l = shortest_loop_through(s_, g_, root, loops_, std::numeric_limits<double>::infinity(), w.scratch, w.tree);
    if (improves(l)) best_ = std::move(l);
  }

  /// Searches the loops through each root in turn and keeps the cheapest (ties to the earlier root).
  /// A loop through a root cheaper than the best reaches no vertex farther than half the best's cost
  /// plus half its leftover edge: that is the radius searched. Several roots are searched at once with
  /// the radius the best so far gives; their loops are taken in order up to the first cheaper one, and
  /// the roots after it are searched again with the new, smaller radius. So every root is searched
  /// with the radius it would get one at a time, and the loop kept is the one that would be.
  void try_roots(const std::vector<uint32_t>& roots) {
    std::vector<Loop> found(workers_.size());
    for (size_t i = 0; i < roots.size();) {
      // Before any loop is known the radius is unbounded: one root then, not a batch of whole-surface searches.
      const size_t n = std::isfinite(best_.cost) ? std::min(workers_.size(), roots.size() - i) : 1;
      const double radius = (best_.cost + longest_edge_) / 2;
      tbb::parallel_for(size_t(0), n, [&](size_t k) {
        found[k] = shortest_loop_through(s_, g_, roots[i + k], loops_, radius, workers_[k].scratch, workers_[k].tree);
      });
      size_t k = 0;
      while (k < n && !improves(found[k])) ++k;
      if (k < n) best_ = std::move(found[k]);
      i += std::min(k + 1, n);
    }
  }
  const Loop& best() const { return best_; }

 private:
  /// Whether `l` replaces the best loop: cheaper beyond rounding (a tie keeps the earlier root's).
  bool improves(const Loop& l) const { return l.cost < best_.cost * (1 - 1e-12); }

  struct Worker {
    TreeCotreeScratch scratch;
    TreeCotree tree;
  };
  const Surface& s_;
  const EdgeGraph& g_;
  const std::vector<std::vector<uint32_t>>& loops_;
  const double longest_edge_;
  Loop best_;
  std::vector<Worker> workers_;
};

/// Candidate roots: a global tree-cotree from one vertex; its leftover edges sit on the handles, so
/// roots at their ends find each handle's own short loop. Empty where there is no handle. `bound`: the
/// cost of the global tree's shortest loop (infinite where there is none), a loop the search's first
/// root can be measured against.
std::vector<uint32_t> candidate_roots(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops,
                                      double& bound) {
  const TreeCotree global = tree_cotree(s, g, {s.triangles[0][0]}, loops);
  std::vector<uint32_t> roots;
  bound = global.leftover.empty() ? std::numeric_limits<double>::infinity() : loop_of(s, g, global, global.leftover.front()).cost;
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
    search.try_roots(tries);
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
    double bound = 0;
    const std::vector<uint32_t> roots = candidate_roots(cur, g, loops, bound);
    if (roots.empty()) break;
    LoopSearch search(cur, g, loops);
    search.try_first_root(roots.front(), bound);
    search.try_roots(std::vector<uint32_t>(roots.begin() + 1, roots.end()));
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
