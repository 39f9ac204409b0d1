#include "prepare/repair.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <unordered_map>

namespace tightex {

namespace {

struct PositionKey {
  uint64_t x, y, z;
  uint32_t source_mesh;
  bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (k.y + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2));
    h ^= (k.z + 0x85EBCA77C2B2AE63ull + (h << 6) + (h >> 2));
    h ^= (k.source_mesh + 0x165667B19E3779F9ull + (h << 6) + (h >> 2));
    return size_t(h);
  }
};
uint64_t bits(double d) {
  if (d == 0.0) d = 0.0;  // -0 and +0 are the same place
  uint64_t b;
  std::memcpy(&b, &d, sizeof b);
  return b;
}

/// Per input vertex, the source mesh of the triangles that use it (TexturedMesh::source_mesh; 0 where
/// the model has one).
std::vector<uint32_t> vertex_source_mesh(const TexturedMesh& mesh) {
  std::vector<uint32_t> group(mesh.num_vertices(), 0);
  if (mesh.source_mesh.empty()) return group;
  for (size_t t = 0; t < mesh.num_triangles(); ++t)
    for (uint32_t v : mesh.triangles[t]) group[v] = mesh.source_mesh[t];
  return group;
}

/// Step 1. Welds equal positions within each source mesh: OBJ exports split vertices along UV seams;
/// the surface is one piece. Two meshes of a glTF scene stay apart even where their geometry is the
/// same. Returns per input vertex its welded vertex; `origin` gets per welded vertex its first input vertex.
std::vector<uint32_t> weld_vertices(const TexturedMesh& mesh, std::vector<uint32_t>& origin) {
  const std::vector<uint32_t> group = vertex_source_mesh(mesh);
  std::vector<uint32_t> weld(mesh.num_vertices());
  std::unordered_map<PositionKey, uint32_t, PositionHash> index;
  index.reserve(mesh.num_vertices() * 2);
  for (uint32_t v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3& p = mesh.positions[v];
    auto [it, inserted] = index.try_emplace(PositionKey{bits(p.x()), bits(p.y()), bits(p.z()), group[v]}, uint32_t(origin.size()));
    if (inserted) origin.push_back(v);
    weld[v] = it->second;
  }
  return weld;
}

/// A triangle by its welded corners, rotated so the smallest index comes first (equal keys: the same
/// corners in the same cyclic order), and how far it was rotated.
struct RotatedTriangle {
  Tri key;
  uint32_t t;
  uint8_t rotation;
};

/// Whether triangles a and b (the same corners in the same cyclic order) have the same texture
/// coordinates at the same corners and the same material: one repeats the other exactly.
bool same_attributes(const TexturedMesh& mesh, const RotatedTriangle& a, const RotatedTriangle& b) {
  if (mesh.face_material[a.t] != mesh.face_material[b.t]) return false;
  for (int k = 0; k < 3; ++k)
    if (mesh.corner_uv[3 * size_t(a.t) + (a.rotation + k) % 3] != mesh.corner_uv[3 * size_t(b.t) + (b.rotation + k) % 3]) return false;
  return true;
}

