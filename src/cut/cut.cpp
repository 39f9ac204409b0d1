#include "cut/cut.hpp"

#include <algorithm>
#include <array>
#include <numbers>
#include <numeric>
#include <queue>

#include "core/error.hpp"
#include "cut/graph.hpp"
#include "prepare/holes.hpp"

namespace tightex {


namespace {

/// Whether the real faces (face_parent != kNone; caps are scaffolding) fall apart into more than one
/// group through the interior edges that are not cut.
bool real_faces_apart(const Surface& s, const std::vector<char>& cut_edge, const EdgeGraph& g) {
  detail::UnionFind uf(s.num_faces());
  for (uint32_t h = 0; h < s.opposite.size(); ++h)
    if (const uint32_t o = s.opposite[h]; o != kNone && !cut_edge[g.halfedge_edge[h]] && s.face_parent[h / 3] != kNone &&
                                          s.face_parent[o / 3] != kNone)
      uf.unite(h / 3, o / 3);
  size_t groups = 0;
  for (uint32_t f = 0; f < s.num_faces(); ++f) groups += s.face_parent[f] != kNone && uf.find(f) == f;
  return groups > 1;
}

}  // namespace

Disk cut_to_disk(const Surface& component, HoleMode holes, CutStats* stats, const std::vector<uint32_t>& slit_to,
                 const Denoised* denoised, bool plain, const std::vector<char>& seams, double fill_budget, bool cap_kept) {
  CutStats st;
  st.before = topology_of(component);
  st.fill_budget = holes == HoleMode::kFill && !plain ? fill_budget : 0.0;
  // Handles first: a genus-0 surface (with its holes) comes back, the handle loops capped.
  Surface base;
  if (plain) {
    // Safety net: no handle search, no caps, no slits; the cut graph below works for any genus.
    base = with_identity_parents(component);
  } else if (denoised) {
    base = denoised->surface;
    st.handle_loops = denoised->handle_loops;
  } else if (st.before.genus() > 0) {
    base = remove_handles(component, &st.handle_loops, seams);
  } else {
    base = with_identity_parents(component);
  }
  auto loops = boundary_loops(base);
  std::vector<double> loop_length(loops.size(), 0.0);
  for (size_t i = 0; i < loops.size(); ++i)
    for (uint32_t h : loops[i]) loop_length[i] += base.edge_length(h);
  const size_t keep = size_t(std::max_element(loop_length.begin(), loop_length.end()) - loop_length.begin());
  if (!loops.empty()) st.longest_loop_edges = loops[keep].size();

  // Holes: the longest loop stays the disk boundary; with kFill the others are capped smallest first
  // within the area budget.
  Surface s;
  double component_area = 0;
  for (const Tri& f : component.triangles)
    component_area += triangle_area(component.positions[f[0]], component.positions[f[1]], component.positions[f[2]]);
  if (!plain && holes == HoleMode::kFill && (loops.size() > 1 || (cap_kept && loops.size() == 1))) {
    std::vector<double> cap_area(loops.size(), 0.0);
    for (size_t i = 0; i < loops.size(); ++i) {
      Vec3 c = Vec3::Zero();
      for (uint32_t h : loops[i]) c += base.positions[base.from(h)];
      c /= double(loops[i].size());
      for (uint32_t h : loops[i]) cap_area[i] += triangle_area(c, base.positions[base.from(h)], base.positions[base.to(h)]);
    }
    std::vector<size_t> order(loops.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cap_area[a] < cap_area[b]; });
    std::vector<std::vector<uint32_t>> fill;
    double used = 0;
    for (size_t i : order) {
      if ((i == keep && !cap_kept) || used + cap_area[i] > fill_budget * component_area) continue;
      used += cap_area[i];
      fill.push_back(loops[i]);
      st.longest_loop_capped = st.longest_loop_capped || i == keep;
    }
    st.holes_filled = fill.size();
    st.filled_area = component_area > 0 ? used / component_area : 0.0;
    s = fill_holes(base, fill);
    for (uint32_t& p : s.vertex_parent)
      if (p != kNone) p = base.vertex_parent[p];
    for (uint32_t& p : s.face_parent)
      if (p != kNone) p = base.face_parent[p];
    loops = boundary_loops(s);
  } else {
    s = std::move(base);
  }
  st.holes_cut = loops.empty() ? 0 : loops.size() - 1;
  const Topology topo = topology_of(s);
  const EdgeGraph g(s, plain ? std::vector<char>{} : seams);
  const size_t nv = s.num_vertices();
  std::vector<char> cut_edge(g.num_edges(), 0);

