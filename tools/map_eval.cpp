// The maps' evaluator (BENCHMARKS.md, "Every map"): for each map slot of an input and its
// tightex output, the surface PSNR (docs/metrics.md) against what an ideal re-sampler keeps at the
// output's own size and layout, and the normal maps' object-space angular error. Also makes the scan-like
// test models: the demo's vase with a hard-mask metallic channel and a tangent-space normal map whose
// normals tilt 20-30 degrees, and a textured scan (several atlas pages) with a packed
// occlusion-roughness-metallic image per page whose occlusion has fine dark creases, as an AO bake.
//
//   tightex_map_eval make-scan DEMO.obj OUTDIR      writes OUTDIR/scan_pbr.glb
//   tightex_map_eval make-orm-scan SCAN.obj OUTDIR [CREASE_TEXELS [DEPTH]]
//                                                   writes OUTDIR/scan_orm.glb (creases 6 texels, 0.4 deep)
//   tightex_map_eval compare INPUT OUTPUT          one table row per map, exit 1 when a check fails
//   tightex_map_eval crushed INPUT [RATIO]         where each map's error sits: triangles crushed RATIO:1 (20) or not
//
// The ideal re-sampler of `compare`: every texel of the output's map the box average of 4 x 4 bilinear
// samples of the input's map over its footprint (ideal_output). That of `crushed`: the same on a grid
// rotated 30 degrees at the input's own texel density, read back bilinearly.
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/eigen_vector.hpp"
#include "core/image.hpp"
#include "core/mesh.hpp"
#include "core/raster.hpp"
#include "core/tangents.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

using namespace tightex;

namespace {

constexpr double kRotation = 30.0 * M_PI / 180.0;
constexpr size_t kSamples = 200000;
constexpr uint64_t kSeed = 20240606;  // docs/metrics.md's surface PSNR seed

/// The ideal re-sampler's value of `img` at texture coordinates uv (8-bit levels, rounded as stored).
std::array<float, 4> ideal_resample(const Image& img, const Vec2& uv) {
  const Eigen::Rotation2Dd rot(kRotation);
  const Vec2 X(uv.x() * img.width, (1 - uv.y()) * img.height);  // input pixel units, texel centres at +0.5
  const Vec2 q = rot.inverse() * as_eigen(X);                   // rotated grid units
  const double gx = q.x() - 0.5, gy = q.y() - 0.5;
  const double fx = std::floor(gx), fy = std::floor(gy);
  const double tx = gx - fx, ty = gy - fy;
  std::array<float, 4> out{0, 0, 0, 0};
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const double w = (di ? tx : 1 - tx) * (dj ? ty : 1 - ty);
      std::array<float, 4> texel{0, 0, 0, 0};
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
          const Vec2 p = rot * Eigen::Vector2d(fx + di + (a + 0.5) / 4, fy + dj + (b + 0.5) / 4);
          const auto c = sample_bilinear(img, p.x() / img.width, 1 - p.y() / img.height);
          for (int k = 0; k < 4; ++k) texel[size_t(k)] += c[size_t(k)] / 16;
        }
      for (int k = 0; k < 4; ++k) out[size_t(k)] += float(w * std::round(texel[size_t(k)]));
    }
  return out;
}

/// The texture of slot (-1: base colour) of triangle t, or nullptr.
const Image* slot_image(const TexturedMesh& m, size_t t, int slot) {
  const int32_t mat = m.face_material[t];
  if (mat < 0) return nullptr;
  const int tex = slot < 0 ? m.materials[size_t(mat)].texture : m.materials[size_t(mat)].maps[size_t(slot)];
  return tex >= 0 && !m.textures[size_t(tex)].image.empty() ? &m.textures[size_t(tex)].image : nullptr;
}

