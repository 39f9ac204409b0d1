#include "report/metrics.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <span>
#include <tuple>

#include "core/hash.hpp"
#include "core/image.hpp"
#include "core/large_buffer.hpp"
#include "core/raster.hpp"
#include "core/statistics.hpp"
#include "core/surface.hpp"
#include "core/tangents.hpp"
#include "layout/chart_orientation.hpp"

namespace tightex {

namespace {

/// Calls f(x, y) for every texel centre inside the UV triangle (edges included), in texel indices of a
/// W x H image before wrapping.
template <typename F>
void raster(const Vec2& a, const Vec2& b, const Vec2& c, int W, int H, F&& f) {
  const Vec2 p[3] = {{a.x() * W, (1 - a.y()) * H}, {b.x() * W, (1 - b.y()) * H}, {c.x() * W, (1 - c.y()) * H}};
  const double x0 = std::min({p[0].x(), p[1].x(), p[2].x()}), x1 = std::max({p[0].x(), p[1].x(), p[2].x()});
  const double y0 = std::min({p[0].y(), p[1].y(), p[2].y()}), y1 = std::max({p[0].y(), p[1].y(), p[2].y()});
  if (!(x1 - x0 <= 4.0 * W && y1 - y0 <= 4.0 * H)) return;  // absurd or non-finite span: a broken input triangle
  // So far out (a material's -o of 1e300) that its texel indices overflow: no texel a renderer can address.
  if (!(std::abs(x0) < 1e15 && std::abs(x1) < 1e15 && std::abs(y0) < 1e15 && std::abs(y1) < 1e15)) return;
  scan_triangle(p[0], p[1], p[2], long(std::floor(x0)) - 1, long(std::ceil(x1)) + 1, long(std::floor(y0)) - 1, long(std::ceil(y1)) + 1,
                EdgeRule::kInclusive, [&](long x, long y, double, double, double) { f(x, y); });
}

/// How many texels of a W x H image the UV triangles `tris` of `mesh` cover (texel centres inside a
/// triangle, edges included, wrapped as a renderer repeats), drawn on every core: a texel two
/// triangles share may be marked by both at once, so each mark is a relaxed atomic store.
size_t covered_texels(const TexturedMesh& mesh, const std::vector<size_t>& tris, int W, int H) {
  std::vector<uint8_t, LargeBufferAllocator<uint8_t>> cov(size_t(W) * size_t(H), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const size_t t = tris[k];
      raster(mesh.sampled_uv(t, 0), mesh.sampled_uv(t, 1), mesh.sampled_uv(t, 2), W, H, [&](long x, long y) {
        x %= W, y %= H;
        if (x < 0) x += W;
        if (y < 0) y += H;
        std::atomic_ref<uint8_t>(cov[size_t(y) * size_t(W) + size_t(x)]).store(1, std::memory_order_relaxed);
      });
    }
  });
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, cov.size(), size_t(1) << 20), size_t(0),
      [&](const tbb::blocked_range<size_t>& r, size_t n) {
        return n + size_t(std::count(cov.begin() + std::ptrdiff_t(r.begin()), cov.begin() + std::ptrdiff_t(r.end()), 1));
      },
      std::plus<>());
}

/// `stored` (an sRGB-encoded value on the 0..255 scale) times a linear `factor`, in linear light, back
/// on the 0..255 scale (docs/metrics.md: colour factors multiply in linear light).
double times_in_linear_light(double stored, double factor) {
  if (factor == 1.0) return stored;
  return linear_to_srgb(srgb_to_linear(std::clamp(stored / 255.0, 0.0, 1.0)) * factor) * 255.0;
}

/// The colour a viewer shows at `uv` (barycentrics `b` of its own corners) of triangle t
/// (docs/metrics.md, surface PSNR): its base colour texture read bilinearly, unrounded on the 0..255
/// scale, times the material's colour factor where the format multiplies it (glTF's baseColorFactor,
/// and COLOR_0 where the model has vertex colours, in linear light); without a texture the factor alone
/// (white without a material).
std::array<double, 3> shown_colour(const TexturedMesh& m, size_t t, const Vec2& uv, const double* b) {
  const int32_t mat = m.face_material[t];
  const Image* img = image_of(m, t);
  if (!img) {
    if (mat < 0) return {255, 255, 255};
    const auto& kd = m.materials[size_t(mat)].kd;
    return {linear_to_srgb(kd[0]) * 255, linear_to_srgb(kd[1]) * 255, linear_to_srgb(kd[2]) * 255};
  }
  const auto c = sample_bilinear(*img, uv.x(), uv.y());
  std::array<double, 3> shown{c[0], c[1], c[2]};
  const Material& material = m.materials[size_t(mat)];
  if (!material.kd_multiplies_texture) return shown;
  std::array<double, 3> factor = material.kd;
  if (!m.corner_color.empty() && !m.textures[size_t(material.texture)].from_vertex_colours)
    for (size_t k = 0; k < 3; ++k) {
      double linear = 0;  // COLOR_0 is linear; the mesh keeps it sRGB-encoded
      for (size_t corner = 0; corner < 3; ++corner) linear += b[corner] * srgb_to_linear(m.corner_color[3 * t + corner][k]);
      factor[k] *= linear;
    }
  for (size_t k = 0; k < 3; ++k) shown[k] = times_in_linear_light(shown[k], factor[k]);
  return shown;
}

}  // namespace

ModelFigures measure_texture_space(const TexturedMesh& mesh) {
  ModelFigures f;
  f.image_utilization.assign(mesh.textures.size(), 0.0);
  std::vector<std::vector<size_t>> tris(mesh.textures.size());
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const int tex = texture_of(mesh, t);
    if (tex >= 0) tris[size_t(tex)].push_back(t);
  }
  // A texture bound only as another map (MaterialSlot) shares the base colour's layout: not counted again.
  std::vector<uint8_t> map_only(mesh.textures.size(), 0);
  for (const Material& m : mesh.materials)
    for (int tex : m.maps)
      if (tex >= 0 && size_t(tex) < map_only.size()) map_only[size_t(tex)] = 1;
  for (const Material& m : mesh.materials)
    if (m.texture >= 0 && size_t(m.texture) < map_only.size()) map_only[size_t(m.texture)] = 0;
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    if (map_only[i]) continue;
    // Not a structured binding: clang 14 (the fuzz build) cannot capture one in the lambda below.
    const std::pair<int, int> size = texture_size(mesh, int(i));
    const int W = size.first, H = size.second;
    if (W <= 0 || H <= 0) continue;
    const size_t used = covered_texels(mesh, tris[i], W, H);
    f.image_utilization[i] = double(used) / (double(W) * double(H));
    f.used_texels += double(used);
    f.texels += size_t(W) * size_t(H);
  }
  f.utilization = f.texels ? f.used_texels / double(f.texels) : 0.0;
  return f;
}

