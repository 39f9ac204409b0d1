#include "prepare/loop_classes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace tightex {

namespace {

/// The dual graph of a surface with its holes capped: a node per face, then one per boundary loop.
struct DualNodes {
  const Surface& s;
  const std::vector<std::vector<uint32_t>>& loops;
  std::vector<uint32_t> cap_of;  // per boundary halfedge, its loop's node

  DualNodes(const Surface& surface, const std::vector<std::vector<uint32_t>>& boundary) : s(surface), loops(boundary) {
    cap_of.assign(s.opposite.size(), kNone);
    for (size_t i = 0; i < loops.size(); ++i)
      for (uint32_t h : loops[i]) cap_of[h] = uint32_t(s.num_faces() + i);
  }
  size_t size() const { return s.num_faces() + loops.size(); }
  /// Calls f(h, across) for each halfedge h on node x's boundary, `across` the node on h's other side.
  template <typename F>
  void for_each_side(uint32_t x, F f) const {
    const uint32_t nf = uint32_t(s.num_faces());
    if (x >= nf) {
      for (uint32_t h : loops[x - nf]) f(h, h / 3);
      return;
    }
    for (uint32_t h = 3 * x; h < 3 * x + 3; ++h) f(h, s.opposite[h] == kNone ? cap_of[h] : s.opposite[h] / 3);
  }
};

/// A spanning tree of the dual graph over the edges not `in_tree`: per node its edge towards node 0
/// (kNone at node 0), and the nodes in the order reached (parents first).
void dual_tree(const DualNodes& dual, const EdgeGraph& g, const std::vector<char>& in_tree, std::vector<uint32_t>& parent_edge,
               std::vector<uint32_t>& order) {
  parent_edge.assign(dual.size(), kNone);
  std::vector<char> seen(dual.size(), 0);
  order.assign(1, 0);
  seen[0] = 1;
  for (size_t k = 0; k < order.size(); ++k)
    dual.for_each_side(order[k], [&](uint32_t h, uint32_t y) {
      const uint32_t e = g.halfedge_edge[h];
      if (in_tree[e] || seen[y]) return;
      seen[y] = 1;
      parent_edge[y] = e;
      order.push_back(y);
    });
}

}  // namespace

LoopClasses loop_classes(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops,
                         const std::vector<uint32_t>& tree_pred) {
  std::vector<char> in_tree(g.num_edges(), 0);
  size_t tree_edges = 0;
  for (uint32_t e : tree_pred)
    if (e != kNone) in_tree[e] = 1, ++tree_edges;
  const DualNodes dual(s, loops);
  std::vector<uint32_t> parent_edge, order;
  dual_tree(dual, g, in_tree, parent_edge, order);
  size_t vertices = 0;  // those on an edge: a vertex no triangle uses is in no loop
  for (uint32_t v = 0; v < s.num_vertices(); ++v) vertices += g.offset[v + 1] > g.offset[v];
  if (tree_edges + 1 != vertices || order.size() != dual.size())
    fail_internal("loop_classes: the trees do not span the surface ({} of {} vertices, {} of {} faces and caps)", tree_edges + 1, vertices,
                  order.size(), dual.size());
  std::vector<char> in_dual(g.num_edges(), 0);
  for (uint32_t e : parent_edge)
    if (e != kNone) in_dual[e] = 1;
  std::vector<uint32_t> leftover;
  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (!in_tree[e] && !in_dual[e]) leftover.push_back(e);
  LoopClasses c;
  c.words = (leftover.size() + 63) / 64;
  c.bits.assign(g.num_edges() * c.words, 0);
  for (size_t i = 0; i < leftover.size(); ++i) c.bits[leftover[i] * c.words + i / 64] |= uint64_t(1) << (i % 64);
  // Leaf first: a node's parent edge takes the xor of its other edges, so the node's own xor is 0.
  for (size_t k = order.size(); k-- > 1;) {
    const uint32_t x = order[k], up = parent_edge[x];
    uint64_t* target = c.bits.data() + size_t(up) * c.words;
    dual.for_each_side(x, [&](uint32_t h, uint32_t) {
      const uint32_t e = g.halfedge_edge[h];
      if (e == up) return;
      for (size_t w = 0; w < c.words; ++w) target[w] ^= c.bits[size_t(e) * c.words + w];
    });
  }
  return c;
}

