#include "core/surface.hpp"

#include <algorithm>
#include <numeric>

#include "core/error.hpp"

namespace tightex {

std::vector<std::pair<uint64_t, uint32_t>> halfedges_by_edge(const Surface& s) {
  const size_t nh = 3 * s.num_faces();
  std::vector<std::pair<uint64_t, uint32_t>> keyed(nh);
  for (uint32_t h = 0; h < nh; ++h) {
    const uint64_t a = s.from(h), b = s.to(h);
    keyed[h] = {std::min(a, b) << 32 | std::max(a, b), h};
  }
  std::sort(keyed.begin(), keyed.end());
  return keyed;
}

void inherit_input_map(Surface& child, const Surface& parent) {
  child.input_face.clear();
  child.input_corner.clear();
  if (parent.input_face.empty()) return;
  child.input_face.resize(child.num_faces());
  child.input_corner.resize(3 * child.num_faces());
  for (size_t f = 0; f < child.num_faces(); ++f) {
    const uint32_t p = child.face_parent[f];
    child.input_face[f] = p == kNone ? kNone : parent.input_face[p];
    for (size_t k = 0; k < 3; ++k) child.input_corner[3 * f + k] = p == kNone ? uint8_t(k) : parent.input_corner[3 * size_t(p) + k];
  }
}

Surface with_identity_parents(const Surface& s) {
  Surface r = s;
  r.vertex_parent.resize(r.num_vertices());
  std::iota(r.vertex_parent.begin(), r.vertex_parent.end(), 0u);
  r.face_parent.resize(r.num_faces());
  std::iota(r.face_parent.begin(), r.face_parent.end(), 0u);
  return r;
}

void build_opposite(Surface& s) {
  const size_t nh = 3 * s.num_faces();
  s.opposite.assign(nh, kNone);
  const auto keyed = halfedges_by_edge(s);
  for (size_t i = 0; i < nh;) {
    size_t j = i + 1;
    while (j < nh && keyed[j].first == keyed[i].first) ++j;
    if (j - i == 2) {
      const uint32_t h = keyed[i].second, o = keyed[i + 1].second;
      if (s.from(h) != s.to(o)) fail_internal("edge ({}, {}) is used twice in the same direction", s.from(h), s.to(h));
      s.opposite[h] = o;
      s.opposite[o] = h;
    } else if (j - i > 2) {
      fail_internal("edge ({}, {}) is used by {} triangles", s.from(keyed[i].second), s.to(keyed[i].second), j - i);
    }
    i = j;
  }
}

Surface regroup(const Surface& s, const std::vector<uint32_t>& corner_vertex, uint32_t num_groups) {
  Surface r;
  r.positions.resize(num_groups);
  r.vertex_parent.resize(num_groups);
  r.triangles.resize(s.num_faces());
  r.face_parent.resize(s.num_faces());
  for (uint32_t t = 0; t < s.num_faces(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner_vertex[3 * t + k], old = s.triangles[t][k];
      r.triangles[t][k] = v;
      r.positions[v] = s.positions[old];
      r.vertex_parent[v] = old;
    }
    r.face_parent[t] = t;
  }
  // Opposites: a pair survives exactly when both its corner pairs were joined.
  r.opposite.assign(3 * s.num_faces(), kNone);
  for (uint32_t h = 0; h < r.opposite.size(); ++h) {
    const uint32_t o = s.opposite[h];
    if (o != kNone && r.from(h) == r.to(o) && r.to(h) == r.from(o)) r.opposite[h] = o;
  }
  return r;
}

Topology topology_of(const Surface& s) {
  Topology t;
  std::vector<char> used(s.num_vertices(), 0);
  for (const Tri& f : s.triangles)
    for (uint32_t v : f) used[v] = 1;
  t.vertices = size_t(std::count(used.begin(), used.end(), 1));
  t.faces = s.num_faces();
  size_t interior_halfedges = 0, boundary_halfedges = 0;
  for (uint32_t o : s.opposite) (o == kNone ? boundary_halfedges : interior_halfedges)++;
  t.edges = interior_halfedges / 2 + boundary_halfedges;
  t.boundary_loops = boundary_loops(s).size();
  return t;
}

std::vector<std::vector<uint32_t>> boundary_loops(const Surface& s) {
  const size_t nh = s.opposite.size();
  // For a manifold surface each boundary vertex has exactly one outgoing boundary halfedge.
  std::vector<uint32_t> out_boundary(s.num_vertices(), kNone);
  for (uint32_t h = 0; h < nh; ++h)
    if (s.opposite[h] == kNone) {
      if (out_boundary[s.from(h)] != kNone) fail_internal("vertex {} appears in more than one boundary loop", s.from(h));
      out_boundary[s.from(h)] = h;
    }
  std::vector<char> seen(nh, 0);
  std::vector<std::vector<uint32_t>> loops;
  for (uint32_t h = 0; h < nh; ++h) {
    if (s.opposite[h] != kNone || seen[h]) continue;
    std::vector<uint32_t> loop;
    uint32_t cur = h;
    while (!seen[cur]) {
      seen[cur] = 1;
      loop.push_back(cur);
      cur = out_boundary[s.to(cur)];
      if (cur == kNone) fail_internal("boundary loop through vertex {} does not close", s.to(loop.back()));
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

uint32_t face_components(const Surface& s, std::vector<uint32_t>& component) {
  component.assign(s.num_faces(), kNone);
  uint32_t count = 0;
  std::vector<uint32_t> stack;
  for (uint32_t t0 = 0; t0 < s.num_faces(); ++t0) {
    if (component[t0] != kNone) continue;
    component[t0] = count;
    stack.push_back(t0);
    while (!stack.empty()) {
      const uint32_t t = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = s.opposite[3 * t + k];
        if (o != kNone && component[o / 3] == kNone) {
          component[o / 3] = count;
          stack.push_back(o / 3);
        }
      }
    }
    ++count;
  }
  return count;
}

}  // namespace tightex