namespace {

/// Chart of every triangle (union-find root): triangles joined through edges whose two endpoints have
/// the same uv, and the same image, on both sides. Adds the seam's 3D length to *seam when given.
std::vector<uint32_t> chart_ids(const TexturedMesh& m, const WeldedEdges& edges, double* seam) {
  const std::vector<uint32_t>& vid = edges.vertex;
  const std::vector<uint32_t>& by_ends = edges.by_ends;
  detail::UnionFind uf(m.num_triangles());
  auto uv_at = [&](uint32_t h, uint32_t v) {
    const uint32_t t = h / 3;
    for (int k = 0; k < 3; ++k)
      if (vid[m.triangles[t][k]] == v) return m.corner_uv[3 * t + size_t(k)];
    return Vec2(NAN, NAN);
  };
  edges.for_each_edge(m, [&](size_t i, size_t j) {
    const uint32_t a = edges.lower(m, by_ends[i]), b = edges.higher(m, by_ends[i]);
    bool differs = false;
    for (size_t k0 = i; k0 < j; ++k0)
      for (size_t k = k0 + 1; k < j; ++k) {
        const uint32_t h0 = by_ends[k0], h1 = by_ends[k];
        if (uv_at(h0, a) == uv_at(h1, a) && uv_at(h0, b) == uv_at(h1, b) && texture_of(m, h0 / 3) == texture_of(m, h1 / 3))
          uf.unite(h0 / 3, h1 / 3);
        else
          differs = true;
      }
    if (differs && seam) {
      const uint32_t h = by_ends[i];
      *seam += (m.positions[m.triangles[h / 3][h % 3]] - m.positions[m.triangles[h / 3][(h % 3 + 1) % 3]]).norm();
    }
  });
  std::vector<uint32_t> id(m.num_triangles());
  for (uint32_t t = 0; t < m.num_triangles(); ++t) id[t] = uf.find(t);
  return id;
}

}  // namespace

namespace {

/// count_charts, keeping the chart of every triangle in *ids (count_flips needs them too).
size_t count_charts(const TexturedMesh& m, const WeldedEdges& edges, double* seam_length, std::vector<uint32_t>* ids) {
  double seam = 0, area = 0;
  *ids = chart_ids(m, edges, &seam);
  const std::vector<uint32_t>& id = *ids;
  for (size_t t = 0; t < m.num_triangles(); ++t)
    area += triangle_area(m.positions[m.triangles[t][0]], m.positions[m.triangles[t][1]], m.positions[m.triangles[t][2]]);
  // Triangles without a texture (a scene's untextured parts) sample nothing: they make no chart.
  size_t charts = 0;
  for (uint32_t t = 0; t < m.num_triangles(); ++t) charts += id[t] == t && texture_of(m, t) >= 0;
  if (seam_length) *seam_length = area > 0 ? seam / std::sqrt(area) : 0;
  return charts;
}

}  // namespace

size_t count_charts(const TexturedMesh& m, const WeldedEdges& edges, double* seam_length) {
  std::vector<uint32_t> ids;
  return count_charts(m, edges, seam_length, &ids);
}

size_t count_charts(const TexturedMesh& m, double* seam_length) { return count_charts(m, welded_edges(m), seam_length); }

