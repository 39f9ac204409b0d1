#include "core/mesh.hpp"

#include <Eigen/Geometry>

namespace tightex {

Vec2 TexturedMesh::sampled_uv(size_t triangle, int corner) const {
  Vec2 uv = corner_uv[3 * triangle + size_t(corner)];
  const int32_t m = face_material[triangle];
  if (m >= 0) {
    const Material& mat = materials[size_t(m)];
    uv = Vec2(uv.x() * mat.uv_scale[0] + mat.uv_offset[0], uv.y() * mat.uv_scale[1] + mat.uv_offset[1]);
  }
  return uv;
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y()));
}

}  // namespace tightex
