// Sampling the original texture through one output triangle's original UVs (paper §4.3), with
// footprint filtering where the input is minified. Shared by the bake and its least-squares fit.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "bake/bake.hpp"
#include "core/image.hpp"
#include "core/mesh.hpp"

namespace tightex {

/// A colour in [0, 255] per channel rounded to 8 bits (clamped).
inline Rgba8 to_rgba(const std::array<float, 4>& c) {
  auto q = [](float x) { return uint8_t(std::clamp(x + 0.5f, 0.0f, 255.0f)); };
  return {q(c[0]), q(c[1]), q(c[2]), q(c[3])};
}

/// What sampling one triangle needs, computed once: the source UV and the barycentric weights as affine
/// functions of the target pixel position, and the footprint of an output texel in input pixels.
struct TriangleSampler {
  const Image* src = nullptr;  // the input texture; nullptr: the triangle takes `flat`
  Rgba8 flat{255, 255, 255, 255};
  Vec2 uv0, du_dx, du_dy;                   // source uv at target pixel (0,0) and its derivatives (affine per triangle)
  double bary_x[3], bary_y[3], bary_0[3];   // barycentric weights as affine functions of the target pixel
  double footprint_x = 0, footprint_y = 0;  // input pixels spanned by one output texel along x and y
  double weight = 0;                        // 3D area per output texel (least-squares fit)
  bool valid = false;                       // false for a degenerate target triangle or a non-finite weight
  /// The input's colours are defined at the triangle's corners (a texture made from vertex colours):
  /// the fit also samples the corners, so that the output reproduces each vertex's colour there.
  bool corner_samples = false;
  std::array<Vec2, 3> corner_uv;
  bool unread = false;  // MaterialSampling::unread
  /// How the texels are filtered (bake_material_map); kData without `frames` is the base colour's plain path.
  SlotEncoding encoding = SlotEncoding::kData;
  const NormalFrames* frames = nullptr;  // kTangentNormal only

  /// Requires: `source` outlives the sampler (or is nullptr). Guarantees: `valid` says whether the
  /// affine maps and the weight are usable; `src` and `flat` are set either way.
  void init(const BakeTriangle& tri, const Image* source, Rgba8 flat_colour) {
    src = source;
    flat = flat_colour;
    corner_uv = tri.source_uv;
    const Vec2 &p0 = tri.target_px[0], &p1 = tri.target_px[1], &p2 = tri.target_px[2];
    const double det = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p1.y() - p0.y()) * (p2.x() - p0.x());
    if (!(std::abs(det) > 0) || !std::isfinite(det)) return;
    // w1, w2 from the 2x2 inverse; w0 = 1 - w1 - w2.
    const double i00 = (p2.y() - p0.y()) / det, i01 = -(p2.x() - p0.x()) / det;
    const double i10 = -(p1.y() - p0.y()) / det, i11 = (p1.x() - p0.x()) / det;
    bary_x[1] = i00, bary_y[1] = i01, bary_0[1] = -(i00 * p0.x() + i01 * p0.y());
    bary_x[2] = i10, bary_y[2] = i11, bary_0[2] = -(i10 * p0.x() + i11 * p0.y());
    bary_x[0] = -bary_x[1] - bary_x[2], bary_y[0] = -bary_y[1] - bary_y[2], bary_0[0] = 1 - bary_0[1] - bary_0[2];
    uv0 = Vec2::Zero(), du_dx = Vec2::Zero(), du_dy = Vec2::Zero();
    for (int k = 0; k < 3; ++k) {
      uv0 += bary_0[k] * tri.source_uv[k];
      du_dx += bary_x[k] * tri.source_uv[k];
      du_dy += bary_y[k] * tri.source_uv[k];
    }
    if (src) {
      footprint_x = std::hypot(du_dx.x() * src->width, du_dx.y() * src->height);
      footprint_y = std::hypot(du_dy.x() * src->width, du_dy.y() * src->height);
    }
    weight = tri.area3 / (0.5 * std::abs(det));
    valid = std::isfinite(weight);
  }

  /// The source UV at target pixel position (x, y), kept inside the triangle: outside it, the
  /// barycentrics are clamped to 0 and renormalised (approximately the nearest point of the triangle).
  Vec2 source_uv_at(double x, double y) const {
    double w[3], total = 0;
    for (int k = 0; k < 3; ++k) total += w[k] = std::max(0.0, bary_0[k] + bary_x[k] * x + bary_y[k] * y);
    Vec2 uv = uv0 + x * du_dx + y * du_dy;
    if (w[0] == 0 || w[1] == 0 || w[2] == 0) {
      uv = Vec2::Zero();
      for (int k = 0; k < 3; ++k) uv += (w[k] / total) * corner_uv[k];
    }
    return uv;
  }