namespace {

/// The sorted triple of a triangle's corner positions (bit patterns), so that the same triangle is
/// found whatever its corner order and vertex numbering.
struct CornerKey {
  std::array<uint64_t, 10> v;  // the last: the source mesh, where both models have them
  auto operator<=>(const CornerKey&) const = default;
};

/// Whether every coordinate of m is a float32 value (a model read from glTF, which stores no other).
bool has_float32_positions(const TexturedMesh& m) {
  for (const Vec3& p : m.positions)
    for (int i = 0; i < 3; ++i)
      if (double(float(p[i])) != p[i] && std::isfinite(p[i])) return false;
  return true;
}

/// How two models' triangles are keyed: with `as_float32` the positions are rounded to float32 first
/// (a model written to a format that stores float32, glTF, keeps its positions as exactly as that
/// format can); with `by_source_mesh` the key holds the triangle's source mesh (both models have them:
/// two meshes of a scene with the same geometry are told apart).
struct KeyRules {
  bool as_float32 = false;
  bool by_source_mesh = false;
};

/// The key of triangle t of m; `order` (optional) gets its corners in key order.
CornerKey corner_key(const TexturedMesh& m, size_t t, const KeyRules& rules, std::array<int, 3>* order) {
  const bool as_float32 = rules.as_float32;
  std::array<int, 3> o{0, 1, 2};
  auto corner_bits = [&](int k) {
    const Vec3& p = m.positions[m.triangles[t][k]];
    auto coordinate = [&](int i) { return as_float32 ? double(float(p[i])) : p[i]; };
    return std::array<uint64_t, 3>{position_bits(coordinate(0)), position_bits(coordinate(1)), position_bits(coordinate(2))};
  };
  std::sort(o.begin(), o.end(), [&](int a, int b) { return corner_bits(a) < corner_bits(b); });
  CornerKey k;
  for (int i = 0; i < 3; ++i) {
    const auto b = corner_bits(o[i]);
    k.v[3 * i] = b[0], k.v[3 * i + 1] = b[1], k.v[3 * i + 2] = b[2];
  }
  k.v[9] = rules.by_source_mesh ? m.source_mesh[t] : 0;
  if (order) *order = o;
  return k;
}

/// docs/metrics.md "Correspondence": for each input triangle, the output triangle with the same three corner
/// positions and which of its corners each input corner is.
struct Correspondence {
  std::vector<uint32_t> match;                 // per input triangle: output triangle, kNone if none
  std::vector<std::array<int, 3>> corner_map;  // per input triangle: output corner of each input corner
  std::vector<double> area3;                   // per input triangle: its 3D area
  size_t lost_triangles = 0;                   // input triangles of non-zero area without a match
};

using KeyedTriangle = std::pair<CornerKey, uint32_t>;
using HashedTriangle = std::pair<uint64_t, uint32_t>;  // (hash of its CornerKey, triangle)

uint64_t hash_of(const CornerKey& k) {
  uint64_t h = 0;
  for (uint64_t word : k.v) h = splitmix64(h ^ word);
  return h;
}

/// Both sorted by their first members: for each run of equal first members in `in` that begins at i or
/// after and before `stop`, with the run of the same value in `out` (searched from o on), where there
/// is one, fn(in_begin, in_end, out_begin, out_end).
template <typename Pair, typename Fn>
void for_each_shared_run(std::span<const Pair> in, std::span<const Pair> out, size_t i, size_t stop, size_t o, Fn&& fn) {
  while (i < stop) {
    size_t i_end = i + 1;
    while (i_end < in.size() && in[i_end].first == in[i].first) ++i_end;
    while (o < out.size() && out[o].first < in[i].first) ++o;
    size_t o_end = o;
    while (o_end < out.size() && out[o_end].first == in[i].first) ++o_end;
    if (o_end > o) fn(i, i_end, o, o_end);
    i = i_end, o = o_end;
  }
}

/// Matches input triangles to output triangles, both sorted by (key, triangle): the k-th of an input
/// triangle's copies matches the k-th copy in the output, each output triangle at most once, so two
/// input copies need two in the output (the copies beyond the output's stay unmatched: lost).
void match_sorted(std::span<const KeyedTriangle> in_keys, std::span<const KeyedTriangle> out_keys, std::vector<uint32_t>& match) {
  for_each_shared_run(in_keys, out_keys, 0, in_keys.size(), 0, [&](size_t i, size_t i_end, size_t o, size_t o_end) {
    for (size_t k = i; k < i_end && o + (k - i) < o_end; ++k) match[in_keys[k].second] = out_keys[o + (k - i)].second;
  });
}

/// match_sorted for the input and output triangles whose keys hash alike (`in_run`, `out_run`, each in
/// triangle order). One and one, the usual case, are matched without comparing their keys: match_triangles
/// compares them after.
void match_hash_run(const TexturedMesh& in, const TexturedMesh& out, const KeyRules& rules, std::span<const HashedTriangle> in_run,
                    std::span<const HashedTriangle> out_run, std::vector<uint32_t>& match) {
  if (in_run.size() == 1 && out_run.size() == 1) {
    match[in_run[0].second] = out_run[0].second;
    return;
  }
  auto keyed = [&](const TexturedMesh& m, std::span<const HashedTriangle> run) {
    std::vector<KeyedTriangle> keys;
    keys.reserve(run.size());
    for (const auto& [hash, t] : run) keys.push_back({corner_key(m, t, rules, nullptr), t});
    std::sort(keys.begin(), keys.end());
    return keys;
  };
  match_sorted(keyed(in, in_run), keyed(out, out_run), match);
}

/// Positions compare exactly; where one model stores float32 (glTF) and the other does not, both are
/// rounded to float32 first.
Correspondence match_triangles(const TexturedMesh& in, const TexturedMesh& out) {
  // Both models' triangles sorted by the hash of their key (then index), on every core; each input run
  // of a hash is matched with the output's run of that hash, blocks of input runs on every core.
  const KeyRules rules{has_float32_positions(in) != has_float32_positions(out), !in.source_mesh.empty() && !out.source_mesh.empty()};
  auto sorted_hashes = [&](const TexturedMesh& m) {
    std::vector<HashedTriangle> hashes(m.num_triangles());
    tbb::parallel_for(uint32_t(0), uint32_t(m.num_triangles()), [&](uint32_t t) {
      hashes[t] = {hash_of(corner_key(m, t, rules, nullptr)), t};
    });
    tbb::parallel_sort(hashes.begin(), hashes.end());
    return hashes;
  };
  std::vector<HashedTriangle> in_h, out_h;
  tbb::parallel_invoke([&] { in_h = sorted_hashes(in); }, [&] { out_h = sorted_hashes(out); });
  Correspondence c;
  c.match.assign(in.num_triangles(), kNone);
  c.corner_map.resize(in.num_triangles());
  c.area3.resize(in.num_triangles());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, in_h.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    size_t i = r.begin();
    while (i > 0 && i < r.end() && in_h[i - 1].first == in_h[i].first) ++i;  // a run begun before the block is the earlier block's
    if (i >= r.end()) return;
    auto before = [](const HashedTriangle& a, uint64_t h) { return a.first < h; };
    const auto o = size_t(std::lower_bound(out_h.begin(), out_h.end(), in_h[i].first, before) - out_h.begin());
    const std::span<const HashedTriangle> in_s(in_h), out_s(out_h);
    for_each_shared_run(in_s, out_s, i, r.end(), o, [&](size_t i0, size_t i1, size_t o0, size_t o1) {
      match_hash_run(in, out, rules, in_s.subspan(i0, i1 - i0), out_s.subspan(o0, o1 - o0), c.match);
    });
  });
  std::vector<char> lost(in.num_triangles(), 0);
  tbb::parallel_for(uint32_t(0), uint32_t(in.num_triangles()), [&](uint32_t t) {
    c.area3[t] = triangle_area(in.positions, in.triangles[t]);
    if (c.match[t] != kNone) {
      // Equal keys, unless the hashes of two different keys met (then no output triangle has t's key).
      std::array<int, 3> oi, oo;
      if (corner_key(in, t, rules, &oi) == corner_key(out, c.match[t], rules, &oo))
        for (size_t i = 0; i < 3; ++i) c.corner_map[t][size_t(oi[i])] = oo[i];
      else
        c.match[t] = kNone;
    }
    lost[t] = c.match[t] == kNone && c.area3[t] > 0;
  });
  c.lost_triangles = size_t(std::count(lost.begin(), lost.end(), 1));
  return c;
}

