#include "report/view_mesh.hpp"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/hash.hpp"

namespace tightex {

namespace {

/// Per vertex, the dense index of its cell (cells numbered in order of first appearance); the count of
/// cells in `cells`.
std::vector<uint32_t> vertex_cells(const TexturedMesh& mesh, double cell, size_t& cells) {
  std::unordered_map<uint64_t, uint32_t> index;
  index.reserve(mesh.num_vertices() / 4 + 16);
  std::vector<uint32_t> of(mesh.num_vertices());
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a)  // 21 bits an axis: a cell grid of up to 2^21 cells a side
      key |= (uint64_t(int64_t(std::floor(mesh.positions[v][a] / cell))) & 0x1FFFFF) << (21 * a);
    of[v] = index.try_emplace(key, uint32_t(index.size())).first->second;
  }
  cells = index.size();
  return of;
}

/// The triangles kept: corners in three different cells, the first on each set of three cells.
std::vector<uint32_t> kept_triangles(const TexturedMesh& mesh, const std::vector<uint32_t>& cell_of) {
  std::unordered_set<uint64_t> seen;
  std::vector<uint32_t> kept;
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    std::array<uint32_t, 3> c{cell_of[mesh.triangles[t][0]], cell_of[mesh.triangles[t][1]], cell_of[mesh.triangles[t][2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    std::sort(c.begin(), c.end());
    if (seen.insert(splitmix64(c[0] ^ splitmix64(c[1] ^ splitmix64(c[2])))).second) kept.push_back(uint32_t(t));
  }
  return kept;
}

/// Union-find over corners.
struct CornerSets {
  std::vector<uint32_t> parent;
  explicit CornerSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  }
  void join(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

/// The corners' patches (see clustered_mesh): corners at one vertex with one material and equal texture
/// coordinates joined, then the two ends of every triangle edge that lies inside one cell.
CornerSets corner_patches(const TexturedMesh& mesh, const std::vector<uint32_t>& cell_of) {
  const size_t n = 3 * mesh.num_triangles();
  CornerSets sets(n);
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto key = [&](uint32_t c) {
    const Vec2& uv = mesh.corner_uv[c];
    return std::make_tuple(mesh.triangles[c / 3][c % 3], mesh.face_material[c / 3], uv.x(), uv.y());
  };
  tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  for (size_t i = 1; i < n; ++i)
    if (key(order[i]) == key(order[i - 1])) sets.join(order[i], order[i - 1]);
  for (uint32_t t = 0; t < mesh.num_triangles(); ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t k1 = (k + 1) % 3;
      if (cell_of[mesh.triangles[t][k]] == cell_of[mesh.triangles[t][k1]]) sets.join(3 * t + k, 3 * t + k1);
    }
  return sets;
}

}  // namespace

TexturedMesh clustered_mesh(const TexturedMesh& mesh, double cell) {
  size_t cells = 0;
  const std::vector<uint32_t> cell_of = vertex_cells(mesh, cell, cells);
  const std::vector<uint32_t> kept = kept_triangles(mesh, cell_of);
  // Each corner's patch, numbered densely (the union-find's array reused for the numbers).
  const uint32_t corners = uint32_t(3 * mesh.num_triangles());
  std::vector<uint32_t> patch_of(corners);
  size_t patches = 0;
  {
    CornerSets sets = corner_patches(mesh, cell_of);
    for (uint32_t c = 0; c < corners; ++c) patch_of[c] = sets.find(c);
    std::vector<uint32_t>& number = sets.parent;  // per root, its patch
    std::fill(number.begin(), number.end(), kNone);
    for (uint32_t c = 0; c < corners; ++c) {
      uint32_t& n = number[patch_of[c]];
      if (n == kNone) n = uint32_t(patches++);
      patch_of[c] = n;
    }
  }
  // Each cell's mean position, each patch's mean texture coordinate.
  std::vector<Vec3> cell_sum(cells, Vec3(0, 0, 0));
  std::vector<double> cell_count(cells, 0);
  for (size_t v = 0; v < mesh.num_vertices(); ++v) cell_sum[cell_of[v]] += mesh.positions[v], cell_count[cell_of[v]] += 1;
  std::vector<Vec2> uv_sum(patches, Vec2(0, 0));
  std::vector<uint32_t> uv_count(patches, 0);
  for (uint32_t c = 0; c < corners; ++c) uv_sum[patch_of[c]] += mesh.corner_uv[c], ++uv_count[patch_of[c]];
  TexturedMesh out;
  out.materials = mesh.materials;
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    Texture t;
    t.path = mesh.textures[i].path;
    std::tie(t.width, t.height) = texture_size(mesh, int(i));
    out.textures.push_back(std::move(t));
  }
  std::vector<uint32_t> vertex_of_cell(cells, kNone);
  for (const uint32_t t : kept) {
    Tri tri;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t c = cell_of[mesh.triangles[t][k]];
      if (vertex_of_cell[c] == kNone) {
        vertex_of_cell[c] = uint32_t(out.positions.size());
        out.positions.push_back(cell_sum[c] / cell_count[c]);
      }
      tri[k] = vertex_of_cell[c];
      const uint32_t p = patch_of[3 * t + k];
      out.corner_uv.push_back(uv_sum[p] / double(uv_count[p]));
    }
    out.triangles.push_back(tri);
    out.face_material.push_back(mesh.face_material[t]);
  }
  return out;
}

double cluster_cell(const TexturedMesh& mesh, size_t max_triangles) {
  if (mesh.num_triangles() <= max_triangles || mesh.num_vertices() == 0) return 0;
  double area = 0;
  Vec3 lo = mesh.positions[0], hi = mesh.positions[0];
  for (const Vec3& p : mesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (const Tri& t : mesh.triangles)
    area += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
  // About two triangles per occupied cell, and a surface crosses about 1.5 area / cell^2 cells; then
  // grown by the square root of the excess (the count goes as 1 / cell^2) until under the cap.
  const double diagonal = (hi - lo).norm();
  double cell = std::max(std::sqrt(3.0 * area / double(std::max<size_t>(max_triangles, 1))), diagonal * 1e-5);
  if (!(cell > 0)) return 1;  // every vertex at one point: one cell
  for (int tries = 0; tries < 60; ++tries) {
    size_t cells = 0;
    const size_t kept = kept_triangles(mesh, vertex_cells(mesh, cell, cells)).size();
    if (kept <= max_triangles) break;
    cell *= std::max(1.05, 1.02 * std::sqrt(double(kept) / double(std::max<size_t>(max_triangles, 1))));
  }
  return cell;
}

}  // namespace tightex