  /// The barycentric weights at target pixel position (x, y), clamped to the triangle as source_uv_at
  /// does (the triangle's centre when they all clamp to 0).
  std::array<double, 3> barycentrics_at(double x, double y) const {
    std::array<double, 3> w{};
    double total = 0;
    for (int k = 0; k < 3; ++k) total += w[size_t(k)] = std::max(0.0, bary_0[k] + bary_x[k] * x + bary_y[k] * y);
    if (!(total > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
    for (double& v : w) v /= total;
    return w;
  }

  /// The input's object-space normal at barycentrics b: the normal map's texel (bilinear, decoded as
  /// glTF does: 2 c / 255 - 1) through the input's interpolated tangent frame, normalised.
  Vec3 object_normal_at(const std::array<double, 3>& b) const {
    const Vec2 uv = b[0] * corner_uv[0] + b[1] * corner_uv[1] + b[2] * corner_uv[2];
    const auto c = sample_bilinear(*src, uv.x(), uv.y());
    Vec3 tangent = Vec3::Zero(), normal = Vec3::Zero();
    for (size_t k = 0; k < 3; ++k) tangent += b[k] * frames->input[k].tangent, normal += b[k] * frames->input[k].normal;
    const Vec3 bitangent = frames->input[0].sign * normal.cross(tangent);
    const Vec3 n = (c[0] / 127.5 - 1) * tangent + (c[1] / 127.5 - 1) * bitangent + (c[2] / 127.5 - 1) * normal;
    return n.norm() > 0 ? Vec3(n.normalized()) : Vec3(normal.normalized());
  }

  /// Object-space normal n encoded in the output's tangent frame at barycentrics b (8-bit scale).
  std::array<float, 4> encode_normal(const Vec3& n, const std::array<double, 3>& b) const {
    Vec3 tangent = Vec3::Zero(), normal = Vec3::Zero();
    for (size_t k = 0; k < 3; ++k) tangent += b[k] * frames->output[k].tangent, normal += b[k] * frames->output[k].normal;
    // The frame's inverse by its adjugate: rows (B x N, N x T, T x B) / det (the scale does not matter,
    // t is normalised; the sign of det does).
    const Vec3 bitangent = frames->output[0].sign * normal.cross(tangent);
    const double det = tangent.dot(bitangent.cross(normal));
    Vec3 t(bitangent.cross(normal).dot(n), normal.cross(tangent).dot(n), tangent.cross(bitangent).dot(n));
    t = det < 0 ? Vec3(-t) : t;
    t = t.allFinite() && t.norm() > 0 ? Vec3(t.normalized()) : Vec3(0, 0, 1);
    return {float((t.x() + 1) * 127.5), float((t.y() + 1) * 127.5), float((t.z() + 1) * 127.5), 255.f};
  }

  /// One sample of the source map at target pixel position (x, y) as the map's encoding filters it:
  /// linear light for sRGB colour, as stored for data.
  std::array<float, 4> map_sample(double x, double y) const {
    const Vec2 uv = source_uv_at(x, y);
    return encoding == SlotEncoding::kSrgbColour ? sample_bilinear_linear_light(*src, uv.x(), uv.y())
                                                 : sample_bilinear(*src, uv.x(), uv.y());
  }

  /// footprint_colour of a map other than the plain base colour (see bake_material_map).
  std::array<float, 4> footprint_map_value(double x, double y, double box, int max_samples) const {
    auto samples_along = [&](double footprint) {
      const double n = std::ceil(footprint * box - 1e-9);
      return n >= max_samples ? max_samples : n >= 1 ? int(n) : 1;
    };
    const int nx = samples_along(footprint_x), ny = samples_along(footprint_y);
    std::array<float, 4> sum{0, 0, 0, 0};
    Vec3 normal_sum = Vec3::Zero();
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double sx = x + box * ((i + 0.5) / nx - 0.5), sy = y + box * ((j + 0.5) / ny - 0.5);
        if (encoding == SlotEncoding::kTangentNormal) {
          normal_sum += object_normal_at(barycentrics_at(sx, sy));
          continue;
        }
        const auto c = map_sample(sx, sy);
        for (int ch = 0; ch < 4; ++ch) sum[size_t(ch)] += c[size_t(ch)];
      }
    if (encoding == SlotEncoding::kTangentNormal) return encode_normal(normal_sum, barycentrics_at(x, y));
    const float inv = 1.0f / float(nx * ny);
    for (float& c : sum) c *= inv;
    if (encoding == SlotEncoding::kSrgbColour)
      for (int ch = 0; ch < 3; ++ch) sum[size_t(ch)] = srgb_encode_255(sum[size_t(ch)]);
    return sum;
  }

  /// Footprint filtering: the mean colour over a box of side `box` output texels centred at target
  /// pixel position (x, y), from n x m bilinear samples (n, m the box's extent in input pixels along x
  /// and y, at least 1, at most `max_samples`). The sample points are kept inside the triangle, so a
  /// texel on a chart's edge never averages in the input's empty space beyond the triangle.
  /// Requires: `valid` when `src` is set. Returns `flat` without a source texture.
  std::array<float, 4> footprint_colour(double x, double y, double box, int max_samples) const {
    if (!src) return {float(flat.r), float(flat.g), float(flat.b), float(flat.a)};
    if (encoding != SlotEncoding::kData || frames) return footprint_map_value(x, y, box, max_samples);
    // Clamped before the conversion to int: a material's -s can make the footprint 1e300, and a NaN
    // footprint takes one sample.
    auto samples_along = [&](double footprint) {
      const double n = std::ceil(footprint * box - 1e-9);
      return n >= max_samples ? max_samples : n >= 1 ? int(n) : 1;
    };
    // Common case (a footprint of at most one input pixel along both axes): one sample, the same as the
    // general loop below with nx = ny = 1, without its ceil() calls (the fit takes K^2 samples a texel).
    if (footprint_x * box - 1e-9 <= 1 && footprint_y * box - 1e-9 <= 1) {
      const Vec2 uv = source_uv_at(x, y);
      return sample_bilinear(*src, uv.x(), uv.y());
    }
    const int nx = samples_along(footprint_x), ny = samples_along(footprint_y);
    std::array<float, 4> sum{0, 0, 0, 0};
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double sx = x + box * ((i + 0.5) / nx - 0.5), sy = y + box * ((j + 0.5) / ny - 0.5);
        const Vec2 uv = source_uv_at(sx, sy);
        const auto c = sample_bilinear(*src, uv.x(), uv.y());
        for (int ch = 0; ch < 4; ++ch) sum[size_t(ch)] += c[size_t(ch)];
      }
    const float inv = 1.0f / float(nx * ny);
    for (float& c : sum) c *= inv;
    return sum;
  }
};

