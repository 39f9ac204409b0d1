// The input's texture seams, mapped onto a component's edges (see find_texture_seams).
#include "repair/repair.hpp"
#include "topology/topology.hpp"

namespace tightex {

std::vector<char> find_texture_seams(const TexturedMesh& input, const Surface& surface, const Surface& component,
                                     const std::vector<char>& reversed) {
  std::vector<char> seam(component.opposite.size(), 0);
  for (uint32_t h = 0; h < component.opposite.size(); ++h) {
    const uint32_t o = component.opposite[h];
    if (o == kNone || o < h) continue;
    const uint32_t t = surface.face_parent[component.face_parent[h / 3]], u = surface.face_parent[component.face_parent[o / 3]];
    // h runs from corner k to corner k + 1 of t; o from corner j (the same vertex as k + 1) to j + 1 (as k).
    const size_t k = h % 3, j = o % 3;
    auto uv = [&](uint32_t tri, size_t corner) {
      return input.corner_uv[3 * tri + size_t(input_corner(!reversed.empty() && reversed[tri], int(corner)))];
    };
    const bool differs = input.face_material[t] != input.face_material[u] || uv(t, k) != uv(u, (j + 1) % 3) ||
                         uv(t, (k + 1) % 3) != uv(u, j);
    seam[h] = seam[o] = differs;
  }
  return seam;
}

}  // namespace tightex
