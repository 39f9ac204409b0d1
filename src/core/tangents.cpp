#include "core/tangents.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace tightex {

namespace {

/// A unit vector orthogonal to unit vector n.
Vec3 any_orthogonal(const Vec3& n) {
  const Vec3 axis = std::abs(n.x()) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  return (axis - n * n.dot(axis)).normalized();
}

/// The direction of increasing u on triangle t (unnormalised) and whether its texture-space area is
/// positive; a zero vector when the triangle has no area in texture space.
std::pair<Vec3, bool> triangle_u_direction(const TexturedMesh& mesh, size_t t) {
  const Tri& tri = mesh.triangles[t];
  const Vec3 e1 = mesh.positions[tri[1]] - mesh.positions[tri[0]], e2 = mesh.positions[tri[2]] - mesh.positions[tri[0]];
  const Vec2 q0 = mesh.sampled_uv(t, 0), d1 = mesh.sampled_uv(t, 1) - q0, d2 = mesh.sampled_uv(t, 2) - q0;
  const double det = d1.x() * d2.y() - d2.x() * d1.y();
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return {Vec3::Zero(), true};
  const Vec3 s = (e1 * d2.y() - e2 * d1.y()) / det;
  return {s.allFinite() ? s : Vec3::Zero(), det > 0};
}

/// The angle of triangle t at corner k (its weight in the vertex average).
double corner_angle(const TexturedMesh& mesh, size_t t, int k) {
  const Tri& tri = mesh.triangles[t];
  const Vec3& p = mesh.positions[tri[size_t(k)]];
  const Vec3 a = mesh.positions[tri[size_t((k + 1) % 3)]] - p, b = mesh.positions[tri[size_t((k + 2) % 3)]] - p;
  const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
  return std::isfinite(angle) ? angle : 0.0;
}

/// What makes two corners one vertex of the tangent computation.
struct CornerKey {
  uint32_t vertex;
  double u, v, nx, ny, nz;
  bool positive;
  auto tie() const { return std::tie(vertex, u, v, nx, ny, nz, positive); }
};

}  // namespace

Vec3 frame_normal(const TexturedMesh& mesh, size_t t, int k) {
  if (mesh.corner_normal.size() == 3 * mesh.num_triangles()) {
    const Vec3& n = mesh.corner_normal[3 * t + size_t(k)];
    if (n.allFinite() && n.norm() > 0) return n.normalized();
  }
  const Tri& tri = mesh.triangles[t];
  const Vec3 n = (mesh.positions[tri[1]] - mesh.positions[tri[0]]).cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
  return n.allFinite() && n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 1);
}

std::vector<Vec4> compute_corner_tangents(const TexturedMesh& mesh) {
  const size_t corners = 3 * mesh.num_triangles();
  std::vector<CornerKey> key(corners);
  std::vector<Vec3> contribution(corners, Vec3::Zero());
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto [s, positive] = triangle_u_direction(mesh, t);
    for (int k = 0; k < 3; ++k) {
      const size_t c = 3 * t + size_t(k);
      const Vec3 n = frame_normal(mesh, t, k);
      const Vec2 uv = mesh.sampled_uv(t, k);
      key[c] = {mesh.triangles[t][size_t(k)], uv.x(), uv.y(), n.x(), n.y(), n.z(), positive};
      const Vec3 projected = s - n * n.dot(s);
      if (projected.norm() > 0) contribution[c] = projected.normalized() * corner_angle(mesh, t, k);
    }
  }
  std::vector<size_t> order(corners);
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return std::make_pair(key[a].tie(), a) < std::make_pair(key[b].tie(), b); });
  std::vector<Vec4> tangents(corners);
  for (size_t begin = 0; begin < corners;) {
    size_t end = begin + 1;
    while (end < corners && key[order[end]].tie() == key[order[begin]].tie()) ++end;
    Vec3 sum = Vec3::Zero();
    for (size_t i = begin; i < end; ++i) sum += contribution[order[i]];
    const size_t first = order[begin];
    const Vec3 n(key[first].nx, key[first].ny, key[first].nz);
    const Vec3 tangent = sum.norm() > 1e-12 ? Vec3(sum.normalized()) : any_orthogonal(n);
    for (size_t i = begin; i < end; ++i) tangents[order[i]] = Vec4(tangent, key[first].positive ? 1.0 : -1.0);
    begin = end;
  }
  return tangents;
}

std::vector<Vec4> completed_corner_tangents(const TexturedMesh& mesh) {
  const size_t corners = 3 * mesh.num_triangles();
  std::vector<Vec4> computed = compute_corner_tangents(mesh);
  if (mesh.corner_tangent.size() != corners) return computed;
  std::vector<Vec4> result = mesh.corner_tangent;
  for (size_t c = 0; c < corners; ++c) {
    Vec4& tg = result[c];
    const Vec3 n = frame_normal(mesh, c / 3, int(c % 3));
    Vec3 xyz = tg.head<3>();
    xyz -= n * n.dot(xyz);
    if (!tg.allFinite() || std::abs(std::abs(tg.w()) - 1) > 1e-3 || !(xyz.norm() > 1e-6)) {
      tg = computed[c];
      continue;
    }
    tg = Vec4(xyz.normalized(), tg.w() > 0 ? 1.0 : -1.0);
  }
  return result;
}

}  // namespace tightex