/// The scan-like model's object-space normal at point p with surface normal n and tangent t: n tilted by
/// 20 to 30 degrees towards a direction that turns over the surface (smooth bumps about 0.3 units wide).
Vec3 tilted_normal(const Vec3& p, const Vec3& n, const Vec3& t) {
  const double tilt = (20 + 10 * (0.5 + 0.5 * std::sin(7.0 * p.x() + 3.0 * p.y()))) * M_PI / 180;
  const double turn = 2 * M_PI * (0.5 + 0.5 * std::sin(9.0 * p.y() - 5.0 * p.z() + 4.0 * p.x()));
  const Vec3 u = (t - n * n.dot(t)).normalized(), v = n.cross(u);
  return (std::cos(tilt) * n + std::sin(tilt) * (std::cos(turn) * u + std::sin(turn) * v)).normalized();
}

/// Each image of `images` (one size) grown `passes` texels from its `covered` texels into the rest.
void grow_gutters(std::vector<Image>& images, std::vector<uint8_t> covered, int passes = 4) {
  const int W = images[0].width, H = images[0].height;
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<uint8_t> next = covered;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (covered[size_t(y) * size_t(W) + size_t(x)]) continue;
        for (const auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= W || ny >= H || !covered[size_t(ny) * size_t(W) + size_t(nx)]) continue;
          for (Image& img : images) img.at(x, y) = img.at(nx, ny);
          next[size_t(y) * size_t(W) + size_t(x)] = 1;
          break;
        }
      }
    covered = std::move(next);
  }
}

/// One texel of a generated map: the values at barycentrics b of triangle t (surface point p, corner-
/// interpolated tangent T and normal N), one per generated image.
using Painter = std::function<void(size_t t, const Vec3& p, const Vec3& T, const Vec3& N, std::vector<Rgba8>& values)>;

/// Generated maps drawn through `m`'s atlas: per base colour texture (page), one image per `fill` entry
/// at the page's size, each covered texel from the surface point under it (`paint`), then gutters grown
/// 4 texels from the charts, as a scan's texturing tool pads them. Returns the images per texture index
/// (empty for a texture no material binds as its base colour).
std::vector<std::vector<Image>> paint_pages(const TexturedMesh& m, const std::vector<Rgba8>& fill, const Painter& paint) {
  const std::vector<Vec4> tg = compute_corner_tangents(m);
  std::vector<std::vector<Image>> maps(m.textures.size());
  std::vector<std::vector<uint8_t>> covered(m.textures.size());
  std::vector<Rgba8> values(fill.size());
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    const int32_t mat = m.face_material[t];
    const int tex = mat < 0 ? -1 : m.materials[size_t(mat)].texture;
    if (tex < 0) continue;
    const int W = m.textures[size_t(tex)].image.width, H = m.textures[size_t(tex)].image.height;
    if (maps[size_t(tex)].empty()) {
      for (const Rgba8& f : fill) maps[size_t(tex)].emplace_back(W, H, f);
      covered[size_t(tex)].assign(size_t(W) * size_t(H), 0);
    }
    Vec2 px[3];
    for (int k = 0; k < 3; ++k) px[k] = Vec2(m.sampled_uv(t, k).x() * W, (1 - m.sampled_uv(t, k).y()) * H);
    scan_triangle(px[0], px[1], px[2], 0, W, 0, H, EdgeRule::kInclusive, [&](long x, long y, double w0, double w1, double w2) {
      const double b[3] = {w0, w1, w2};
      Vec3 p = Vec3::Zero(), T = Vec3::Zero(), N = Vec3::Zero();
      for (int k = 0; k < 3; ++k)
        p += b[k] * m.positions[m.triangles[t][size_t(k)]], T += b[k] * tg[3 * t + size_t(k)].head<3>(), N += b[k] * frame_normal(m, t, k);
      paint(t, p, T, N, values);
      for (size_t i = 0; i < values.size(); ++i) maps[size_t(tex)][i].at(int(x), int(y)) = values[i];
      covered[size_t(tex)][size_t(y) * size_t(W) + size_t(x)] = 1;
    });
  }
  for (size_t tex = 0; tex < maps.size(); ++tex)
    if (!maps[tex].empty()) grow_gutters(maps[tex], covered[tex]);
  return maps;
}