/// docs/metrics.md "flipped" and "degenerate": UV signed area against the majority sign of its chart
/// (`chart`: chart_ids of out).
void count_flips(const TexturedMesh& out, const std::vector<uint32_t>& chart, size_t* flipped, size_t* degenerate) {
  std::vector<double> sa(out.num_triangles());
  tbb::parallel_for(size_t(0), sa.size(),
                    [&](size_t t) { sa[t] = signed_area(out.corner_uv[3 * t], out.corner_uv[3 * t + 1], out.corner_uv[3 * t + 2]); });
  std::vector<long> balance(out.num_triangles(), 0);  // per chart (its root triangle)
  for (uint32_t t = 0; t < out.num_triangles(); ++t)
    if (sa[t] != 0) balance[chart[t]] += sa[t] > 0 ? 1 : -1;
  for (uint32_t t = 0; t < out.num_triangles(); ++t) {
    if (texture_of(out, t) < 0) continue;  // untextured: its texture coordinates read nothing
    if (sa[t] == 0) {
      *degenerate += triangle_area(out.positions, out.triangles[t]) > 0;
      continue;
    }
    const long b = balance[chart[t]];
    if ((b >= 0 && sa[t] < 0) || (b < 0 && sa[t] > 0)) ++*flipped;
  }
}

/// Per triangle of `out`, whether it repeats an earlier triangle exactly: the same image and texture
/// coordinates at the same three corner positions (an input's repeated triangle, written as a copy of
/// the one it repeats). One surface twice, not two surfaces on one texel.
std::vector<char> exact_repeats(const TexturedMesh& out) {
  auto key_of = [&](size_t t) {
    uint64_t h = splitmix64(uint64_t(int64_t(texture_of(out, t))));
    for (size_t k = 0; k < 3; ++k) {
      const Vec2 uv = out.corner_uv[3 * t + k];
      const Vec3& p = out.positions[out.triangles[t][k]];
      for (const double x : {uv.x(), uv.y(), p.x(), p.y(), p.z()}) h = splitmix64(h ^ position_bits(x));
    }
    return h;
  };
  std::vector<std::pair<uint64_t, uint32_t>> keys(out.num_triangles());
  tbb::parallel_for(uint32_t(0), uint32_t(keys.size()), [&](uint32_t t) { keys[t] = {key_of(t), t}; });
  tbb::parallel_sort(keys.begin(), keys.end());
  auto same = [&](uint32_t a, uint32_t b) {
    if (texture_of(out, a) != texture_of(out, b)) return false;
    for (size_t k = 0; k < 3; ++k)
      if (out.corner_uv[3 * a + k] != out.corner_uv[3 * b + k] || out.positions[out.triangles[a][k]] != out.positions[out.triangles[b][k]])
        return false;
    return true;
  };
  std::vector<char> repeat(out.num_triangles(), 0);
  for (size_t i = 1; i < keys.size(); ++i)
    for (size_t j = i; j-- > 0 && keys[j].first == keys[i].first;)
      if (!repeat[keys[j].second] && same(keys[j].second, keys[i].second)) {
        repeat[keys[i].second] = 1;
        break;
      }
  return repeat;
}

/// docs/metrics.md "overlap": texel centres covered by two or more triangles of the same image; a centre
/// exactly on a shared edge is counted for one triangle only (top-left rule via a half-open test). An
/// exact repeat of a triangle (exact_repeats) is that triangle again, not an overlap.
double overlap_fraction(const TexturedMesh& out) {
  size_t overlapped = 0, total = 0;
  const std::vector<char> repeat = exact_repeats(out);
  std::vector<std::vector<size_t>> tris(out.textures.size());
  for (size_t t = 0; t < out.num_triangles(); ++t)
    if (texture_of(out, t) >= 0 && !repeat[t]) tris[size_t(texture_of(out, t))].push_back(t);
  for (size_t i = 0; i < out.textures.size(); ++i) {
    const Image& img = out.textures[i].image;
    if (img.empty()) continue;
    const int W = img.width, H = img.height;
    std::vector<uint8_t, LargeBufferAllocator<uint8_t>> cnt(size_t(W) * size_t(H), 0);
    for (size_t t : tris[i]) {
      const Vec2 uv[3] = {out.sampled_uv(t, 0), out.sampled_uv(t, 1), out.sampled_uv(t, 2)};
      const Vec2 p[3] = {{uv[0].x() * W, (1 - uv[0].y()) * H}, {uv[1].x() * W, (1 - uv[1].y()) * H}, {uv[2].x() * W, (1 - uv[2].y()) * H}};
      scan_triangle(p[0], p[1], p[2], 0, W, 0, H, EdgeRule::kTopLeft, [&](long x, long y, double, double, double) {
        uint8_t& c = cnt[size_t(y) * size_t(W) + size_t(x)];
        if (c < 2) c++;
      });
    }
    for (uint8_t c : cnt) {
      total += c > 0;
      overlapped += c > 1;
    }
  }
  return total ? double(overlapped) / double(total) : 0.0;
}

/// Width and height in texels of the image output triangle o samples (1 x 1 without one).
std::pair<double, double> texel_scale(const TexturedMesh& out, uint32_t o) {
  const Image* oi = image_of(out, o);
  return {oi ? oi->width : 1, oi ? oi->height : 1};
}

struct DensityFigures {
  Quantiles spread;
  double detail_loss_area = 0;
};

/// docs/metrics.md "density spread" and "detail loss area" over the matched input triangles of non-zero area.
DensityFigures measure_density(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c) {
  // Each triangle's densities on every core; the sums in triangle order, as one loop adds them.
  std::vector<double> dens(in.num_triangles(), 0), din(in.num_triangles(), 0), texels(in.num_triangles(), 0);
  auto counted = [&](uint32_t t) { return c.match[t] != kNone && c.area3[t] > 0; };
  tbb::parallel_for(uint32_t(0), uint32_t(in.num_triangles()), [&](uint32_t t) {
    if (!counted(t)) return;
    const uint32_t o = c.match[t];
    const Image* ii = image_of(in, t);
    const auto [Wo, Ho] = texel_scale(out, o);
    texels[t] = std::abs(signed_area(out.sampled_uv(o, 0), out.sampled_uv(o, 1), out.sampled_uv(o, 2))) * Wo * Ho;
    dens[t] = texels[t] / c.area3[t];
    if (ii)
      din[t] = std::abs(signed_area(in.sampled_uv(t, 0), in.sampled_uv(t, 1), in.sampled_uv(t, 2))) * ii->width * ii->height / c.area3[t];
  });
  double sum_at = 0, sum_a3 = 0, loss = 0;
  for (uint32_t t = 0; t < in.num_triangles(); ++t)
    if (counted(t)) sum_at += texels[t], sum_a3 += c.area3[t];
  const double mean = sum_a3 > 0 ? sum_at / sum_a3 : 1;
  std::vector<std::pair<double, double>> logd;
  for (uint32_t t = 0; t < in.num_triangles(); ++t) {
    if (!counted(t)) continue;
    logd.push_back({dens[t] > 0 ? std::log2(dens[t] / mean) : -60.0, c.area3[t]});
    if (din[t] > 0 && dens[t] < 0.5 * din[t]) loss += c.area3[t];
  }
  DensityFigures f;
  f.spread = {weighted_quantile(logd, 0.05), weighted_quantile(logd, 0.5), weighted_quantile(logd, 0.95)};
  f.detail_loss_area = sum_a3 > 0 ? loss / sum_a3 : 0;
  return f;
}

