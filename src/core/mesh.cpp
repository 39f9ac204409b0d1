#include "core/mesh.hpp"

#include <Eigen/Geometry>
#include <cmath>

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

std::pair<int, int> texture_size(const TexturedMesh& mesh, int i) {
  if (i < 0 || size_t(i) >= mesh.textures.size()) return {0, 0};
  const Texture& t = mesh.textures[size_t(i)];
  if (!t.image.empty()) return {t.image.width, t.image.height};
  return {t.width, t.height};
}

double input_texel_area(const TexturedMesh& mesh, size_t t) {
  const int32_t m = mesh.face_material[t];
  if (m < 0) return 0.0;
  const auto [w, h] = texture_size(mesh, mesh.materials[size_t(m)].texture);
  const double a = std::abs(signed_area(mesh.sampled_uv(t, 0), mesh.sampled_uv(t, 1), mesh.sampled_uv(t, 2)));
  return a * double(w) * double(h);
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y()));
}

}  // namespace tightex