/// The demo's vase with a metallic-roughness map (a hard-mask metallic in blue, a smooth roughness in
/// green) and a tangent-space normal map (tilted_normal), both drawn through its atlas at the colour's
/// size: each covered texel from the surface point under it.
int make_scan(const std::string& demo_obj, const std::string& outdir) {
  TexturedMesh m = read_obj(demo_obj);
  const std::vector<Vec4> tg = compute_corner_tangents(m);
  std::vector<std::vector<Image>> maps =
      paint_pages(m, {Rgba8{255, 128, 0, 255}, Rgba8{128, 128, 255, 255}},
                  [&](size_t t, const Vec3& p, const Vec3& T, const Vec3& N, std::vector<Rgba8>& v) {
                    const bool metal = std::sin(11.0 * p.x() + 2.0 * p.z()) * std::sin(13.0 * p.y()) > 0.2;
                    const double rough = 0.5 + 0.4 * std::sin(5.0 * p.y() + 3.0 * p.x());
                    v[0] = {255, uint8_t(std::lround(255 * rough)), uint8_t(metal ? 255 : 0), 255};
                    const Vec3 n = tilted_normal(p, N.normalized(), T);
                    Eigen::Matrix3d frame;
                    frame.col(0) = as_eigen(T), frame.col(1) = as_eigen(Vec3((tg[3 * t].w() < 0 ? -1.0 : 1.0) * N.cross(T))),
                    frame.col(2) = as_eigen(N);
                    const Vec3 e = Vec3(frame.fullPivLu().solve(as_eigen(n))).normalized();
                    auto q = [](double c) { return uint8_t(std::clamp(std::lround((c + 1) * 127.5), 0l, 255l)); };
                    v[1] = {q(e.x()), q(e.y()), q(e.z()), 255};
                  });
  for (Material& mat : m.materials) {
    mat.maps[size_t(MaterialSlot::kMetallicRoughness)] = int(m.textures.size());
    mat.maps[size_t(MaterialSlot::kNormal)] = int(m.textures.size()) + 1;
  }
  m.textures.push_back(Texture{"scan_pbr_metallic_roughness", std::move(maps[0][0])});
  m.textures.push_back(Texture{"scan_pbr_normal", std::move(maps[0][1])});
  m.textures[0].path = "scan_pbr_base_colour";
  m.source = "scan_pbr.obj";
  std::filesystem::create_directories(outdir);
  write_gltf(m, outdir, "scan_pbr", ImageFormat::kPng, GltfContainer::kGlb);
  return 0;
}

/// The mean 3D length of one input texel over `m`'s textured triangles: the root of the 3D area over
/// the texels the triangles cover.
double texel_length(const TexturedMesh& m) {
  double area3 = 0, texels = 0;
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    const Image* img = slot_image(m, t, -1);
    if (!img) continue;
    area3 += triangle_area(m.positions, m.triangles[t]);
    texels += std::abs(signed_area(m.sampled_uv(t, 0), m.sampled_uv(t, 1), m.sampled_uv(t, 2))) * img->width * img->height;
  }
  return texels > 0 ? std::sqrt(area3 / texels) : 1.0;
}

/// The dark creases of occlusion_at: half-width in input texels and depth (0-1 of white).
struct Creases {
  double width = 6, depth = 0.4;
};

