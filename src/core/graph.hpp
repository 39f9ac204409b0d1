// Edge graph of a manifold surface and the shortest-path machinery the cut (§4.2) and the handle
// removal (§4.1) share: an edge is numbered by its smaller halfedge, in halfedge order, so per-edge
// flags (a cut graph) are tied to the surface they were computed on.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <span>
#include <vector>

#include "core/surface.hpp"

namespace tightex {

/// Shortest paths (handle loops, hole connections, the cut graph) pay this fraction of an edge's length
/// on an edge where the input already has a texture seam: where there is a choice of nearly equal
/// paths, the new seam lies where the eye already accepts a discontinuity. See find_texture_seams.
/// Chosen by measurement: docs/decisions.md.
constexpr double kSeamCost = 0.95;

/// Undirected edges of a manifold surface with vertex adjacency in CSR form.
/// `seams`: per halfedge of the surface that s.face_parent maps into (the component), 1 on an input
/// texture seam (find_texture_seams); empty: none. Scaffolding edges are never seams.
struct EdgeGraph {
  std::vector<uint32_t> edge_halfedge;               // edge -> a halfedge of it (the one with the smaller id)
  std::vector<uint32_t> halfedge_edge;               // halfedge -> edge
  std::vector<double> length;                        // 3D length
  std::vector<double> cost;                          // what a shortest path pays: length, times kSeamCost on a seam
  std::vector<char> on_seam;                         // per edge: an input texture seam
  std::vector<uint32_t> offset, neighbor, via_edge;  // CSR: vertex -> (neighbor, edge)

