#include "core/mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>

namespace tightex {

namespace {

/// What each MaterialSlot is, in slot order.
struct SlotTraits {
  const char* name;
  SlotEncoding encoding;
  unsigned channels;  // bit 0 red, 1 green, 2 blue, 3 alpha
  SlotFactor factor;  // glTF's default factor
};

constexpr SlotEncoding kColour = SlotEncoding::kSrgbColour, kData = SlotEncoding::kData, kNormal = SlotEncoding::kTangentNormal;
constexpr SlotTraits kSlots[kMaterialSlots] = {
    {"metallic_roughness", kData, 6, {1, 1, 1, 1}},
    {"occlusion", kData, 1, {1, 1, 1, 1}},
    {"emissive", kColour, 7, {0, 0, 0, 1}},
    {"normal", kNormal, 7, {1, 1, 1, 1}},
    {"specular", kColour, 7, {1, 1, 1, 1}},
    {"roughness", kData, 1, {1, 1, 1, 1}},
    {"metallic", kData, 1, {0, 0, 0, 1}},
    {"bump", kData, 1, {0, 0, 0, 1}},
    {"specular_strength", kData, 8, {1, 1, 1, 1}},
    {"clearcoat", kData, 1, {0, 0, 0, 1}},
    {"clearcoat_roughness", kData, 2, {0, 0, 0, 1}},
    {"clearcoat_normal", kNormal, 7, {1, 1, 1, 1}},
    {"sheen_colour", kColour, 7, {0, 0, 0, 1}},
    {"sheen_roughness", kData, 8, {0, 0, 0, 0}},
    {"transmission", kData, 1, {0, 0, 0, 1}},
    {"thickness", kData, 2, {0, 0, 0, 1}},
    {"iridescence", kData, 1, {0, 0, 0, 1}},
    {"iridescence_thickness", kData, 2, {1, 1, 1, 1}},
    {"anisotropy", kData, 7, {1, 1, 0, 1}},
    {"opacity", kData, 1, {1, 1, 1, 1}},
    {"shininess", kData, 1, {1, 1, 1, 1}},
    {"displacement", kData, 1, {0, 0, 0, 1}},
};

}  // namespace

SlotEncoding slot_encoding(MaterialSlot slot) { return kSlots[size_t(slot)].encoding; }

unsigned material_slot_channels(MaterialSlot slot) { return kSlots[size_t(slot)].channels; }

const char* material_slot_name(MaterialSlot slot) { return kSlots[size_t(slot)].name; }

std::array<SlotFactor, kMaterialSlots> default_slot_factors() {
  std::array<SlotFactor, kMaterialSlots> f;
  for (size_t s = 0; s < kMaterialSlots; ++s) f[s] = kSlots[s].factor;
  return f;
}

std::array<int, kMaterialSlots> unbound_slots() {
  std::array<int, kMaterialSlots> maps;
  maps.fill(-1);
  return maps;
}

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

namespace {

/// The mean squared gradient of `img` (8-bit levels per texel, summed over the channels of `channels`)
/// at up to 15 points of triangle a b c, times the triangle's texels in `img`: the squared detail per
/// unit of 3D area once divided by the 3D area. 0 for a triangle without texels.
double squared_detail_texels(const Image& img, const Vec2& a, const Vec2& b, const Vec2& c, unsigned channels) {
  const double texels = std::abs(signed_area(a, b, c)) * double(img.width) * double(img.height);
  if (!(texels > 0) || !std::isfinite(texels)) return 0.0;
  // Points: a barycentric grid of n(n+1)/2 points, n from 1 (tiny) to 5 (25+ texels).
  const int n = texels >= 25 ? 5 : std::max(1, int(std::sqrt(texels)));
  const double du = 1.0 / img.width, dv = 1.0 / img.height;
  double sum = 0;
  int count = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j) {
      const double l1 = (i + 1.0 / 3.0) / n, l2 = (j + 1.0 / 3.0) / n, l0 = 1.0 - l1 - l2;
      const Vec2 p = l0 * a + l1 * b + l2 * c;
      const auto xp = sample_bilinear(img, p.x() + du, p.y()), xm = sample_bilinear(img, p.x() - du, p.y());
      const auto yp = sample_bilinear(img, p.x(), p.y() + dv), ym = sample_bilinear(img, p.x(), p.y() - dv);
      for (int ch = 0; ch < 4; ++ch) {
        if (!(channels & (1u << ch))) continue;
        const double gx = 0.5 * (xp[size_t(ch)] - xm[size_t(ch)]), gy = 0.5 * (yp[size_t(ch)] - ym[size_t(ch)]);
        sum += gx * gx + gy * gy;
      }
      ++count;
    }
  return sum / count * texels;
}

}  // namespace

double input_detail(const TexturedMesh& mesh, size_t t) {
  const int32_t m = mesh.face_material[t];
  if (m < 0) return 0.0;
  const Material& mat = mesh.materials[size_t(m)];
  const int ti = mat.texture;
  if (ti < 0 || mesh.textures[size_t(ti)].image.empty()) return 0.0;
  const Image& img = mesh.textures[size_t(ti)].image;
  const Vec2 a = mesh.sampled_uv(t, 0), b = mesh.sampled_uv(t, 1), c = mesh.sampled_uv(t, 2);
  const double texels = std::abs(signed_area(a, b, c)) * double(img.width) * double(img.height);
  const double a3 =
      triangle_area(mesh.positions[mesh.triangles[t][0]], mesh.positions[mesh.triangles[t][1]], mesh.positions[mesh.triangles[t][2]]);
  if (!(a3 > 0) || !(texels > 0) || !std::isfinite(texels) || !std::isfinite(a3)) return 0.0;
  // Levels per texel -> levels per unit length: times the texels per unit length. Every other slot the
  // material binds adds its own, brought to the colour's three channels (each slot's PSNR is a mean
  // over its own channels, so one channel's error counts as much as three of the colour's).
  double squared = squared_detail_texels(img, a, b, c, 7u) / a3;
  for (size_t s = 0; s < kMaterialSlots; ++s) {
    const int tex = mat.maps[s];
    if (tex < 0 || mesh.textures[size_t(tex)].image.empty()) continue;
    const unsigned channels = material_slot_channels(MaterialSlot(s));
    const double per_colour = 3.0 / double(std::popcount(channels));
    squared += per_colour * squared_detail_texels(mesh.textures[size_t(tex)].image, a, b, c, channels) / a3;
  }
  const double detail = std::sqrt(squared);
  return std::isfinite(detail) ? detail : 0.0;
}

int texture_of(const TexturedMesh& m, size_t t) {
  const int32_t mat = m.face_material[t];
  return mat >= 0 && size_t(mat) < m.materials.size() ? m.materials[size_t(mat)].texture : -1;
}

const Image* image_of(const TexturedMesh& m, size_t t) {
  const int32_t mat = m.face_material[t];
  if (mat < 0) return nullptr;
  const int tex = m.materials[size_t(mat)].texture;
  if (tex < 0 || m.textures[size_t(tex)].image.empty()) return nullptr;
  return &m.textures[size_t(tex)].image;
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y()));
}

}  // namespace tightex