RootLoopSearch::RootLoopSearch(const Surface& s, const EdgeGraph& g, const LoopClasses& classes, std::span<const double> weight)
    : s_(s),
      g_(g),
      classes_(classes),
      weight_(weight),
      dist_(s.num_vertices(), std::numeric_limits<double>::infinity()),
      pred_(s.num_vertices(), kNone),
      settled_(s.num_vertices(), 0),
      vertex_class_(std::make_unique_for_overwrite<uint64_t[]>(s.num_vertices() * classes.words)) {}

void RootLoopSearch::reset() {
  for (uint32_t v : reached_) dist_[v] = std::numeric_limits<double>::infinity(), pred_[v] = kNone, settled_[v] = 0;
  reached_.clear();
  heap_.clear();
  closing_edge_ = kNone;
  loop_cost_ = std::numeric_limits<double>::infinity();
}

void RootLoopSearch::settle(uint32_t v) {
  settled_[v] = 1;
  const size_t W = classes_.words;
  uint64_t* mine = vertex_class_.get() + size_t(v) * W;
  const uint32_t up = pred_[v];
  if (up == kNone) {
    std::fill(mine, mine + W, 0);
  } else {
    const uint64_t* parent = vertex_class_.get() + size_t(other_end(s_, g_, up, v)) * W;
    const auto edge = classes_.of_edge(up);
    for (size_t w = 0; w < W; ++w) mine[w] = parent[w] ^ edge[w];
  }
}

void RootLoopSearch::try_closing(uint32_t v, uint32_t w, uint32_t e) {
  if (e == pred_[v] || s_.opposite[g_.edge_halfedge[e]] == kNone) return;
  const double cost = dist_[v] + dist_[w] + g_.cost[e];
  if (cost > loop_cost_ || (cost == loop_cost_ && closing_edge_ != kNone && e < closing_edge_)) return;
  const size_t W = classes_.words;
  const uint64_t *mine = vertex_class_.get() + size_t(v) * W, *theirs = vertex_class_.get() + size_t(w) * W;
  const auto edge = classes_.of_edge(e);
  bool separating = true;
  for (size_t k = 0; k < W && separating; ++k) separating = (mine[k] ^ theirs[k] ^ edge[k]) == 0;
  if (!separating) loop_cost_ = cost, closing_edge_ = e;
}

uint32_t RootLoopSearch::search(uint32_t root, double radius) {
  reset();
  using Item = std::pair<double, uint32_t>;
  auto push = [&](double d, uint32_t v) {
    heap_.push_back({d, v});
    std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
  };
  dist_[root] = 0;
  reached_.push_back(root);
  push(0.0, root);
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), std::greater<>());
    const Item top = heap_.back();
    heap_.pop_back();
    const auto [d, v] = top;
    if (settled_[v] || d > dist_[v]) continue;
    // A loop closed at v or later costs at least 2 d (dist[v] <= dist[w] + cost of (v, w)).
    if (d > radius || 2 * d > loop_cost_) break;
    settle(v);
    for (uint32_t i = g_.offset[v]; i < g_.offset[v + 1]; ++i) {
      const uint32_t w = g_.neighbor[i], e = g_.via_edge[i];
      if (settled_[w]) {
        try_closing(v, w, e);
        continue;
      }
      const double nd = d + weight_[e];
      if (!(nd < dist_[w])) continue;
      if (std::isinf(dist_[w])) reached_.push_back(w);
      dist_[w] = nd;
      pred_[w] = e;
      push(nd, w);
    }
  }
  return closing_edge_;
}

}  // namespace tightex