/// A baked ambient occlusion's look at surface point p (L: one input texel's 3D length): bright, with
/// dark creases (`c`) along the zero set of a sum of three plane waves (about 40 texels apart; the
/// distance estimated as |f| / |grad f|, the gradient held off zero where the waves cancel) and a
/// broad darkening in hollows.
double occlusion_at(const Vec3& p, double L, Creases c) {
  const Vec3 k[3] = {Vec3(1.0, 0.3, -0.5), Vec3(-0.4, 1.0, 0.6), Vec3(0.5, -0.7, 1.0)};
  const double scale = 2 * M_PI / (40 * L);
  double f = 0;
  Vec3 grad = Vec3::Zero();
  for (const Vec3& ki : k) {
    const Vec3 kk = scale * ki.normalized();
    f += std::sin(kk.dot(p)), grad += kk * std::cos(kk.dot(p));
  }
  const double d = std::abs(f) / std::max(grad.norm(), 0.5 * scale) / (c.width * L);  // crease half-widths to the crease
  const double crease = c.depth * std::exp(-d * d);
  const double hollow = 0.15 * (0.5 + 0.5 * std::sin(scale / 9 * (p.x() + 2 * p.y() - p.z())));
  return std::clamp(1.0 - crease - hollow, 0.0, 1.0);
}

/// A textured scan (OBJ, one or several atlas pages) with a packed occlusion-roughness-metallic image
/// per page, bound as both occlusion (red: occlusion_at, fine dark creases) and metallic-roughness
/// (green: a smooth roughness, blue: a hard metallic mask, both some hundreds of texels across), drawn
/// through its atlas at each page's size: writes OUTDIR/scan_orm.glb.
int make_orm_scan(const std::string& obj, const std::string& outdir, Creases creases) {
  TexturedMesh m = read_obj(obj);
  const double L = texel_length(m), s = 2 * M_PI / (400 * L);
  std::vector<std::vector<Image>> maps =
      paint_pages(m, {Rgba8{255, 128, 0, 255}}, [&](size_t, const Vec3& p, const Vec3&, const Vec3&, std::vector<Rgba8>& v) {
        const bool metal = std::sin(s * (1.1 * p.x() + 0.2 * p.z())) * std::sin(s * 1.3 * p.y()) > 0.2;
        const double rough = 0.5 + 0.4 * std::sin(s * 0.5 * (p.y() + 0.6 * p.x()));
        v[0] = {uint8_t(std::lround(255 * occlusion_at(p, L, creases))), uint8_t(std::lround(255 * rough)), uint8_t(metal ? 255 : 0), 255};
      });
  const size_t colour_textures = m.textures.size();
  std::vector<int> orm_of(colour_textures, -1);
  for (size_t tex = 0; tex < colour_textures; ++tex) {
    if (maps[tex].empty()) continue;
    orm_of[tex] = int(m.textures.size());
    m.textures.push_back(Texture{"scan_orm_page" + std::to_string(tex) + "_orm", std::move(maps[tex][0])});
    m.textures[tex].path = "scan_orm_page" + std::to_string(tex) + "_base_colour";
  }
  for (Material& mat : m.materials)
    if (mat.texture >= 0 && orm_of[size_t(mat.texture)] >= 0)
      mat.maps[size_t(MaterialSlot::kOcclusion)] = mat.maps[size_t(MaterialSlot::kMetallicRoughness)] = orm_of[size_t(mat.texture)];
  m.source = "scan_orm.obj";
  std::filesystem::create_directories(outdir);
  write_gltf(m, outdir, "scan_orm", ImageFormat::kPng, GltfContainer::kGlb);
  return 0;
}

/// The texture of slot (-1: base colour) of triangle t, as an index of m.textures, or -1.
int slot_texture(const TexturedMesh& m, size_t t, int slot) {
  const int32_t mat = m.face_material[t];
  if (mat < 0) return -1;
  const int tex = slot < 0 ? m.materials[size_t(mat)].texture : m.materials[size_t(mat)].maps[size_t(slot)];
  return tex >= 0 && !m.textures[size_t(tex)].image.empty() ? tex : -1;
}

/// How texels take their values in paint_ideal_triangle: those whose centre the triangle covers, or
/// those it touches (at 4 x 4 points a texel) that no triangle's centre rule reached.
enum class TexelRule { kCentres, kTouched };