/// sigma_max / sigma_min of the Jacobian from input triangle t's 3D plane (a local frame) to the output
/// triangle o's texels; 1e12 where it collapses.
double singular_value_ratio(const TexturedMesh& in, size_t t, const TexturedMesh& out, uint32_t o, const std::array<int, 3>& cm) {
  const auto [Wo, Ho] = texel_scale(out, o);
  const Vec3 &p0 = in.positions[in.triangles[t][0]], &p1 = in.positions[in.triangles[t][1]], &p2 = in.positions[in.triangles[t][2]];
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const Vec3 x = e1.normalized(), n = e1.cross(e2).normalized(), y = n.cross(x);
  Eigen::Matrix2d P;
  P << e1.dot(x), e2.dot(x), e1.dot(y), e2.dot(y);
  const Vec2 q0 = out.sampled_uv(o, cm[0]), q1 = out.sampled_uv(o, cm[1]), q2 = out.sampled_uv(o, cm[2]);
  Eigen::Matrix2d U;
  U << (q1.x() - q0.x()) * Wo, (q2.x() - q0.x()) * Wo, (q1.y() - q0.y()) * Ho, (q2.y() - q0.y()) * Ho;
  const Eigen::Matrix2d J = U * P.inverse();
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(J);
  const double smax = svd.singularValues()(0), smin = svd.singularValues()(1);
  return smin > 0 ? smax / smin : 1e12;
}

/// docs/metrics.md "angle distortion": area-weighted mean and P95 of the singular value ratio over the
/// matched input triangles of non-zero area (the mean is over all of their area).
std::pair<double, double> measure_angle_distortion(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c) {
  // The ratios on every core; the sums in triangle order.
  std::vector<double> ratio(in.num_triangles(), 0);
  tbb::parallel_for(uint32_t(0), uint32_t(in.num_triangles()), [&](uint32_t t) {
    if (c.match[t] != kNone && c.area3[t] > 0) ratio[t] = singular_value_ratio(in, t, out, c.match[t], c.corner_map[t]);
  });
  std::vector<std::pair<double, double>> angle;
  double area_total = 0, angle_sum = 0;
  for (uint32_t t = 0; t < in.num_triangles(); ++t) {
    if (c.match[t] == kNone || c.area3[t] <= 0) continue;
    if (std::isfinite(ratio[t])) {
      angle.push_back({ratio[t], c.area3[t]});
      angle_sum += ratio[t] * c.area3[t];
    }
    area_total += c.area3[t];
  }
  return {area_total > 0 ? angle_sum / area_total : 0, weighted_quantile(angle, 0.95)};
}

/// The angle in degrees (0..45) between direction d and the nearest axis; NaN for a zero direction.
double folded_axis_angle(const Vec2& d) {
  if (!(d.squaredNorm() > 0)) return NAN;
  const double a = std::fmod(std::abs(std::atan2(d.y(), d.x())) * 180 / M_PI, 90.0);
  return std::min(a, 90.0 - a);
}

/// docs/metrics.md "texture axes angle": area-weighted mean and quantiles over the matched input
/// triangles of non-zero area that sample an image and have texture area on both sides.
std::pair<double, Quantiles> measure_axes_angle(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c) {
  std::vector<double> angle(in.num_triangles(), NAN);
  tbb::parallel_for(uint32_t(0), uint32_t(in.num_triangles()), [&](uint32_t t) {
    const Image* ii = image_of(in, t);
    if (c.match[t] == kNone || !(c.area3[t] > 0) || !ii) return;
    const uint32_t o = c.match[t];
    const auto [Wo, Ho] = texel_scale(out, o);
    std::array<Vec2, 3> uv_in, uv_out;
    for (size_t k = 0; k < 3; ++k) uv_in[k] = in.sampled_uv(t, int(k)), uv_out[k] = out.sampled_uv(o, c.corner_map[t][k]);
    angle[t] = texture_axes_angle(uv_in, Vec2(ii->width, ii->height), uv_out, Vec2(Wo, Ho));
  });
  std::vector<std::pair<double, double>> weighted;
  double sum = 0, area = 0;
  for (uint32_t t = 0; t < in.num_triangles(); ++t)
    if (std::isfinite(angle[t])) weighted.push_back({angle[t], c.area3[t]}), sum += angle[t] * c.area3[t], area += c.area3[t];
  if (weighted.empty()) return {0.0, Quantiles{}};
  return {sum / area, Quantiles{weighted_quantile(weighted, 0.05), weighted_quantile(weighted, 0.5), weighted_quantile(weighted, 0.95)}};
}

/// Seed of the surface PSNR's sample points: the same points in every run.
constexpr uint64_t kPsnrSeed = 20240606;

/// A point of the surface PSNR: input triangle t, barycentrics b of its own corners.
struct SurfacePoint {
  uint32_t t = 0;
  double b[3] = {0, 0, 0};
};

