#include "prepare/components.hpp"

namespace tightex {

std::vector<Surface> split_components(const Surface& s) {
  std::vector<uint32_t> comp;
  const uint32_t n = face_components(s, comp);
  std::vector<Surface> out(n);
  std::vector<uint32_t> local_vertex(s.num_vertices(), kNone), local_face(s.num_faces());
  for (uint32_t t = 0; t < s.num_faces(); ++t) {
    Surface& c = out[comp[t]];
    local_face[t] = uint32_t(c.triangles.size());
    Tri f;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = s.triangles[t][k];
      if (local_vertex[v] == kNone) {
        local_vertex[v] = uint32_t(c.positions.size());
        c.positions.push_back(s.positions[v]);
        c.vertex_parent.push_back(v);
      }
      f[k] = local_vertex[v];
    }
    c.triangles.push_back(f);
    c.face_parent.push_back(t);
  }
  for (Surface& c : out) {
    c.opposite.assign(3 * c.num_faces(), kNone);
    for (uint32_t lt = 0; lt < c.num_faces(); ++lt)
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = s.opposite[3 * c.face_parent[lt] + k];
        if (o != kNone) c.opposite[3 * lt + k] = 3 * local_face[o / 3] + o % 3;
      }
    inherit_input_map(c, s);
  }
  return out;
}

}  // namespace tightex