/// The ideal texels of input triangle t (image `src`) in `dst`, through output triangle q (corners
/// `corner`: the output corner of each input corner), by `rule`: each texel the box average of n x n
/// bilinear samples of `src` over its footprint, carried to the input's coordinates by the triangle's
/// affine map (so a triangle thinner than a texel still gives the texels it crosses its own values);
/// where the map is the identity at the same size, the input's texel itself. `covered` marks the
/// texels painted (1: by a centre, 2: touched).
void paint_ideal_triangle(const TexturedMesh& in, const TexturedMesh& out, size_t t, size_t q, const std::array<int, 3>& corner,
                          const Image& src, int n, TexelRule rule, Image& dst, std::vector<uint8_t>& covered) {
  const int W = dst.width, H = dst.height;
  Vec2 po[3], ui[3];
  bool identity = src.width == W && src.height == H;
  for (int k = 0; k < 3; ++k) {
    const Vec2 uo = out.sampled_uv(q, corner[size_t(k)]);
    ui[k] = in.sampled_uv(t, k), po[k] = Vec2(uo.x() * W, (1 - uo.y()) * H);
    identity = identity && (uo - ui[k]).norm() < 1e-7;
  }
  Eigen::Matrix2d edges;
  edges.col(0) = as_eigen(Vec2(po[1] - po[0])), edges.col(1) = as_eigen(Vec2(po[2] - po[0]));
  if (std::abs(edges.determinant()) < 1e-12) return;
  const Eigen::Matrix2d to_barycentric = edges.inverse();
  auto paint = [&](long x, long y) {
    if (identity) {
      dst.at(int(x), int(y)) = src.at(int(x), int(y));
      return;
    }
    std::array<double, 4> sum{0, 0, 0, 0};
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const Eigen::Vector2d w =
            to_barycentric * (Eigen::Vector2d(double(x) + (a + 0.5) / n, double(y) + (b + 0.5) / n) - as_eigen(po[0]));
        const Vec2 uv = ui[0] + w.x() * (ui[1] - ui[0]) + w.y() * (ui[2] - ui[0]);
        const auto c = sample_bilinear(src, uv.x(), uv.y());
        for (size_t k = 0; k < 4; ++k) sum[k] += c[k] / (n * n);
      }
    auto level = [](double v) { return uint8_t(std::clamp(std::lround(v), 0l, 255l)); };
    dst.at(int(x), int(y)) = {level(sum[0]), level(sum[1]), level(sum[2]), level(sum[3])};
  };
  if (rule == TexelRule::kCentres) {
    scan_triangle(po[0], po[1], po[2], 0, W, 0, H, EdgeRule::kInclusive, [&](long x, long y, double, double, double) {
      covered[size_t(y) * size_t(W) + size_t(x)] = 1;
      paint(x, y);
    });
    return;
  }
  constexpr int kTouch = 4;
  scan_triangle(kTouch * po[0], kTouch * po[1], kTouch * po[2], 0, kTouch * W, 0, kTouch * H, EdgeRule::kInclusive,
                [&](long sx, long sy, double, double, double) {
                  const long x = sx / kTouch, y = sy / kTouch;
                  if (covered[size_t(y) * size_t(W) + size_t(x)]) return;
                  covered[size_t(y) * size_t(W) + size_t(x)] = 2;
                  paint(x, y);
                });
}

