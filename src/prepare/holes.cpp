#include "prepare/holes.hpp"

namespace tightex {

Surface fill_holes(const Surface& s, const std::vector<std::vector<uint32_t>>& loops) {
  Surface r = with_identity_parents(s);
  for (const auto& loop : loops) {
    Vec3 centroid = Vec3::Zero();
    for (uint32_t h : loop) centroid += s.positions[s.from(h)];
    centroid /= double(loop.size());
    const uint32_t c = uint32_t(r.positions.size());
    r.positions.push_back(centroid);
    r.vertex_parent.push_back(kNone);
    for (uint32_t h : loop) {
      // boundary halfedge a->b has the surface on its left; the fan triangle uses b->a.
      r.triangles.push_back({c, s.to(h), s.from(h)});
      r.face_parent.push_back(kNone);
    }
  }
  build_opposite(r);
  inherit_input_map(r, s);
  return r;
}

}  // namespace tightex
