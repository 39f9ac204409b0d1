#include "cut/cut_graph.hpp"

#include <algorithm>
#include <array>

#include "core/error.hpp"

namespace tightex {

namespace {

/// The paper's single seam on a closed genus-0 surface: the shortest path by cost between two far-apart
/// vertices (double sweep), so it follows the input's texture seams where that costs little. A one-edge
/// path opens nothing (both ends stay whole): it is extended by one edge.
std::vector<char> shortest_path_cut(const Surface& s, const EdgeGraph& g) {
  std::vector<char> cut_edge(g.num_edges(), 0);
  std::vector<double> dist;
  std::vector<uint32_t> pred;
  uint32_t a = 0;
  const uint32_t b = double_sweep(s, g, &a, dist, pred);
  dijkstra(g, s.num_vertices(), {a}, g.cost, dist, pred);  // the path between them prefers the input's seams
  size_t path_edges = 0;
  for (uint32_t v = b; pred[v] != kNone; v = other_end(s, g, pred[v], v)) cut_edge[pred[v]] = 1, ++path_edges;
  if (path_edges < 2) {
    for (uint32_t i = g.offset[b]; i < g.offset[b + 1]; ++i)
      if (g.neighbor[i] != a) {
        cut_edge[g.via_edge[i]] = 1;
        break;
      }
  }
  return cut_edge;
}

/// Tree-cotree's marked edges: each generator loop (leftover edge + tree paths to the root) and each
/// hole's tree path to the root. The shortest-path tree is rooted on the longest boundary loop
/// (boundary edges cost nothing, so every hole acts as one point and the tree reaches each hole through
/// its nearest vertex), or, on a closed surface of higher genus, near the middle of a diameter so that
/// the generator loops are short.
std::vector<char> mark_generators(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops,
                                  const std::vector<char>& is_boundary_edge) {
  std::vector<uint32_t> sources;
  size_t root_loop = kNone;
  if (!loops.empty()) {
    root_loop = longest_loop(s, loops);
    for (uint32_t h : loops[root_loop]) sources.push_back(s.from(h));
  } else {
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    uint32_t a = 0;
    uint32_t v = double_sweep(s, g, &a, dist, pred);
    const double half = dist[v] / 2;
    while (pred[v] != kNone && dist[v] > half) v = other_end(s, g, pred[v], v);
    sources.push_back(v);
  }
  const TreeCotree tc = tree_cotree(s, g, sources, loops);
  std::vector<char> marked(g.num_edges(), 0);
  auto mark_path = [&](uint32_t v) {
    for (; tc.pred[v] != kNone; v = other_end(s, g, tc.pred[v], v)) marked[tc.pred[v]] = 1;
  };
  for (uint32_t e : tc.leftover) {
    if (is_boundary_edge[e]) continue;
    marked[e] = 1;
    mark_path(s.from(g.edge_halfedge[e]));
    mark_path(s.to(g.edge_halfedge[e]));
  }
  for (size_t i = 0; i < loops.size(); ++i) {
    if (i == root_loop) continue;
    uint32_t best = s.from(loops[i][0]);
    for (uint32_t h : loops[i])
      if (tc.dist[s.from(h)] < tc.dist[best]) best = s.from(h);
    mark_path(best);
  }
  return marked;
}

/// Breadth-first dual spanning tree from face 0 that crosses no `forbidden` edge: `crossed` gets its
/// edges. Returns whether it reaches every face.
bool dual_spanning_tree(const Surface& s, const EdgeGraph& g, const std::vector<char>& forbidden, std::vector<char>& crossed) {
  const uint32_t nf = uint32_t(s.num_faces());
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
}

/// Real-first dual spanning tree: Prim's order over edge classes (0: unmarked between real faces,
/// 1: marked between real faces, 2: unmarked beside a cap, 3: marked beside a cap), from a real face.
/// Every real face is then reached through real faces before any cap is entered; a marked path crossed
/// there is cut through the cap instead. `crossed` gets its edges.
void real_first_dual_tree(const Surface& s, const EdgeGraph& g, const std::vector<char>& marked, std::vector<char>& crossed) {
  const uint32_t nf = uint32_t(s.num_faces());
  crossed.assign(g.num_edges(), 0);
  std::vector<char> seen(nf, 0);
  uint32_t start = 0;
  while (start + 1 < nf && s.face_parent[start] == kNone) ++start;
  std::array<std::vector<uint32_t>, 4> bucket;  // halfedges leaving the tree
  auto visit = [&](uint32_t t) {
    seen[t] = 1;
    for (int k = 0; k < 3; ++k) {
      const uint32_t h = 3 * t + k, o = s.opposite[h];
      if (o == kNone || seen[o / 3]) continue;
      const bool real = s.face_parent[t] != kNone && s.face_parent[o / 3] != kNone;
      bucket[size_t((real ? 0 : 2) + (marked[g.halfedge_edge[h]] ? 1 : 0))].push_back(h);
    }
  };
  visit(start);
  for (;;) {
    size_t b = 0;
    while (b < 4 && bucket[b].empty()) ++b;
    if (b == 4) break;
    const uint32_t h = bucket[b].back();
    bucket[b].pop_back();
    const uint32_t o = s.opposite[h];
    if (seen[o / 3]) continue;
    crossed[g.halfedge_edge[h]] = 1;
    visit(o / 3);
  }
}

/// The cut graph of a dual spanning tree: the interior edges it does not cross, pruned of dangling
/// branches (a vertex left with one cut or boundary edge drops that edge, repeatedly).
void prune_to_cut_graph(const Surface& s, const EdgeGraph& g, const std::vector<char>& crossed, const std::vector<char>& is_boundary_edge,
                        std::vector<char>& cut_edge) {
  const size_t nv = s.num_vertices();
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

/// Tree-cotree cut graph: a dual spanning tree of the faces crossing only unmarked interior edges (any
/// dual spanning tree where the marks leave none); its complement, pruned, is always a valid cut to a
/// disk whatever the marks. Rebuilt real-first where the caps would be the only link between real faces.
CutGraph tree_cotree_cut(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops) {
  CutGraph cut{std::vector<char>(g.num_edges(), 0), "cut-graph"};
  std::vector<char> is_boundary_edge(g.num_edges(), 0);
  for (uint32_t e = 0; e < g.num_edges(); ++e) is_boundary_edge[e] = s.opposite[g.edge_halfedge[e]] == kNone;
  const std::vector<char> marked = mark_generators(s, g, loops, is_boundary_edge);
  std::vector<char> crossed;
  if (!dual_spanning_tree(s, g, marked, crossed)) {
    std::vector<char> none(g.num_edges(), 0);
    dual_spanning_tree(s, g, none, crossed);
  }
  prune_to_cut_graph(s, g, crossed, is_boundary_edge, cut.cut_edge);
  const bool has_caps = std::find(s.face_parent.begin(), s.face_parent.end(), kNone) != s.face_parent.end();
  if (has_caps && real_faces_apart(s, g, cut.cut_edge)) {
    real_first_dual_tree(s, g, marked, crossed);
    prune_to_cut_graph(s, g, crossed, is_boundary_edge, cut.cut_edge);
    cut.method += " (real-first)";
  }
  return cut;
}

}  // namespace

bool real_faces_apart(const Surface& s, const EdgeGraph& g, const std::vector<char>& cut_edge) {
  detail::UnionFind uf(s.num_faces());
  for (uint32_t h = 0; h < s.opposite.size(); ++h)
    if (const uint32_t o = s.opposite[h];
        o != kNone && !cut_edge[g.halfedge_edge[h]] && s.face_parent[h / 3] != kNone && s.face_parent[o / 3] != kNone)
      uf.unite(h / 3, o / 3);
  size_t groups = 0;
  for (uint32_t f = 0; f < s.num_faces(); ++f) groups += s.face_parent[f] != kNone && uf.find(f) == f;
  return groups > 1;
}

size_t longest_loop(const Surface& s, const std::vector<std::vector<uint32_t>>& loops) {
  std::vector<double> loop_length(loops.size(), 0.0);
  for (size_t i = 0; i < loops.size(); ++i)
    for (uint32_t h : loops[i]) loop_length[i] += s.edge_length(h);
  return size_t(std::max_element(loop_length.begin(), loop_length.end()) - loop_length.begin());
}

CutGraph compute_cut_graph(const Surface& s, const EdgeGraph& g) {
  const auto loops = boundary_loops(s);
  const Topology topo = topology_of(s);
  if (loops.size() == 1 && topo.genus() == 0) return {std::vector<char>(g.num_edges(), 0), "disk"};
  if (loops.empty() && topo.genus() == 0) return {shortest_path_cut(s, g), "path"};
  return tree_cotree_cut(s, g, loops);
}

}  // namespace tightex
