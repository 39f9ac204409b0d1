#include <algorithm>
#include <numbers>
#include <numeric>
#include <queue>

#include "core/error.hpp"
#include "topology/topology.hpp"

namespace tightex {

namespace {

/// Undirected edges of a manifold surface with vertex adjacency in CSR form.
struct EdgeGraph {
  std::vector<uint32_t> edge_halfedge;  // edge -> a halfedge of it (the one with the smaller id)
  std::vector<uint32_t> halfedge_edge;  // halfedge -> edge
  std::vector<double> length;
  std::vector<uint32_t> offset, neighbor, via_edge;  // CSR: vertex -> (neighbor, edge)

  explicit EdgeGraph(const Surface& s) {
    const uint32_t nh = uint32_t(s.opposite.size());
    halfedge_edge.assign(nh, kNone);
    for (uint32_t h = 0; h < nh; ++h) {
      const uint32_t o = s.opposite[h];
      if (o != kNone && o < h) continue;
      const uint32_t e = uint32_t(edge_halfedge.size());
      edge_halfedge.push_back(h);
      length.push_back(s.edge_length(h));
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
void dijkstra(const EdgeGraph& g, size_t nv, const std::vector<uint32_t>& sources,
              const std::vector<double>& weight, std::vector<double>& dist, std::vector<uint32_t>& pred_edge) {
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

uint32_t other_end(const Surface& s, const EdgeGraph& g, uint32_t e, uint32_t v) {
  const uint32_t h = g.edge_halfedge[e];
  return s.from(h) == v ? s.to(h) : s.from(h);
}

uint32_t farthest(const std::vector<double>& dist) {
  uint32_t best = 0;
  for (uint32_t v = 0; v < dist.size(); ++v)
    if (std::isfinite(dist[v]) && dist[v] > dist[best]) best = v;
  return best;
}

}  // namespace

Disk cut_to_disk(const Surface& component, HoleMode holes, CutStats* stats) {
  CutStats st;
  st.before = topology_of(component);
  auto loops = boundary_loops(component);

  // Holes: with kFill every loop but the longest is capped with scaffolding.
  Surface s;
  if (holes == HoleMode::kFill && loops.size() > 1) {
    std::vector<double> loop_length(loops.size(), 0.0);
    for (size_t i = 0; i < loops.size(); ++i)
      for (uint32_t h : loops[i]) loop_length[i] += component.edge_length(h);
    const size_t keep = size_t(std::max_element(loop_length.begin(), loop_length.end()) - loop_length.begin());
    std::vector<std::vector<uint32_t>> fill;
    for (size_t i = 0; i < loops.size(); ++i)
      if (i != keep) fill.push_back(loops[i]);
    st.holes_filled = fill.size();
    s = fill_holes(component, fill);
    loops = boundary_loops(s);
  } else {
    s = component;
    s.vertex_parent.resize(s.num_vertices());
    std::iota(s.vertex_parent.begin(), s.vertex_parent.end(), 0u);
    s.face_parent.resize(s.num_faces());
    std::iota(s.face_parent.begin(), s.face_parent.end(), 0u);
  }
  st.holes_cut = loops.empty() ? 0 : loops.size() - 1;
  const Topology topo = topology_of(s);
  const EdgeGraph g(s);
  const size_t nv = s.num_vertices();
  const uint32_t nh = uint32_t(s.opposite.size());
  std::vector<char> cut_edge(g.num_edges(), 0);

  if (loops.size() == 1 && topo.genus() == 0) {
    // A disk is used as is, unless it is deep: a tube closed at one end (a vase, a scanned object
    // resting on the ground) maps its far end into a tiny spot at the square's centre. When the farthest
    // vertex from the boundary lies deeper than a flat round disk of the same perimeter allows
    // (perimeter / 2 pi) by kDeepDisk, the disk is slit from the boundary to that vertex.
    constexpr double kDeepDisk = 1.5;
    double perimeter = 0;
    std::vector<uint32_t> sources;
    for (uint32_t h : loops[0]) perimeter += s.edge_length(h), sources.push_back(s.from(h));
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    dijkstra(g, nv, sources, g.length, dist, pred);
    const uint32_t far = farthest(dist);
    if (dist[far] > kDeepDisk * perimeter / (2 * std::numbers::pi)) {
      st.method = "disk+slit";
      for (uint32_t v = far; pred[v] != kNone; v = other_end(s, g, pred[v], v)) cut_edge[pred[v]] = 1;
    } else {
      st.method = "disk";
    }
  } else if (loops.empty() && topo.genus() == 0) {
    // The paper's single seam: shortest path between two far-apart vertices (double sweep).
    st.method = "path";
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    dijkstra(g, nv, {s.triangles[0][0]}, g.length, dist, pred);
    const uint32_t a = farthest(dist);
    dijkstra(g, nv, {a}, g.length, dist, pred);
    uint32_t b = farthest(dist);
    size_t path_edges = 0;
    for (uint32_t v = b; pred[v] != kNone; v = other_end(s, g, pred[v], v)) cut_edge[pred[v]] = 1, ++path_edges;
    if (path_edges < 2) {
      // A one-edge cut opens nothing (both ends stay whole): extend it by one edge at b.
      for (uint32_t i = g.offset[b]; i < g.offset[b + 1]; ++i)
        if (g.neighbor[i] != a) {
          cut_edge[g.via_edge[i]] = 1;
          break;
        }
    }
  } else {
    st.method = "cut-graph";
    // Shortest-path tree T. Boundary edges cost nothing, so every hole acts as one point and T reaches
    // each hole through its nearest vertex.
    std::vector<double> weight = g.length;
    std::vector<char> is_boundary_edge(g.num_edges(), 0);
    for (uint32_t e = 0; e < g.num_edges(); ++e)
      if (s.opposite[g.edge_halfedge[e]] == kNone) is_boundary_edge[e] = 1, weight[e] = 0;
    std::vector<uint32_t> sources;
    size_t root_loop = kNone;
    if (!loops.empty()) {
      std::vector<double> loop_length(loops.size(), 0.0);
      for (size_t i = 0; i < loops.size(); ++i)
        for (uint32_t h : loops[i]) loop_length[i] += s.edge_length(h);
      root_loop = size_t(std::max_element(loop_length.begin(), loop_length.end()) - loop_length.begin());
      for (uint32_t h : loops[root_loop]) sources.push_back(s.from(h));
    } else {
      // Closed surface of higher genus: root near the middle of a diameter, so generator loops are short.
      std::vector<double> dist;
      std::vector<uint32_t> pred;
      dijkstra(g, nv, {s.triangles[0][0]}, g.length, dist, pred);
      const uint32_t a = farthest(dist);
      dijkstra(g, nv, {a}, g.length, dist, pred);
      uint32_t v = farthest(dist);
      const double half = dist[v] / 2;
      while (pred[v] != kNone && dist[v] > half) v = other_end(s, g, pred[v], v);
      sources.push_back(v);
    }
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    dijkstra(g, nv, sources, weight, dist, pred);
    std::vector<char> in_tree(g.num_edges(), 0);
    for (uint32_t v = 0; v < nv; ++v)
      if (pred[v] != kNone) in_tree[pred[v]] = 1;

    // Greedy dual tree over the edges not in T (faces + one node per hole), keeping the edges whose
    // loops are longest, so the leftover edges close the shortest generator loops.
    const uint32_t nf = uint32_t(s.num_faces());
    std::vector<uint32_t> hole_node(nh, kNone);
    for (size_t i = 0; i < loops.size(); ++i)
      for (uint32_t h : loops[i]) hole_node[h] = nf + uint32_t(i);
    std::vector<uint32_t> order;
    for (uint32_t e = 0; e < g.num_edges(); ++e)
      if (!in_tree[e]) order.push_back(e);
    auto loop_len = [&](uint32_t e) {
      const uint32_t h = g.edge_halfedge[e];
      return dist[s.from(h)] + dist[s.to(h)] + g.length[e];
    };
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return loop_len(a) > loop_len(b); });
    detail::UnionFind dual(nf + loops.size());
    std::vector<uint32_t> leftover;
    for (uint32_t e : order) {
      const uint32_t h = g.edge_halfedge[e], o = s.opposite[h];
      const uint32_t a = h / 3, b = o == kNone ? hole_node[h] : o / 3;
      if (dual.find(a) != dual.find(b)) {
        dual.unite(a, b);
      } else {
        leftover.push_back(e);
      }
    }
    // Marked edges: each generator loop (leftover edge + tree paths to the root) and each hole's tree
    // path to the root.
    std::vector<char> marked(g.num_edges(), 0);
    auto mark_path = [&](uint32_t v) {
      for (; pred[v] != kNone; v = other_end(s, g, pred[v], v)) marked[pred[v]] = 1;
    };
    for (uint32_t e : leftover) {
      if (is_boundary_edge[e]) continue;
      marked[e] = 1;
      mark_path(s.from(g.edge_halfedge[e]));
      mark_path(s.to(g.edge_halfedge[e]));
    }
    for (size_t i = 0; i < loops.size(); ++i) {
      if (i == root_loop) continue;
      uint32_t best = s.from(loops[i][0]);
      for (uint32_t h : loops[i])
        if (dist[s.from(h)] < dist[best]) best = s.from(h);
      mark_path(best);
    }
    // Dual spanning tree of the real faces crossing only unmarked interior edges; its complement,
    // pruned of dangling branches, is the cut graph. Always a valid cut to a disk, whatever `marked`.
    auto dual_tree = [&](const std::vector<char>& forbidden, std::vector<char>& crossed) {
      crossed.assign(g.num_edges(), 0);
      std::vector<char> seen(nf, 0);
      std::vector<uint32_t> queue{0};
      seen[0] = 1;
      for (size_t qi = 0; qi < queue.size(); ++qi) {
        const uint32_t t = queue[qi];
        for (int k = 0; k < 3; ++k) {
          const uint32_t h = 3 * t + k, o = s.opposite[h];
          if (o == kNone || seen[o / 3] || forbidden[g.halfedge_edge[h]]) continue;
          seen[o / 3] = 1;
          crossed[g.halfedge_edge[h]] = 1;
          queue.push_back(o / 3);
        }
      }
      return queue.size() == nf;
    };
    std::vector<char> crossed;
    if (!dual_tree(marked, crossed)) {
      std::vector<char> none(g.num_edges(), 0);
      dual_tree(none, crossed);
    }
    for (uint32_t e = 0; e < g.num_edges(); ++e) cut_edge[e] = !crossed[e] && !is_boundary_edge[e];
    std::vector<uint32_t> degree(nv, 0);
    for (uint32_t e = 0; e < g.num_edges(); ++e)
      if (cut_edge[e] || is_boundary_edge[e]) degree[s.from(g.edge_halfedge[e])]++, degree[s.to(g.edge_halfedge[e])]++;
    std::vector<uint32_t> stack;
    for (uint32_t v = 0; v < nv; ++v)
      if (degree[v] == 1) stack.push_back(v);
    while (!stack.empty()) {
      const uint32_t v = stack.back();
      stack.pop_back();
      if (degree[v] != 1) continue;
      for (uint32_t i = g.offset[v]; i < g.offset[v + 1]; ++i) {
        const uint32_t e = g.via_edge[i];
        if (!cut_edge[e]) continue;
        cut_edge[e] = 0;
        degree[v]--;
        const uint32_t w = g.neighbor[i];
        if (--degree[w] == 1) stack.push_back(w);
        break;
      }
    }
  }

  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (cut_edge[e]) st.cut_edges++, st.cut_length += g.length[e];
  uint32_t groups = 0;
  const auto corner_vertex = group_corners(s, [&](uint32_t h) { return !cut_edge[g.halfedge_edge[h]]; }, &groups);
  Disk disk;
  disk.mesh = regroup(s, corner_vertex, groups);
  // regroup's maps point into `s`; compose with s's maps so they point into the component.
  for (uint32_t& p : disk.mesh.vertex_parent) p = s.vertex_parent[p];
  for (uint32_t& p : disk.mesh.face_parent) p = s.face_parent[p];
  const Topology dt = topology_of(disk.mesh);
  const auto disk_loops = boundary_loops(disk.mesh);
  if (disk_loops.size() != 1 || dt.euler() != 1)
    fail_internal("cut_to_disk: result has {} boundary loops and Euler characteristic {} (expected a disk)",
                  disk_loops.size(), dt.euler());
  for (uint32_t h : disk_loops[0]) disk.boundary.push_back(disk.mesh.from(h));
  if (stats) *stats = st;
  return disk;
}

}  // namespace tightex