/// What the sampler of a triangle of one material reads: its texture (nullptr: none with pixels), the
/// colour it takes without one, and whether it samples its corners (TriangleSampler::corner_samples).
struct MaterialSampling {
  const Image* src = nullptr;
  Rgba8 flat{255, 255, 255, 255};
  bool corner_samples = false;
  /// The material does not bind the map being baked: its triangles write no texel and give the fit no
  /// sample; dilation fills their texels from the neighbours that have one, so no flat value bleeds
  /// into a neighbouring material's read-back.
  bool unread = false;
};

/// Makes the sampler of any triangle of one bake where a tile needs it: a sampler held for every
/// triangle at once (about 230 bytes each) would be the largest buffer of a bake of millions of
/// triangles, and one is made in far less time than its texels take to sample.
struct SamplerMaker {
  const std::vector<BakeTriangle>& triangles;
  std::vector<MaterialSampling> material;  // per input material, then one for no material (-1)
  SlotEncoding encoding = SlotEncoding::kData;
  const std::vector<NormalFrames>* frames = nullptr;  // kTangentNormal: one per triangle

  /// The sampler of triangle t.
  TriangleSampler operator()(uint32_t t) const {
    const BakeTriangle& tri = triangles[t];
    const MaterialSampling& m = tri.material >= 0 ? material[size_t(tri.material)] : material.back();
    TriangleSampler smp = TriangleSampler();  // zeroed, as a sampler left invalid by init has always been
    smp.init(tri, m.src, m.flat);
    smp.corner_samples = m.corner_samples;
    smp.unread = m.unread;
    smp.encoding = encoding;
    if (frames) smp.frames = &(*frames)[t];
    return smp;
  }
  /// The samplers of the triangles `tris`, in their order.
  std::vector<TriangleSampler> of(const std::vector<uint32_t>& tris) const {
    std::vector<TriangleSampler> samplers;
    samplers.reserve(tris.size());
    for (const uint32_t t : tris) samplers.push_back((*this)(t));
    return samplers;
  }
};

}  // namespace tightex