/// Step 2. Drops zero-area triangles, sets aside exact repeats (same corners, texture coordinates and
/// material as an earlier triangle of the same source mesh: `repeats` gets (repeat, the triangle it
/// repeats)), and the triangles `left_out` marks. A triangle with the corners of an earlier one but
/// other texture coordinates or material is kept on a layer of its own (`layer`, 1 for the first such
/// copy; all 0 when there is none). The kept ones go to `s0` (welded vertices, in input order;
/// face_parent = input triangle).
void drop_degenerate_triangles(const TexturedMesh& mesh, const std::vector<uint32_t>& weld, const std::vector<char>* left_out, Surface& s0,
                               RepairStats& st, std::vector<std::pair<uint32_t, uint32_t>>& repeats, std::vector<uint32_t>& layer) {
  std::vector<RotatedTriangle> keyed;
  keyed.reserve(mesh.num_triangles());
  for (uint32_t t = 0; t < mesh.num_triangles(); ++t) {
    if (left_out != nullptr && (*left_out)[t]) continue;
    Tri f{weld[mesh.triangles[t][0]], weld[mesh.triangles[t][1]], weld[mesh.triangles[t][2]]};
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0] || triangle_area(s0.positions, f) == 0.0) {
      ++st.zero_area_triangles;
      continue;
    }
    const int m = f[0] < f[1] ? (f[0] < f[2] ? 0 : 2) : (f[1] < f[2] ? 1 : 2);
    keyed.push_back({Tri{f[m], f[(m + 1) % 3], f[(m + 2) % 3]}, t, uint8_t(m)});
  }
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.key < b.key; });
  std::vector<char> keep(mesh.num_triangles(), 0);
  for (size_t i = 0; i < keyed.size();) {
    size_t end = i + 1;
    while (end < keyed.size() && keyed[end].key == keyed[i].key) ++end;
    std::vector<size_t> kept_in_run;  // the first triangle of each set of attributes, its layer its place
    for (size_t k = i; k < end; ++k) {
      const auto same =
          std::find_if(kept_in_run.begin(), kept_in_run.end(), [&](size_t j) { return same_attributes(mesh, keyed[j], keyed[k]); });
      if (same != kept_in_run.end()) {
        ++st.repeated_triangles;
        repeats.push_back({keyed[k].t, keyed[*same].t});
        continue;
      }
      if (!kept_in_run.empty()) {
        if (layer.empty()) layer.assign(mesh.num_triangles(), 0);
        layer[keyed[k].t] = uint32_t(kept_in_run.size());
        ++st.layered_triangles;
      }
      kept_in_run.push_back(k);
      keep[keyed[k].t] = 1;
    }
    i = end;
  }
  std::sort(repeats.begin(), repeats.end());
  for (uint32_t t = 0; t < mesh.num_triangles(); ++t) {
    if (!keep[t]) continue;
    s0.triangles.push_back({weld[mesh.triangles[t][0]], weld[mesh.triangles[t][1]], weld[mesh.triangles[t][2]]});
    s0.face_parent.push_back(t);
  }
}

/// Step 2b. Gives the triangles of each layer above 0 vertices of their own, shared within the layer,
/// so that a copy of a surface with other texture coordinates becomes a surface of its own instead of
/// a stack of non-manifold edges.
void separate_layers(const std::vector<uint32_t>& layer, Surface& s0) {
  if (layer.empty()) return;
  std::unordered_map<uint64_t, uint32_t> copy;  // (layer, welded vertex) -> its copy
  for (size_t f = 0; f < s0.num_faces(); ++f) {
    const uint32_t l = layer[s0.face_parent[f]];
    if (l == 0) continue;
    for (uint32_t& v : s0.triangles[f]) {
      auto [it, inserted] = copy.try_emplace(uint64_t(l) << 32 | v, uint32_t(s0.positions.size()));
      if (inserted) {
        s0.positions.push_back(s0.positions[v]);
        s0.vertex_parent.push_back(s0.vertex_parent[v]);
      }
      v = it->second;
    }
  }
}

/// Union-find over faces with parity: each face's orientation relative to its root (1 = opposite).
struct OrientationUnionFind {
  std::vector<uint32_t> parent;
  std::vector<uint8_t> parity;  // orientation relative to the parent: 1 = opposite

  explicit OrientationUnionFind(uint32_t n) : parent(n), parity(n, 0) { std::iota(parent.begin(), parent.end(), 0u); }
  /// Root of f, and f's orientation relative to it; halves the path.
  std::pair<uint32_t, uint8_t> find(uint32_t f) {
    uint8_t p = 0;
    while (parent[f] != f) {
      const uint32_t g = parent[f];
      if (parent[g] != g) {
        parity[f] ^= parity[g];
        parent[f] = parent[g];
      }
      p ^= parity[f];
      f = parent[f];
    }
    return {f, p};
  }
  /// Relates a and b (`opposite`: their orientations disagree). Already related: a conflict stays, to
  /// be sliced by pair_halfedges.
  void join(uint32_t a, uint32_t b, uint8_t opposite) {
    const auto [ra, pa] = find(a);
    const auto [rb, pb] = find(b);
    if (ra == rb) return;
    parent[rb] = ra;
    parity[rb] = uint8_t(pa ^ pb ^ opposite);
  }
};