  if (loops.size() == 1 && topo.genus() == 0) {
    st.method = "disk";
  } else if (loops.empty() && topo.genus() == 0) {
    // The paper's single seam: shortest path between two far-apart vertices (double sweep); the
    // shortest by cost, so it follows the input's texture seams where that costs little.
    st.method = "path";
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    uint32_t a = 0;
    const uint32_t b = double_sweep(s, g, &a, dist, pred);
    dijkstra(g, nv, {a}, g.cost, dist, pred);  // the path between them prefers the input's seams
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
    std::vector<char> is_boundary_edge(g.num_edges(), 0);
    for (uint32_t e = 0; e < g.num_edges(); ++e) is_boundary_edge[e] = s.opposite[g.edge_halfedge[e]] == kNone;
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
      uint32_t a = 0;
      uint32_t v = double_sweep(s, g, &a, dist, pred);
      const double half = dist[v] / 2;
      while (pred[v] != kNone && dist[v] > half) v = other_end(s, g, pred[v], v);
      sources.push_back(v);
    }
    const TreeCotree tc = tree_cotree(s, g, sources, loops);
    const std::vector<double>& dist = tc.dist;
    const std::vector<uint32_t>& pred = tc.pred;
    const std::vector<uint32_t>& leftover = tc.leftover;
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
    const uint32_t nf = uint32_t(s.num_faces());
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
    // Real-first dual tree, used when the plain one leaves the real faces joined only through caps:
    // Prim's order over edge classes (0: unmarked between real faces, 1: marked between real faces,
    // 2: unmarked beside a cap, 3: marked beside a cap), from a real face. Every real face is then
    // reached through real faces before any cap is entered; a marked path crossed there is cut
    // through the cap instead.
    auto real_first_tree = [&](std::vector<char>& crossed) {
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
    };
    // The cut graph: the complement of the tree, pruned of dangling branches.
    auto cut_from = [&](const std::vector<char>& crossed) {
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
    };
    std::vector<char> crossed;
    if (!dual_tree(marked, crossed)) {
      std::vector<char> none(g.num_edges(), 0);
      dual_tree(none, crossed);
    }
    cut_from(crossed);
    if (st.holes_filled > 0 && real_faces_apart(s, cut_edge, g)) {
      real_first_tree(crossed);
      cut_from(crossed);
      st.method += " (real-first)";
    }
  }

  // A deep disk maps its far end into a tiny spot (a tube closed at one end: a vase, an object resting
  // on the ground; harmonic maps crowd exponentially with depth, down to below double precision).
  // While the farthest vertex from the disk's boundary (the surface boundary and both sides of every
  // cut) lies deeper than a flat round disk of that perimeter allows (perimeter / 2 pi) by kDeepDisk,
  // the disk is slit from its boundary to that vertex. Each slit lengthens the perimeter, so this ends;
  // kMaxSlits bounds it all the same.
  {
    constexpr double kDeepDisk = 1.5;
    const int kMaxSlits = plain ? 0 : 16;
    for (int slit = 0; slit < kMaxSlits; ++slit) {
      double perimeter = 0;
      std::vector<uint32_t> sources;
      for (uint32_t e = 0; e < g.num_edges(); ++e) {
        const bool boundary = s.opposite[g.edge_halfedge[e]] == kNone;
        if (!boundary && !cut_edge[e]) continue;
        perimeter += (boundary ? 1.0 : 2.0) * g.length[e];
        sources.push_back(s.from(g.edge_halfedge[e]));
        sources.push_back(s.to(g.edge_halfedge[e]));
      }
      if (sources.empty()) break;
      std::vector<double> dist;
      std::vector<uint32_t> pred;
      dijkstra(g, nv, sources, g.length, dist, pred);
      uint32_t far = farthest(dist);
      if (size_t(slit) < slit_to.size()) {
        far = kNone;  // requested slits first
        for (uint32_t v = 0; v < nv && far == kNone; ++v)
          if (s.vertex_parent[v] == slit_to[size_t(slit)]) far = v;
        if (far == kNone || !std::isfinite(dist[far])) continue;
      } else if (!(dist[far] > kDeepDisk * perimeter / (2 * std::numbers::pi))) {
        break;
      }
      st.slits++;
      for (uint32_t v = far; pred[v] != kNone; v = other_end(s, g, pred[v], v)) cut_edge[pred[v]] = 1;
    }
    if (st.slits) st.method += "+slit";
    if (plain) st.method += " (plain fallback)";
  }
  // One chart per component: the real faces must hang together without the caps. A cap can be the only
  // link between a few faces and the rest (a handle's capped side on one hand, the cut graph on the
  // other: the generated plate of genus 3 with a 5% budget, 4 of its 608 faces); the output would then
  // hold them as a chart of their own. Then cut again without caps (every face real: one chart).
  if (holes == HoleMode::kFill && st.holes_filled > 0 && real_faces_apart(s, cut_edge, g)) {
    Disk open = cut_to_disk(component, HoleMode::kCut, stats, slit_to, denoised, plain, seams, fill_budget);
    if (stats) stats->method += " (caps would split the chart: holes opened)";
    return open;
  }
  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (cut_edge[e]) st.cut_edges++, st.cut_length += g.length[e];
  uint32_t groups = 0;
  const auto corner_vertex = group_corners(s, [&](uint32_t h) { return !cut_edge[g.halfedge_edge[h]]; }, &groups);
  Disk disk;
  disk.mesh = regroup(s, corner_vertex, groups);
  // regroup's maps point into `s`; compose with s's maps so they point into the component.
  for (uint32_t& p : disk.mesh.vertex_parent) p = s.vertex_parent[p];
  for (uint32_t& p : disk.mesh.face_parent) p = s.face_parent[p];  // kNone stays kNone: scaffolding
  inherit_input_map(disk.mesh, component);
  const Topology dt = topology_of(disk.mesh);
  const auto disk_loops = boundary_loops(disk.mesh);
  if (disk_loops.size() != 1 || dt.euler() != 1)
    fail_internal("cut_to_disk: result has {} boundary loops and Euler characteristic {} (expected a disk)",
                  disk_loops.size(), dt.euler());
  for (uint32_t h : disk_loops[0]) disk.boundary.push_back(disk.mesh.from(h));
  // The seam this component gets in the output (METRICS.md): its edges whose two triangles end up apart
  // (handle loops, hole connections, the cut graph, slits), each counted once from both sides, and the
  // part of it that lies on the input's texture seams.
  for (uint32_t h = 0; h < disk.mesh.opposite.size(); ++h) {
    const uint32_t f = disk.mesh.face_parent[h / 3], o = disk.mesh.opposite[h];
    if (f == kNone || (o != kNone && disk.mesh.face_parent[o / 3] != kNone)) continue;
    const uint32_t ch = 3 * f + h % 3;
    if (component.opposite[ch] == kNone) continue;  // the surface's own boundary
    const double half = 0.5 * component.edge_length(ch);
    st.seam_length += half;
    if (!seams.empty() && seams[ch]) st.seam_on_input_seams += half;
  }
  if (stats) *stats = st;
  return disk;
}

}  // namespace tightex