/// A re-sampler at the output's density: `out` with the image of every slot but the normal maps (and
/// the base colour) replaced by one of the same size whose texels are the input's map re-sampled through
/// the output's coordinates (paint_ideal_triangle, n x n samples a texel), the texels no triangle
/// touches grown from the painted ones, as a bake pads its charts. An image two slots share becomes one
/// per slot.
TexturedMesh resampled_output(const TexturedMesh& in, const TexturedMesh& out, int n) {
  const TriangleMatch match = match_output_triangles(in, out);
  TexturedMesh ideal = out;
  std::map<std::pair<int, int>, size_t> ideal_of;  // (slot, output texture) -> texture of `ideal`
  std::vector<std::vector<uint8_t>> covered(out.textures.size());
  for (const TexelRule rule : {TexelRule::kCentres, TexelRule::kTouched})
    for (int slot = -1; slot < int(kMaterialSlots); ++slot) {
      if (slot >= 0 && slot_encoding(MaterialSlot(slot)) == SlotEncoding::kTangentNormal) continue;
      for (size_t t = 0; t < in.num_triangles(); ++t) {
        const uint32_t q = match.output_triangle[t];
        const Image* src = q == TriangleMatch::kNoOutputTriangle ? nullptr : slot_image(in, t, slot);
        const int J = src ? slot_texture(out, q, slot) : -1;
        if (J < 0) continue;
        const auto [it, fresh] = ideal_of.try_emplace({slot, J}, ideal.textures.size());
        if (fresh) {
          const Image& o = out.textures[size_t(J)].image;
          ideal.textures.push_back(out.textures[size_t(J)]);
          ideal.textures.back().image = Image(o.width, o.height);
          covered.emplace_back(size_t(o.width) * size_t(o.height), 0);
        }
        paint_ideal_triangle(in, out, t, q, match.output_corner[t], *src, n, rule, ideal.textures[it->second].image, covered[it->second]);
      }
    }
  for (const auto& [key, tex] : ideal_of) {
    std::vector<Image> one(1);
    std::swap(one[0], ideal.textures[tex].image);
    grow_gutters(one, covered[tex], 64);
    std::swap(one[0], ideal.textures[tex].image);
  }
  for (Material& mat : ideal.materials)
    for (int slot = -1; slot < int(kMaterialSlots); ++slot) {
      int& tex = slot < 0 ? mat.texture : mat.maps[size_t(slot)];
      if (const auto it = ideal_of.find({slot, tex}); tex >= 0 && it != ideal_of.end()) tex = int(it->second);
    }
  return ideal;
}

/// The ideal re-sampler's figures at the output's density: per slot (and the base colour, slot -1) the
/// better of a box filter (4 x 4 samples a texel, which keeps no alias) and a point sample (the
/// texel centre's, which keeps every edge sharp) through resampled_output, measured from the input as
/// docs/metrics.md defines.
std::map<int, double> ideal_psnr(const TexturedMesh& in, const TexturedMesh& out) {
  std::map<int, double> best;
  for (const int n : {4, 1}) {
    const TexturedMesh ideal = resampled_output(in, out, n);
    const double base = surface_psnr(in, ideal);
    best[-1] = std::max(best.count(-1) ? best[-1] : 0.0, base);
    for (const MaterialMapFigures& f : measure_material_maps(in, ideal))
      if (slot_encoding(f.slot) != SlotEncoding::kTangentNormal) best[int(f.slot)] = std::max(best[int(f.slot)], f.surface_psnr);
  }
  return best;
}

