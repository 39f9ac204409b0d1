#include "prepare/handles.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/cut_along_edges.hpp"
#include "core/error.hpp"
#include "core/graph.hpp"
#include "core/hash.hpp"
#include "prepare/loop_classes.hpp"

namespace tightex {

namespace {

struct Loop {
  std::vector<uint32_t> edges;
  std::vector<uint32_t> vertices;                         // in order along the loop
  double length = 0;                                      // 3D
  double cost = std::numeric_limits<double>::infinity();  // g.cost: what the search minimises
};

/// The loop closed by edge e in the shortest-path tree `pred` (per vertex, its edge towards the root):
/// e and the two tree paths from its ends, trimmed where they share a prefix (so the loop is a simple
/// cycle).
Loop loop_of(const Surface& s, const EdgeGraph& g, const std::vector<uint32_t>& pred, uint32_t e) {
  Loop loop;
  const uint32_t h = g.edge_halfedge[e];
  std::vector<uint32_t> pu, pv;  // vertex paths to the root
  for (uint32_t v = s.from(h);; v = other_end(s, g, pred[v], v)) {
    pu.push_back(v);
    if (pred[v] == kNone) break;
  }
  for (uint32_t v = s.to(h);; v = other_end(s, g, pred[v], v)) {
    pv.push_back(v);
    if (pred[v] == kNone) break;
  }
  // Trim the common suffix (shared path near the root) down to the branching vertex.
  while (pu.size() > 1 && pv.size() > 1 && pu[pu.size() - 2] == pv[pv.size() - 2]) pu.pop_back(), pv.pop_back();
  loop.edges.push_back(e);
  for (const auto* path : {&pu, &pv})
    for (size_t i = 0; i + 1 < path->size(); ++i) loop.edges.push_back(pred[(*path)[i]]);
  loop.vertices = pu;  // u .. branching vertex, then back along pv to v
  loop.vertices.insert(loop.vertices.end(), pv.rbegin() + 1, pv.rend());
  loop.length = loop.cost = 0;
  for (uint32_t pe : loop.edges) loop.length += g.length[pe], loop.cost += g.cost[pe];
  return loop;
}

/// The cheapest non-separating loop through `root` that reaches no farther than `radius` (a loop
/// costing up to twice that is found); empty (cost infinite) where there is none.
Loop shortest_loop_through(const Surface& s, const EdgeGraph& g, uint32_t root, double radius, RootLoopSearch& search) {
  const uint32_t e = search.search(root, radius);
  return e == kNone ? Loop{} : loop_of(s, g, search.pred(), e);
}

/// Loop tightening: roots per move and round, rounds at most, and the least gain for another round.
constexpr size_t kTightenRoots = 8;
constexpr int kTightenRounds = 16;
constexpr double kTightenGain = 0.002;
/// Candidate roots taken from the ends of the global tree-cotree's leftover edges.
constexpr size_t kCandidateRoots = 8;

/// Roots searched at once (at most; fewer on fewer cores): each holds a RootLoopSearch's arrays, the
/// size of the surface.
constexpr size_t kParallelRoots = 4;

/// The search for the cheapest non-separating loop of one surface: the best loop so far, and the
/// radius a root's search needs to find a cheaper one.
class LoopSearch {
 public:
  /// `classes`: loop_classes of s, which decide which loops separate.
  LoopSearch(const Surface& s, const EdgeGraph& g, LoopClasses classes)
      : s_(s),
        g_(g),
        classes_(std::move(classes)),
        weight_(costs_with_free_boundary(s, g)),
        longest_edge_(g.cost.empty() ? 0.0 : *std::max_element(g.cost.begin(), g.cost.end())) {
    const size_t n = std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1, kParallelRoots);
    for (size_t k = 0; k < n; ++k) workers_.emplace_back(s, g, classes_, weight_);
  }

  /// The first root, while no loop is known: its whole surface would be searched. Where its loop is
  /// cheaper than `bound` (the cost of some loop of the surface), a search within the radius that bound
  /// gives finds it; only where it is not is the whole surface searched.
  void try_first_root(uint32_t root, double bound) {
    RootLoopSearch& w = workers_[0];
    Loop l = shortest_loop_through(s_, g_, root, (bound + longest_edge_) / 2, w);
    if (!(l.cost < bound)) l = shortest_loop_through(s_, g_, root, std::numeric_limits<double>::infinity(), w);
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
      tbb::parallel_for(size_t(0), n, [&](size_t k) { found[k] = shortest_loop_through(s_, g_, roots[i + k], radius, workers_[k]); });
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

  const Surface& s_;
  const EdgeGraph& g_;
  const LoopClasses classes_;
  const std::vector<double> weight_;  // g.cost, boundary edges free
  const double longest_edge_;
  Loop best_;
  std::vector<RootLoopSearch> workers_;
};

/// Candidate roots: the leftover edges of `global` (a tree-cotree from one vertex) sit on the handles, so
/// roots at their ends find each handle's own short loop. Empty where there is no handle. `bound`: the
/// cost of the global tree's shortest loop (infinite where there is none), a loop the search's first
/// root can be measured against.
std::vector<uint32_t> candidate_roots(const Surface& s, const EdgeGraph& g, const TreeCotree& global, double& bound) {
  std::vector<uint32_t> roots;
  bound = global.leftover.empty() ? std::numeric_limits<double>::infinity() : loop_of(s, g, global.pred, global.leftover.front()).cost;
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
  long genus = topology_of(cur).genus();
  while (genus > 0) {
    const EdgeGraph g(cur, seams);
    const auto loops = boundary_loops(cur);
    // The tree-cotree that places the roots, and the classes on a tree of their own, side by side.
    TreeCotree global;
    LoopClasses classes;
    tbb::parallel_invoke([&] { global = tree_cotree(cur, g, {cur.triangles[0][0]}, loops); },
                         [&] { classes = loop_classes(cur, g, loops, breadth_first_tree(cur, g, cur.triangles[0][0])); });
    double bound = 0;
    const std::vector<uint32_t> roots = candidate_roots(cur, g, global, bound);
    if (roots.empty()) break;
    LoopSearch search(cur, g, std::move(classes));
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
    const long cut_genus = topology_of(cut).genus();
    if (cut_genus >= genus) fail_internal("remove_handles: cutting a loop of {} edges did not lower the genus", best.edges.size());
    genus = cut_genus;
    if (loop_lengths) loop_lengths->push_back(best.length);
    cur = std::move(cut);
  }
  inherit_input_map(cur, component);
  return cur;
}

}  // namespace tightex