/// docs/metrics.md's sample points: `samples` points uniform by area on the input (fixed seed, so the same
/// points in every run), shared by the surface PSNR and every map's figures.
std::vector<SurfacePoint> surface_points(const TexturedMesh& in, const Correspondence& c, size_t samples) {
  std::vector<double> cdf(in.num_triangles());
  double acc = 0;
  // A scene's meshes by the area it shows of them (TexturedMesh::source_mesh_area_scale).
  const bool scaled = !in.source_mesh_area_scale.empty() && !in.source_mesh.empty();
  for (size_t t = 0; t < in.num_triangles(); ++t)
    cdf[t] = acc += c.area3[t] * (scaled ? in.source_mesh_area_scale[in.source_mesh[t]] : 1.0);
  std::mt19937_64 rng(kPsnrSeed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<SurfacePoint> points;
  points.reserve(acc > 0 ? samples : 0);
  // Stratified: the s-th point falls in the s-th of `samples` equal slices of the area, at a random
  // place within it. Each point is still uniform by area; the figure varies far less with the seed
  // (a map whose error lies on a small part of the surface: 0.7 dB between two seeds at 1,000,000
  // plain random points on WaterBottle's emissive).
  // The picks rise with s, so the triangle under each is found by walking the cumulative areas once
  // (the first whose sum exceeds the pick: std::upper_bound's answer).
  size_t t = 0;
  for (size_t s = 0; s < samples && acc > 0; ++s) {
    const double pick = (double(s) + uni(rng)) / double(samples) * acc;
    while (t < cdf.size() && !(pick < cdf[t])) ++t;
    double r1 = uni(rng), r2 = uni(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    if (t < in.num_triangles()) points.push_back({uint32_t(t), {1 - r1 - r2, r1, r2}});
  }
  return points;
}

/// Sums f(i) over [0, n) on every core in blocks of a fixed size, the blocks' sums added in order: the
/// same total in every run, whatever the threads.
template <typename F>
double deterministic_sum(size_t n, F&& f) {
  constexpr size_t kBlock = 4096;
  std::vector<double> block((n + kBlock - 1) / kBlock, 0.0);
  tbb::parallel_for(size_t(0), block.size(), [&](size_t b) {
    double sum = 0;
    for (size_t i = b * kBlock, end = std::min(n, i + kBlock); i < end; ++i) sum += f(i);
    block[b] = sum;
  });
  double total = 0;
  for (const double x : block) total += x;
  return total;
}

/// PSNR in dB of a mean squared error on the 0..255 scale (99 for none).
double psnr_of(double se, double n) {
  const double mse = n > 0 ? se / n : 0;
  return mse > 0 ? std::min(99.0, 10 * std::log10(255.0 * 255.0 / mse)) : 99.0;
}

/// Where a sample point lies in the output: the matched triangle (kNone if lost), its own barycentrics
/// and its texture coordinates there.
struct OutputPoint {
  uint32_t o = kNone;
  double b[3] = {0, 0, 0};
  Vec2 uv{0, 0};
};

/// The point at barycentrics b (in its input triangle's corner order) of output triangle o (kNone: lost),
/// whose corner corner[k] is input corner k.
template <typename Corners>
OutputPoint point_in_output(const TexturedMesh& out, uint32_t o, const Corners& corner, const double* b) {
  OutputPoint q;
  q.o = o;
  if (q.o == kNone) return q;
  for (size_t k = 0; k < 3; ++k) {
    const int ok = int(corner[k]);
    q.b[ok] = b[k];
    q.uv += b[k] * out.sampled_uv(q.o, ok);
  }
  return q;
}

OutputPoint output_point(const TexturedMesh& out, const Correspondence& c, const SurfacePoint& p) {
  return point_in_output(out, c.match[p.t], c.corner_map[p.t], p.b);
}

/// A sample point's squared error in the surface PSNR: the input's shown colour `in_colour` against the
/// output's at q (black where the point is lost), summed over the three channels.
double squared_colour_error(const std::array<double, 3>& in_colour, const TexturedMesh& out, const OutputPoint& q) {
  const auto co = q.o == kNone ? std::array<double, 3>{0, 0, 0} : shown_colour(out, q.o, q.uv, q.b);
  double sum = 0;
  for (size_t k = 0; k < 3; ++k) sum += (in_colour[k] - co[k]) * (in_colour[k] - co[k]);
  return sum;
}

Vec2 input_uv(const TexturedMesh& in, const SurfacePoint& p) {
  return p.b[0] * in.sampled_uv(p.t, 0) + p.b[1] * in.sampled_uv(p.t, 1) + p.b[2] * in.sampled_uv(p.t, 2);
}

/// docs/metrics.md "surface PSNR" at `points`: the colour a viewer shows of the input (shown_colour) against
/// the output's at the same barycentric point of the matched triangle (black if lost), unrounded.
/// Returns the PSNR in dB (99 for no error) and the number of points.
std::pair<double, size_t> measure_surface_psnr(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c,
                                               const std::vector<SurfacePoint>& points) {
  const double se = deterministic_sum(points.size(), [&](size_t i) {
    return squared_colour_error(shown_colour(in, points[i].t, input_uv(in, points[i]), points[i].b), out, output_point(out, c, points[i]));
  });
  return {psnr_of(se, 3.0 * double(points.size())), points.size()};
}

/// The image triangle t of `m` binds in `slot`; nullptr when none (or not loaded).
const Image* map_image_of(const TexturedMesh& m, size_t t, MaterialSlot slot) {
  const int32_t mat = m.face_material[t];
  if (mat < 0) return nullptr;
  const int tex = m.materials[size_t(mat)].maps[size_t(slot)];
  if (tex < 0 || m.textures[size_t(tex)].image.empty()) return nullptr;
  return &m.textures[size_t(tex)].image;
}

/// The slot's factor for triangle t (glTF's defaults without a material).
const SlotFactor& factor_of(const TexturedMesh& m, size_t t, MaterialSlot slot) {
  static const std::array<SlotFactor, kMaterialSlots> kDefaults = default_slot_factors();
  const int32_t mat = m.face_material[t];
  return mat < 0 ? kDefaults[size_t(slot)] : m.materials[size_t(mat)].factor[size_t(slot)];
}

/// The effective value of `slot` at `uv` of triangle t (docs/metrics.md, per-map PSNR), per channel on
/// the 0..255 scale: the stored value read bilinearly, unrounded, times the slot's factor (colour slots
/// in linear light); without a texture in the slot, the factor alone (255 times it).
std::array<double, 4> effective_value(const TexturedMesh& m, size_t t, const Vec2& uv, MaterialSlot slot) {
  const SlotFactor& f = factor_of(m, t, slot);
  const Image* img = map_image_of(m, t, slot);
  std::array<double, 4> v{255, 255, 255, 255};
  if (img) {
    const auto c = sample_bilinear(*img, uv.x(), uv.y());
    v = {c[0], c[1], c[2], c[3]};
  }
  const bool colour = slot_encoding(slot) == SlotEncoding::kSrgbColour;
  for (size_t k = 0; k < 4; ++k) v[k] = colour && k < 3 ? times_in_linear_light(v[k], f[k]) : v[k] * f[k];
  return v;
}

/// The object-space normal a viewer shades with at barycentrics b of triangle t (docs/metrics.md,
/// normal angular error): the tangent-space normal of `slot`'s image decoded through the corner
/// tangents, x and y scaled by the slot's scale; without a normal map, the interpolated vertex normal.
Vec3 shown_normal(const TexturedMesh& m, size_t t, const double* b, const Vec2& uv, const std::vector<Vec4>& tangents, MaterialSlot slot) {
  Vec3 tangent = Vec3::Zero(), normal = Vec3::Zero();
  for (int k = 0; k < 3; ++k) tangent += b[k] * tangents[3 * t + size_t(k)].head<3>(), normal += b[k] * frame_normal(m, t, k);
  const Image* img = map_image_of(m, t, slot);
  if (!img) return normal.norm() > 0 ? Vec3(normal.normalized()) : normal;
  const Vec3 bitangent = (tangents[3 * t].w() < 0 ? -1.0 : 1.0) * normal.cross(tangent);
  const auto c = sample_bilinear(*img, uv.x(), uv.y());
  const double scale = factor_of(m, t, slot)[0];
  const Vec3 n = scale * (c[0] / 127.5 - 1) * tangent + scale * (c[1] / 127.5 - 1) * bitangent + (c[2] / 127.5 - 1) * normal;
  return n.norm() > 0 ? Vec3(n.normalized()) : Vec3(normal.normalized());
}

/// One slot's MaterialMapFigures at every sample point (every face of the model counts: a face
/// without the slot shows its factor alone).
MaterialMapFigures measure_map_slot(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c, MaterialSlot slot,
                                    const std::vector<SurfacePoint>& points, const std::vector<Vec4>& in_tangents,
                                    const std::vector<Vec4>& out_tangents) {
  MaterialMapFigures f;
  f.slot = slot;
  f.samples = points.size();
  if (slot_encoding(slot) == SlotEncoding::kTangentNormal) {
    std::vector<double> angles(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
      const SurfacePoint& p = points[i];
      const Vec3 ni = shown_normal(in, p.t, p.b, input_uv(in, p), in_tangents, slot);
      const OutputPoint q = output_point(out, c, p);
      const Vec3 no = q.o == kNone ? Vec3(-ni) : shown_normal(out, q.o, q.b, q.uv, out_tangents, slot);
      angles[i] = std::acos(std::clamp(ni.dot(no), -1.0, 1.0)) * 180 / M_PI;
    });
    if (angles.empty()) return f;
    f.angle_mean = deterministic_sum(angles.size(), [&](size_t i) { return angles[i]; }) / double(angles.size());
    std::sort(angles.begin(), angles.end());
    f.angle_median = angles[angles.size() / 2];
    f.angle_p95 = angles[std::min(angles.size() - 1, size_t(0.95 * double(angles.size())))];
    return f;
  }
  const unsigned channels = material_slot_channels(slot);
  const double se = deterministic_sum(points.size(), [&](size_t i) {
    const SurfacePoint& p = points[i];
    const auto vi = effective_value(in, p.t, input_uv(in, p), slot);
    const OutputPoint q = output_point(out, c, p);
    const auto vo = q.o == kNone ? std::array<double, 4>{0, 0, 0, 0} : effective_value(out, q.o, q.uv, slot);
    double sum = 0;
    for (size_t k = 0; k < 4; ++k)
      if (channels & (1u << k)) sum += (vi[k] - vo[k]) * (vi[k] - vo[k]);
    return sum;
  });
  f.surface_psnr = psnr_of(se, double(std::popcount(channels)) * double(points.size()));
  return f;
}

/// Whether some material of m binds `slot` to a loaded image.
bool binds(const TexturedMesh& m, MaterialSlot slot) {
  for (const Material& mat : m.materials)
    if (mat.maps[size_t(slot)] >= 0 && !m.textures[size_t(mat.maps[size_t(slot)])].image.empty()) return true;
  return false;
}

/// The figures of every slot that some material of either model binds.
std::vector<MaterialMapFigures> measure_material_maps(const TexturedMesh& in, const TexturedMesh& out, const Correspondence& c,
                                                      const std::vector<SurfacePoint>& points) {
  std::vector<MaterialMapFigures> figures;
  std::vector<Vec4> in_tangents, out_tangents;
  for (size_t s = 0; s < kMaterialSlots; ++s) {
    const MaterialSlot slot = MaterialSlot(s);
    if (!binds(in, slot) && !binds(out, slot)) continue;
    if (slot_encoding(slot) == SlotEncoding::kTangentNormal && in_tangents.empty())
      in_tangents = completed_corner_tangents(in), out_tangents = completed_corner_tangents(out);
    figures.push_back(measure_map_slot(in, out, c, slot, points, in_tangents, out_tangents));
  }
  return figures;
}

}  // namespace