/// `compare INPUT OUTPUT`: each map of the output (and the base colour) against the ideal re-sampler at
/// the output's density (ideal_psnr), both measured from the input as docs/metrics.md defines (1,000,000
/// points, effective values). A map passes at most 1.5 dB below the ideal; a normal map with its median
/// angle under 2 and its P95 under 8 degrees.
int compare(const std::string& input_path, const std::string& output_path) {
  const TexturedMesh in = read_model(input_path), out = read_model(output_path);
  const Metrics m = measure(in, out);
  std::map<int, double> ideal = ideal_psnr(in, out);
  const std::string model = std::filesystem::path(input_path).filename().string();
  auto size_of = [&](int slot) {
    for (size_t t = 0; t < out.num_triangles(); ++t)
      if (const int J = slot_texture(out, t, slot); J >= 0)
        return std::to_string(out.textures[size_t(J)].image.width) + " x " + std::to_string(out.textures[size_t(J)].image.height);
    return std::string("-");
  };
  std::printf("| model | map | output size | ideal PSNR | tightex PSNR | margin | check |\n");
  const double ideal_base = ideal[-1];
  bool ok = m.lost_triangles == 0 && m.flipped == 0 && m.surface_psnr >= ideal_base - 1.5;
  std::printf("| %s | base_colour | %s | %.2f | %.2f | %+.2f | %s (lost %zu, flipped %zu) |\n", model.c_str(), size_of(-1).c_str(),
              ideal_base, m.surface_psnr, m.surface_psnr - ideal_base, ok ? "pass" : "FAIL", m.lost_triangles, m.flipped);
  for (const MaterialMapFigures& f : m.maps) {
    const char* name = material_slot_name(f.slot);
    if (slot_encoding(f.slot) == SlotEncoding::kTangentNormal) {
      const bool pass = f.angle_median < 2 && f.angle_p95 < 8;
      std::printf("| %s | %s (angle median / P95, deg) | %s | | %.2f / %.2f | | %s |\n", model.c_str(), name, size_of(int(f.slot)).c_str(),
                  f.angle_median, f.angle_p95, pass ? "pass" : "FAIL");
      ok = ok && pass;
      continue;
    }
    const double ideal_slot = ideal[int(f.slot)];
    const bool pass = f.surface_psnr >= ideal_slot - 1.5;
    std::printf("| %s | %s | %s | %.2f | %.2f | %+.2f | %s |\n", model.c_str(), name, size_of(int(f.slot)).c_str(), ideal_slot,
                f.surface_psnr, f.surface_psnr - ideal_slot, pass ? "pass" : "FAIL");
    ok = ok && pass;
  }
  return ok ? 0 : 1;
}

/// How much output triangle o's texture coordinates stretch one direction of its 3D surface against
/// the other: the ratio of the singular values of its map from 3D to texture space (1: no shear).
double anisotropy(const TexturedMesh& out, size_t o) {
  const Vec3 &a = out.positions[out.triangles[o][0]], &b = out.positions[out.triangles[o][1]], &c = out.positions[out.triangles[o][2]];
  const Vec3 e1 = (b - a).normalized(), e2 = (b - a).cross(c - a).normalized().cross(e1);
  Eigen::Matrix2d surface, texture;
  surface << (b - a).dot(e1), (c - a).dot(e1), (b - a).dot(e2), (c - a).dot(e2);
  const Vec2 t1 = out.sampled_uv(o, 1) - out.sampled_uv(o, 0), t2 = out.sampled_uv(o, 2) - out.sampled_uv(o, 0);
  texture.col(0) = as_eigen(t1), texture.col(1) = as_eigen(t2);
  const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(texture * surface.inverse()).singularValues();
  const double r = sv(0) / sv(1);
  return std::isfinite(r) ? r : 1e9;
}

/// The corner of input triangle t at output triangle o's corner k (the same position), or k.
int input_corner_of(const TexturedMesh& in, const TexturedMesh& out, size_t t, size_t o, int k) {
  for (int j = 0; j < 3; ++j)
    if ((out.positions[out.triangles[o][size_t(k)]] - in.positions[in.triangles[t][size_t(j)]]).norm() < 1e-9) return j;
  return k;
}