  explicit EdgeGraph(const Surface& s, std::span<const char> seams = {}) {
    const uint32_t nh = uint32_t(s.opposite.size());
    halfedge_edge.assign(nh, kNone);
    auto seam_at = [&](uint32_t h) {
      const uint32_t f = s.face_parent.empty() ? kNone : s.face_parent[h / 3];
      return f != kNone && seams[3 * f + h % 3];
    };
    for (uint32_t h = 0; h < nh; ++h) {
      const uint32_t o = s.opposite[h];
      if (o != kNone && o < h) continue;
      const uint32_t e = uint32_t(edge_halfedge.size());
      edge_halfedge.push_back(h);
      length.push_back(s.edge_length(h));
      on_seam.push_back(!seams.empty() && o != kNone && seam_at(h) && seam_at(o));
      cost.push_back(on_seam.back() ? kSeamCost * length.back() : length.back());
      halfedge_edge[h] = e;
      if (o != kNone) halfedge_edge[o] = e;
    }
    offset.assign(s.num_vertices() + 1, 0);
    for (uint32_t h : edge_halfedge) {
      offset[s.from(h) + 1]++;
      offset[s.to(h) + 1]++;
    }
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    neighbor.resize(offset.back());
    via_edge.resize(offset.back());
    std::vector<uint32_t> fill(offset.begin(), offset.end() - 1);
    for (uint32_t e = 0; e < edge_halfedge.size(); ++e) {
      const uint32_t h = edge_halfedge[e], a = s.from(h), b = s.to(h);
      neighbor[fill[a]] = b, via_edge[fill[a]++] = e;
      neighbor[fill[b]] = a, via_edge[fill[b]++] = e;
    }
  }
  size_t num_edges() const { return edge_halfedge.size(); }
};

/// Dijkstra from a set of sources; `weight(e)` gives each edge's length. pred_edge is kNone at sources.
/// `limit`: vertices farther than this are left unreached (dist infinite, pred_edge kNone), and the
/// search stops there, so a small limit costs only the ball it covers.
inline void dijkstra(const EdgeGraph& g, size_t nv, const std::vector<uint32_t>& sources, const std::vector<double>& weight,
                     std::vector<double>& dist, std::vector<uint32_t>& pred_edge, double limit = std::numeric_limits<double>::infinity()) {
  dist.assign(nv, std::numeric_limits<double>::infinity());
  pred_edge.assign(nv, kNone);
  using Item = std::pair<double, uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (uint32_t s : sources) {
    dist[s] = 0;
    queue.push({0.0, s});
  }
  while (!queue.empty()) {
    auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    if (d > limit) {  // every vertex still queued is farther: leave them all unreached
      for (; !queue.empty(); queue.pop()) {
        const uint32_t w = queue.top().second;
        if (dist[w] > limit) dist[w] = std::numeric_limits<double>::infinity(), pred_edge[w] = kNone;
      }
      dist[v] = std::numeric_limits<double>::infinity(), pred_edge[v] = kNone;
      break;
    }
    for (uint32_t i = g.offset[v]; i < g.offset[v + 1]; ++i) {
      const uint32_t w = g.neighbor[i], e = g.via_edge[i];
      const double nd = d + weight[e];
      if (nd < dist[w]) {
        dist[w] = nd;
        pred_edge[w] = e;
        queue.push({nd, w});
      }
    }
  }
}

/// A breadth-first spanning tree of the vertices `root` reaches: per vertex its tree edge towards the
/// root (kNone at the root and where not reached).
inline std::vector<uint32_t> breadth_first_tree(const Surface& s, const EdgeGraph& g, uint32_t root) {
  std::vector<uint32_t> pred(s.num_vertices(), kNone), queue{root};
  std::vector<char> seen(s.num_vertices(), 0);
  seen[root] = 1;
  for (size_t k = 0; k < queue.size(); ++k)
    for (uint32_t i = g.offset[queue[k]]; i < g.offset[queue[k] + 1]; ++i)
      if (!seen[g.neighbor[i]]) seen[g.neighbor[i]] = 1, pred[g.neighbor[i]] = g.via_edge[i], queue.push_back(g.neighbor[i]);
  return pred;
}

/// The end of edge e that is not v.
inline uint32_t other_end(const Surface& s, const EdgeGraph& g, uint32_t e, uint32_t v) {
  const uint32_t h = g.edge_halfedge[e];
  return s.from(h) == v ? s.to(h) : s.from(h);
}

/// The vertex with the largest finite distance (0 if none is reached).
inline uint32_t farthest(const std::vector<double>& dist) {
  uint32_t best = 0;
  for (uint32_t v = 0; v < dist.size(); ++v)
    if (std::isfinite(dist[v]) && dist[v] > dist[best]) best = v;
  return best;
}

/// Double sweep: the vertex farthest from an arbitrary start is one end `a` of an approximate
/// diameter; the sweep from `a` gives dist/pred, whose farthest vertex is the other end (returned).
/// Distances are 3D lengths: the ends are far apart on the surface, whatever the seams.
inline uint32_t double_sweep(const Surface& s, const EdgeGraph& g, uint32_t* a, std::vector<double>& dist, std::vector<uint32_t>& pred) {
  dijkstra(g, s.num_vertices(), {s.triangles[0][0]}, g.length, dist, pred);
  *a = farthest(dist);
  dijkstra(g, s.num_vertices(), {*a}, g.length, dist, pred);
  return farthest(dist);
}

/// g.cost with every boundary edge free: a shortest path may run along a hole at no cost, so every
/// hole acts as one point (the tree-cotree's and the handle search's distances).
inline std::vector<double> costs_with_free_boundary(const Surface& s, const EdgeGraph& g) {
  std::vector<double> weight(g.cost.begin(), g.cost.end());
  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (s.opposite[g.edge_halfedge[e]] == kNone) weight[e] = 0;
  return weight;
}

/// Tree-cotree (Eppstein; greedy form of Erickson & Whittlesey 2005): a shortest-path tree T (g.cost) from
/// `sources` (boundary edges cost nothing, so every hole acts as one point), then a dual spanning tree
/// over the edges not in T (faces plus one node per boundary loop) that keeps the edges whose loops are
/// longest. The edges left over close the generator loops: 2g of them on a genus-g surface, each loop
/// (leftover edge + tree paths to the root) non-separating, the shortest ones first.
struct TreeCotree {
  std::vector<double> dist;
  std::vector<uint32_t> pred;      // tree edge towards the root, per vertex
  std::vector<uint32_t> leftover;  // interior edges closing generator loops, shortest loop first
  /// The cost (g.cost) of the loop closed by edge e.
  double loop_length(const Surface& s, const EdgeGraph& g, uint32_t e) const {
    const uint32_t h = g.edge_halfedge[e];
    return dist[s.from(h)] + dist[s.to(h)] + g.cost[e];
  }
};

inline TreeCotree tree_cotree(const Surface& s, const EdgeGraph& g, const std::vector<uint32_t>& sources,
                              const std::vector<std::vector<uint32_t>>& loops) {
  TreeCotree tc;
  dijkstra(g, s.num_vertices(), sources, costs_with_free_boundary(s, g), tc.dist, tc.pred);
  std::vector<char> in_tree(g.num_edges(), 0);
  for (uint32_t v = 0; v < s.num_vertices(); ++v)
    if (tc.pred[v] != kNone) in_tree[tc.pred[v]] = 1;
  const uint32_t nf = uint32_t(s.num_faces());
  std::vector<uint32_t> hole_node(s.opposite.size(), kNone);  // per boundary halfedge, its hole's node
  for (size_t i = 0; i < loops.size(); ++i)
    for (uint32_t h : loops[i]) hole_node[h] = nf + uint32_t(i);
  detail::UnionFind dual(nf + loops.size());
  auto join = [&](uint32_t e) {  // false: its two sides are joined already
    const uint32_t h = g.edge_halfedge[e], o = s.opposite[h];
    const uint32_t a = dual.find(h / 3), b = dual.find(o == kNone ? hole_node[h] : o / 3);
    if (a == b) return false;
    dual.unite(a, b);
    return true;
  };
  // Longest loop first (an edge no source reaches: infinitely long); ties by edge id, so the result
  // does not depend on the sort's stability.
  std::vector<std::pair<double, uint32_t>> order;
  for (uint32_t e = 0; e < g.num_edges(); ++e) {
    if (in_tree[e]) continue;
    const double len = tc.loop_length(s, g, e);
    if (std::isfinite(len))
      order.push_back({-len, e});
    else
      join(e);
  }
  std::sort(order.begin(), order.end());
  for (auto [neg_len, e] : order)
    if (!join(e) && s.opposite[g.edge_halfedge[e]] != kNone) tc.leftover.push_back(e);
  std::reverse(tc.leftover.begin(), tc.leftover.end());
  return tc;
}

}  // namespace tightex