/// Step 3. Orients consistently: scans and merged exports often hold triangles wound the other way.
/// Over the edges that exactly two triangles share, each connected patch gets one orientation, the one
/// most of its area already has (a clean mesh is untouched). The edges whose triangles agree are taken
/// first, then the others: where a patch cannot agree (a Mobius strip) the input's own consistent parts
/// stay as they were, and what still disagrees is sliced by pair_halfedges. `keyed`:
/// halfedges_by_edge(s0). Returns per face whether its corners 1 and 2 were swapped.
std::vector<char> orient_patches(Surface& s0, const std::vector<std::pair<uint64_t, uint32_t>>& keyed, RepairStats& st) {
  const uint32_t nf = uint32_t(s0.num_faces());
  std::vector<char> reversed(nf, 0);
  OrientationUnionFind uf(nf);
  std::vector<std::pair<uint32_t, uint32_t>> agree, disagree;
  for (size_t i = 0; i < keyed.size();) {
    size_t j = i + 1;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    const uint32_t h = keyed[i].second, o = keyed[i + 1 < j ? i + 1 : i].second;
    if (j - i == 2 && h / 3 != o / 3) (s0.from(h) == s0.to(o) ? agree : disagree).push_back({h / 3, o / 3});
    i = j;
  }
  for (auto [a, b] : agree) uf.join(a, b, 0);
  for (auto [a, b] : disagree) uf.join(a, b, 1);
  std::vector<double> area_total(nf, 0.0), area_opposite(nf, 0.0);
  std::vector<uint8_t> rel(nf);
  std::vector<uint32_t> root(nf);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto [r, p] = uf.find(f);
    root[f] = r, rel[f] = p;
    const double a = triangle_area(s0.positions, s0.triangles[f]);
    area_total[r] += a;
    if (p) area_opposite[r] += a;
  }
  for (uint32_t f = 0; f < nf; ++f) {
    const uint8_t majority = area_opposite[root[f]] > 0.5 * area_total[root[f]] ? 1 : 0;  // stays as it is
    if (rel[f] == majority) continue;
    std::swap(s0.triangles[f][1], s0.triangles[f][2]);
    ++st.reoriented_triangles;
    reversed[f] = 1;
  }
  return reversed;
}

/// Step 4. Pairs halfedges: an edge joins its two triangles only when exactly two use it, in opposite
/// directions. Everything else is sliced (each triangle keeps its own copy of the edge). `keyed`:
/// halfedges_by_edge(s0) of its current triangles.
void pair_halfedges(Surface& s0, const std::vector<std::pair<uint64_t, uint32_t>>& keyed, RepairStats& st) {
  const size_t nh = 3 * s0.num_faces();
  s0.opposite.assign(nh, kNone);
  for (size_t i = 0; i < nh;) {
    size_t j = i + 1;
    while (j < nh && keyed[j].first == keyed[i].first) ++j;
    if (j - i == 2) {
      const uint32_t h = keyed[i].second, o = keyed[i + 1].second;
      if (s0.from(h) == s0.to(o)) {
        s0.opposite[h] = o;
        s0.opposite[o] = h;
      } else {
        ++st.inconsistent_edges;
      }
    } else if (j - i > 2) {
      ++st.non_manifold_edges;
    }
    i = j;
  }
}