Metrics measure(const TexturedMesh& in, const TexturedMesh& out, size_t psnr_samples) {
  WeldedEdges in_edges, out_edges;
  tbb::parallel_invoke([&] { in_edges = welded_edges(in); }, [&] { out_edges = welded_edges(out); });
  return measure(in, out, in_edges, out_edges, psnr_samples);
}

Metrics measure(const TexturedMesh& in, const TexturedMesh& out, const WeldedEdges& in_edges, const WeldedEdges& out_edges,
                size_t psnr_samples) {
  Metrics r;
  std::vector<uint32_t> out_chart;
  tbb::parallel_invoke([&] { r.input = measure_texture_space(in); }, [&] { r.output = measure_texture_space(out); },
                       [&] { r.charts_input = count_charts(in, in_edges, &r.seam_length_input); },
                       [&] { r.charts = count_charts(out, out_edges, &r.seam_length, &out_chart); });
  const Correspondence c = match_triangles(in, out);
  r.lost_triangles = c.lost_triangles;
  const std::vector<SurfacePoint> points = surface_points(in, c, psnr_samples);
  tbb::parallel_invoke([&] { count_flips(out, out_chart, &r.flipped, &r.degenerate); }, [&] { r.overlap = overlap_fraction(out); },
                       [&] {
                         const DensityFigures d = measure_density(in, out, c);
                         r.density_spread = d.spread;
                         r.detail_loss_area = d.detail_loss_area;
                       },
                       [&] { std::tie(r.angle_distortion_mean, r.angle_distortion_p95) = measure_angle_distortion(in, out, c); },
                       [&] { std::tie(r.axes_angle_mean, r.axes_angle) = measure_axes_angle(in, out, c); },
                       [&] { std::tie(r.surface_psnr, r.psnr_samples) = measure_surface_psnr(in, out, c, points); },
                       [&] { r.maps = measure_material_maps(in, out, c, points); });
  return r;
}

