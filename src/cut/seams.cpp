// The input's texture seams, mapped onto a component's edges (see find_texture_seams).
#include "cut/seams.hpp"

namespace tightex {

std::vector<char> find_texture_seams(const TexturedMesh& input, const Surface& component) {
  std::vector<char> seam(component.opposite.size(), 0);
  for (uint32_t h = 0; h < component.opposite.size(); ++h) {
    const uint32_t o = component.opposite[h];
    if (o == kNone || o < h) continue;
    const uint32_t t = component.input_face[h / 3], u = component.input_face[o / 3];
    // h runs from corner k to corner k + 1 of t; o from corner j (the same vertex as k + 1) to j + 1 (as k).
    const size_t k = h % 3, j = o % 3;
    auto uv = [&](uint32_t face, size_t corner) {
      return input.corner_uv[3 * size_t(component.input_face[face]) + component.input_corner[3 * face + corner]];
    };
    const bool differs = input.face_material[t] != input.face_material[u] || uv(h / 3, k) != uv(o / 3, (j + 1) % 3) ||
                         uv(h / 3, (k + 1) % 3) != uv(o / 3, j);
    seam[h] = seam[o] = differs;
  }
  return seam;
}

}  // namespace tightex