/// `crushed INPUT [RATIO]`: tightex's default run, every map at the base colour's size (--material-map-budget 0), and
/// where each map's error sits: at kSamples area-weighted points of the output, squared error split
/// between the triangles whose texture coordinates are crushed more than `limit`:1 (anisotropy) and the
/// rest, tightex's and the ideal re-sampler's, per slot over its channels.
int crushed(const std::string& input_path, double limit) {
  const TexturedMesh in = read_model(input_path);
  Options o;
  o.material_map_budget_db = 0, o.measure = false;  // size 0: the default budget
  const TexturedMesh out = optimize(in, o).output;
  std::vector<double> cdf(out.num_triangles()), ratio(out.num_triangles());
  double acc = 0, crushed_area = 0;
  for (size_t t = 0; t < out.num_triangles(); ++t) {
    const double a3 = triangle_area(out.positions, out.triangles[t]);
    cdf[t] = acc += a3, ratio[t] = anisotropy(out, t);
    if (ratio[t] > limit) crushed_area += a3;
  }
  std::printf("%s: output triangles crushed more than %g:1: %.2f%% of the area\n", input_path.c_str(), limit, 100 * crushed_area / acc);
  std::printf("| slot | PSNR crushed (ideal) | PSNR rest (ideal) | crushed share of the squared error |\n");
  for (int slot = -1; slot < int(kMaterialSlots); ++slot) {
    bool bound = slot < 0;
    for (const Material& mat : in.materials) bound |= slot >= 0 && mat.maps[size_t(slot)] >= 0;
    if (!bound || (slot >= 0 && slot_encoding(MaterialSlot(slot)) == SlotEncoding::kTangentNormal)) continue;
    const unsigned channels = slot < 0 ? 7u : material_slot_channels(MaterialSlot(slot));
    double se[2][2] = {{0, 0}, {0, 0}}, n[2] = {0, 0};  // [crushed][ours, ideal]
    std::mt19937_64 rng(kSeed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (size_t s = 0; s < kSamples; ++s) {
      const size_t q = std::min(out.num_triangles() - 1, size_t(std::upper_bound(cdf.begin(), cdf.end(), uni(rng) * acc) - cdf.begin()));
      double r1 = uni(rng), r2 = uni(rng);
      if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
      const double b[3] = {1 - r1 - r2, r1, r2};
      if (q >= out.input_triangle.size()) continue;
      const size_t t = out.input_triangle[q];
      const Image *io = slot_image(in, t, slot), *oo = slot_image(out, q, slot);
      if (!io || !oo) continue;
      Vec2 ui = Vec2::Zero(), uo = Vec2::Zero();
      for (int k = 0; k < 3; ++k) uo += b[k] * out.sampled_uv(q, k), ui += b[k] * in.sampled_uv(t, input_corner_of(in, out, t, q, k));
      const auto exact = sample_bilinear(*io, ui.x(), ui.y()), ours = sample_bilinear(*oo, uo.x(), uo.y()), ideal = ideal_resample(*io, ui);
      const int c = ratio[q] > limit;
      for (int k = 0; k < 3; ++k)
        if (channels & (1u << k)) {
          const double d0 = std::lround(ours[size_t(k)]) - std::lround(exact[size_t(k)]),
                       d1 = std::lround(ideal[size_t(k)]) - std::lround(exact[size_t(k)]);
          se[c][0] += d0 * d0, se[c][1] += d1 * d1, n[c] += 1;
        }
    }
    auto psnr = [](double e, double m) { return e > 0 && m > 0 ? 10 * std::log10(255.0 * 255.0 * m / e) : 99.0; };
    std::printf("| %s | %.1f (%.1f) | %.1f (%.1f) | %.0f%% |\n", slot < 0 ? "base_colour" : material_slot_name(MaterialSlot(slot)),
                psnr(se[1][0], n[1]), psnr(se[1][1], n[1]), psnr(se[0][0], n[0]), psnr(se[0][1], n[0]),
                100 * se[1][0] / std::max(se[0][0] + se[1][0], 1e-300));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 4 && std::string(argv[1]) == "compare") return compare(argv[2], argv[3]);
    if (argc == 4 && std::string(argv[1]) == "make-scan") return make_scan(argv[2], argv[3]);
    if ((argc == 3 || argc == 4) && std::string(argv[1]) == "crushed") return crushed(argv[2], argc == 4 ? std::stod(argv[3]) : 20.0);
    if (argc >= 4 && argc <= 6 && std::string(argv[1]) == "make-orm-scan") {
      Creases c;
      if (argc >= 5) c.width = std::stod(argv[4]);
      if (argc == 6) c.depth = std::stod(argv[5]);
      return make_orm_scan(argv[2], argv[3], c);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tightex_map_eval: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr,
               "usage: tightex_map_eval compare INPUT OUTPUT | make-scan DEMO.obj OUTDIR | make-orm-scan SCAN.obj OUTDIR [CREASE_TEXELS "
               "[DEPTH]] | crushed INPUT [RATIO]\n");
  return 2;
}