double texture_axes_angle(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels, const std::array<Vec2, 3>& out_uv,
                          const Vec2& out_texels) {
  const auto axes = texel_axes_images(in_uv, in_texels, out_uv, out_texels);
  if (!axes) return NAN;
  return 0.5 * (folded_axis_angle((*axes)[0]) + folded_axis_angle((*axes)[1]));
}

double surface_psnr(const TexturedMesh& in, const TexturedMesh& out, size_t psnr_samples) {
  const Correspondence c = match_triangles(in, out);
  return measure_surface_psnr(in, out, c, surface_points(in, c, psnr_samples)).first;
}

/// Where a sample point lies in the output, as a SurfacePsnrOfImages keeps it: the matched triangle
/// (kNone if lost), the point's barycentrics in its input triangle's corner order and each of those
/// corners' corner in the output triangle. 32 bytes, so that a million of them come from the heap that
/// keep_freed_memory_for_reuse (run/process_tuning.hpp) keeps; larger blocks are mapped, and zeroed by
/// the kernel, anew at each judge. Trivial, so that it can be allocated uninitialised.
struct KeptOutputPoint {
  uint32_t o;
  std::array<uint8_t, 3> corner;
  double b[3];
};
static_assert(sizeof(KeptOutputPoint) == 32);

/// What every call of a SurfacePsnrOfImages reads: per sample point the input's shown colour and where
/// it lies in the output, which the images do not change; a call samples the output's images alone.
/// Allocated uninitialised and first written on every core: the kernel's zeroing of the new pages,
/// as costly as the rest of the construction on a million points, is shared out too.
struct SurfacePsnrOfImages::Points {
  size_t size = 0;
  std::unique_ptr<std::array<double, 3>[]> input_colour;
  std::unique_ptr<KeptOutputPoint[]> where;
};

SurfacePsnrOfImages::SurfacePsnrOfImages(const TexturedMesh& input, const TexturedMesh& output, size_t psnr_samples)
    : points_(std::make_unique<Points>()) {
  const Correspondence match = match_triangles(input, output);
  const std::vector<SurfacePoint> points = surface_points(input, match, psnr_samples);
  points_->size = points.size();
  points_->input_colour = std::make_unique_for_overwrite<std::array<double, 3>[]>(points.size());
  points_->where = std::make_unique_for_overwrite<KeptOutputPoint[]>(points.size());
  tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
    const SurfacePoint& p = points[i];
    points_->input_colour[i] = shown_colour(input, p.t, input_uv(input, p), p.b);
    KeptOutputPoint& q = points_->where[i];
    q.o = match.match[p.t];
    for (size_t k = 0; k < 3; ++k) q.corner[k] = uint8_t(match.corner_map[p.t][k]), q.b[k] = p.b[k];
  });
}

SurfacePsnrOfImages::~SurfacePsnrOfImages() = default;

double SurfacePsnrOfImages::operator()(const TexturedMesh& output) const {
  // measure_surface_psnr's sum, term by term, with what the images do not change read from points_.
  const double se = deterministic_sum(points_->size, [&](size_t i) {
    const KeptOutputPoint& kept = points_->where[i];
    return squared_colour_error(points_->input_colour[i], output, point_in_output(output, kept.o, kept.corner, kept.b));
  });
  return psnr_of(se, 3.0 * double(points_->size));
}

nlohmann::json to_json(const Metrics& m) {
  nlohmann::json j;
  auto fig = [](const ModelFigures& f) {
    return nlohmann::json{
        {"utilization", f.utilization}, {"image_utilization", f.image_utilization}, {"used_texels", f.used_texels}, {"texels", f.texels}};
  };
  j["input"] = fig(m.input);
  j["output"] = fig(m.output);
  j["lost_triangles"] = m.lost_triangles;
  j["flipped"] = m.flipped;
  j["degenerate"] = m.degenerate;
  j["overlap"] = m.overlap;
  j["charts"] = m.charts;
  j["seam_length"] = {{"input", m.seam_length_input}, {"output", m.seam_length}};
  j["density_spread"] = {{"p5", m.density_spread.p5}, {"p50", m.density_spread.p50}, {"p95", m.density_spread.p95}};
  j["detail_loss_area"] = m.detail_loss_area;
  j["angle_distortion"] = {{"mean", m.angle_distortion_mean}, {"p95", m.angle_distortion_p95}};
  j["texture_axes_angle_deg"] = {
      {"mean", m.axes_angle_mean}, {"p5", m.axes_angle.p5}, {"p50", m.axes_angle.p50}, {"p95", m.axes_angle.p95}};
  j["surface_psnr_db"] = m.surface_psnr;
  if (m.surface_psnr_bake) j["surface_psnr_bake_db"] = *m.surface_psnr_bake;
  j["psnr_samples"] = m.psnr_samples;
  if (!m.maps.empty()) {
    nlohmann::json maps = nlohmann::json::array();
    for (const MaterialMapFigures& f : m.maps) {
      nlohmann::json e = {{"slot", material_slot_name(f.slot)}, {"samples", f.samples}};
      if (slot_encoding(f.slot) == SlotEncoding::kTangentNormal)
        e["normal_angle_median_deg"] = f.angle_median, e["normal_angle_p95_deg"] = f.angle_p95, e["normal_angle_mean_deg"] = f.angle_mean;
      else
        e["surface_psnr_db"] = f.surface_psnr;
      maps.push_back(std::move(e));
    }
    j["maps"] = std::move(maps);
  }
  return j;
}

}  // namespace tightex

namespace tightex {

TriangleMatch match_output_triangles(const TexturedMesh& input, const TexturedMesh& output) {
  static_assert(kNone == TriangleMatch::kNoOutputTriangle);
  Correspondence c = match_triangles(input, output);
  return TriangleMatch{std::move(c.match), std::move(c.corner_map)};
}

std::vector<MaterialMapFigures> measure_material_maps(const TexturedMesh& input, const TexturedMesh& output, size_t samples) {
  const Correspondence c = match_triangles(input, output);
  return measure_material_maps(input, output, c, surface_points(input, c, samples));
}

}  // namespace tightex
