// The surface as the topology stages see it: positions and triangles only, plus the maps back to the
// previous stage, and a halfedge adjacency built once.
//
// Halfedge h = 3*t + k runs from triangles[t][k] to triangles[t][(k+1)%3]; opposite[h] is the
// halfedge of the neighbouring triangle across that edge, or kNone on the boundary.
#pragma once
#include <vector>

#include "core/mesh.hpp"

namespace tightex {

struct Surface {
  std::vector<Vec3> positions;
  std::vector<Tri> triangles;
  std::vector<uint32_t> vertex_parent;  // vertex -> vertex of the stage before (kNone: added)
  std::vector<uint32_t> face_parent;    // triangle -> triangle of the stage before (kNone: scaffolding)
  std::vector<uint32_t> opposite;       // per halfedge, see above
  // The map back to the input model, composed once by each stage that makes a new mesh
  // (inherit_input_map), so that nothing downstream walks the face_parent chain: per face the input
  // triangle it is part of (kNone: scaffolding), per corner 3*f+k the corner of that input triangle it
  // is (prepare_surface's winding fix folded in). Empty for a surface not made from an input model.
  std::vector<uint32_t> input_face;
  std::vector<uint8_t> input_corner;

  size_t num_vertices() const { return positions.size(); }
  size_t num_faces() const { return triangles.size(); }
  uint32_t from(uint32_t h) const { return triangles[h / 3][h % 3]; }
  uint32_t to(uint32_t h) const { return triangles[h / 3][(h % 3 + 1) % 3]; }
  static uint32_t next(uint32_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static uint32_t prev(uint32_t h) { return h - h % 3 + (h % 3 + 2) % 3; }
  double edge_length(uint32_t h) const { return (positions[to(h)] - positions[from(h)]).norm(); }
};

/// Halfedges sorted by their undirected edge (key = min vertex << 32 | max vertex): the halfedges of
/// one edge are neighbours in the result.
std::vector<std::pair<uint64_t, uint32_t>> halfedges_by_edge(const Surface& s);

/// Sets `child`'s input_face / input_corner from `parent`'s through child.face_parent (kNone:
/// scaffolding). Every stage keeps each face's corners in its parent face's order. Leaves them empty
/// where `parent` has none.
void inherit_input_map(Surface& child, const Surface& parent);

/// A copy whose vertex_parent / face_parent map each element to itself (the start of a stage's maps).
Surface with_identity_parents(const Surface& s);

/// Builds `opposite` for a mesh whose vertices are already manifold. Requires: every undirected edge
/// is used by at most two triangles, in opposite directions. Throws InternalError otherwise.
void build_opposite(Surface& s);

/// Union-find over triangle corners: corners joined across every halfedge pair (h, opposite[h]) for
/// which keep(h) is true become one vertex. Returns, per corner (3*t+k), its new vertex id; new ids are
/// numbered in order of first corner. This is how tightex slices non-manifold vertices and how it cuts
/// along a cut graph: a vertex splits into one copy per fan of corners that stays connected.
template <typename Keep>
std::vector<uint32_t> group_corners(const Surface& s, Keep keep, uint32_t* num_groups);

/// Applies a corner grouping: new positions (copied from the old vertex), triangles, vertex_parent
/// pointing at the old vertex, face_parent = identity, and rebuilt `opposite`.
Surface regroup(const Surface& s, const std::vector<uint32_t>& corner_vertex, uint32_t num_groups);

struct Topology {
  size_t vertices = 0, edges = 0, faces = 0, boundary_loops = 0;
  long euler() const { return long(vertices) - long(edges) + long(faces); }
  /// genus of the closed surface obtained by capping every boundary loop
  long genus() const { return (2 - euler() - long(boundary_loops)) / 2; }
};
/// Counts of a manifold surface (only vertices used by a triangle are counted).
Topology topology_of(const Surface& s);

/// Boundary loops as sequences of halfedges, each loop in the triangles' orientation.
std::vector<std::vector<uint32_t>> boundary_loops(const Surface& s);

/// Connected components through `opposite`: per triangle its component id; returns the count.
uint32_t face_components(const Surface& s, std::vector<uint32_t>& component);

// ---- implementation of the template ----
namespace detail {
struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) {
    for (size_t i = 0; i < n; ++i) parent[i] = uint32_t(i);
  }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[a < b ? b : a] = a < b ? a : b;  // smaller id wins: deterministic
  }
};
}  // namespace detail

template <typename Keep>
std::vector<uint32_t> group_corners(const Surface& s, Keep keep, uint32_t* num_groups) {
  const size_t nc = 3 * s.num_faces();
  detail::UnionFind uf(nc);
  for (uint32_t h = 0; h < nc; ++h) {
    const uint32_t o = s.opposite[h];
    if (o == kNone || o < h || !keep(h)) continue;
    // h: a->b in its triangle, o: b->a. Corner of h's triangle at a is h itself (corner k = from);
    // corner at b is next(h). In o's triangle, corner at b is o, corner at a is next(o).
    uf.unite(h, Surface::next(o));
    uf.unite(Surface::next(h), o);
  }
  std::vector<uint32_t> id(nc, kNone), corner_vertex(nc);
  uint32_t count = 0;
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t r = uf.find(c);
    if (id[r] == kNone) id[r] = count++;
    corner_vertex[c] = id[r];
  }
  *num_groups = count;
  return corner_vertex;
}

}  // namespace tightex