/// Step 5. Slices vertices: one copy per fan of corners that stays connected through paired edges.
/// This separates bowtie vertices and the ends of sliced edges alike. Returns the manifold surface with
/// its maps composed back to the input (vertex_parent, face_parent, input_face, input_corner: a
/// reversed face's corner k is the input triangle's corner (3 - k) % 3).
Surface slice_non_manifold_vertices(const Surface& s0, const std::vector<char>& reversed, RepairStats& st) {
  uint32_t groups = 0;
  const auto corner_vertex = group_corners(
      s0, [](uint32_t) { return true; }, &groups);
  Surface s = regroup(s0, corner_vertex, groups);
  // regroup maps to s0's vertices and faces; compose with s0's maps so they point at the input.
  std::vector<uint32_t> copies(s0.num_vertices(), 0);
  for (uint32_t v = 0; v < s.num_vertices(); ++v) {
    copies[s.vertex_parent[v]]++;
    s.vertex_parent[v] = s0.vertex_parent[s.vertex_parent[v]];
  }
  for (uint32_t c : copies) st.sliced_vertices += c > 1;
  for (uint32_t t = 0; t < s.num_faces(); ++t) s.face_parent[t] = s0.face_parent[t];
  s.input_face = s.face_parent;
  s.input_corner.resize(3 * s.num_faces());
  for (size_t t = 0; t < s.num_faces(); ++t)
    for (size_t k = 0; k < 3; ++k) s.input_corner[3 * t + k] = uint8_t(reversed[t] ? (3 - k) % 3 : k);
  return s;
}

/// Step 6. Closes slits. Slicing an edge shared by several sheets can leave a sheet whose fan around
/// each end vertex is whole but open along that edge: two boundary halfedges a->b and b->a with the
/// same vertex copies. They are the two ends of one fan chain, so pairing them restores a manifold disk.
void close_slits(Surface& s, RepairStats& st) {
  std::vector<std::pair<uint64_t, uint32_t>> open;
  for (uint32_t h = 0; h < s.opposite.size(); ++h)
    if (s.opposite[h] == kNone) open.push_back({uint64_t(s.from(h)) << 32 | s.to(h), h});
  std::sort(open.begin(), open.end());
  auto unique_find = [&](uint64_t key) -> uint32_t {
    auto it = std::lower_bound(open.begin(), open.end(), std::pair<uint64_t, uint32_t>{key, 0});
    if (it == open.end() || it->first != key) return kNone;
    if (std::next(it) != open.end() && std::next(it)->first == key) return kNone;
    return it->second;
  };
  for (auto [key, h] : open) {
    if (s.opposite[h] != kNone) continue;
    const uint32_t g = unique_find((key & 0xffffffffu) << 32 | (key >> 32));
    if (g == kNone || s.opposite[g] != kNone || unique_find(key) != h) continue;
    s.opposite[h] = g;
    s.opposite[g] = h;
    ++st.slits_closed;
  }
}

}  // namespace

Surface prepare_surface(const TexturedMesh& mesh, RepairStats* stats, std::vector<std::pair<uint32_t, uint32_t>>* repeats,
                        const std::vector<char>* left_out) {
  RepairStats st;
  st.input_vertices = mesh.num_vertices();
  std::vector<uint32_t> welded_origin;  // welded vertex -> first input vertex
  const std::vector<uint32_t> weld = weld_vertices(mesh, welded_origin);
  st.welded_vertices = welded_origin.size();

  Surface s0;
  s0.positions.resize(welded_origin.size());
  for (size_t w = 0; w < welded_origin.size(); ++w) s0.positions[w] = mesh.positions[welded_origin[w]];
  s0.vertex_parent = welded_origin;
  std::vector<std::pair<uint32_t, uint32_t>> repeated;
  std::vector<uint32_t> layer;
  drop_degenerate_triangles(mesh, weld, left_out, s0, st, repeated, layer);
  separate_layers(layer, s0);
  if (repeats) *repeats = std::move(repeated);

  auto keyed = halfedges_by_edge(s0);
  const std::vector<char> reversed = orient_patches(s0, keyed, st);
  if (st.reoriented_triangles) keyed = halfedges_by_edge(s0);  // halfedge ids moved with the corners
  pair_halfedges(s0, keyed, st);

  Surface s = slice_non_manifold_vertices(s0, reversed, st);
  close_slits(s, st);
  if (stats) *stats = st;
  return s;
}

}  // namespace tightex
