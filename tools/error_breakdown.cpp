// Where does a run's surface-PSNR error come from? Samples the input surface as docs/metrics.md's surface PSNR
// does (uniform by area) and splits the squared error by
//   - whether the input's bilinear sample reads a texel outside the input's used region (its chart edges,
//     where a renderer blends in the gutter), and
//   - the run's linear texel-density ratio output/input at the sample's triangle (log2 bins).
// Usage: tightex_error_breakdown INPUT.obj OUTPUT.obj [SAMPLES]
// A development tool: the figures it prints explain, they are not the report's.
#include "core/image.hpp"
#include "core/mesh.hpp"
#include "core/raster.hpp"
#include "core/statistics.hpp"
#include "io/obj_reader.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <unordered_map>

using namespace tightex;

namespace {

/// m's colour at uv of triangle t, 8-bit RGB as doubles (white without a texture).
std::array<double, 3> colour(const TexturedMesh& m, size_t t, const Vec2& uv) {
  const Image* img = image_of(m, t);
  if (!img) return {255, 255, 255};
  const auto c = sample_bilinear(*img, uv.x(), uv.y());
  auto q = [](float x) { return double(std::clamp(std::lround(x), 0l, 255l)); };
  return {q(c[0]), q(c[1]), q(c[2])};
}

/// A triangle's corner positions, sorted, as bytes: the same triangle in another model has the same key.
std::string key(const TexturedMesh& m, size_t t) {
  std::array<std::array<double, 3>, 3> p;
  for (int k = 0; k < 3; ++k) {
    const Vec3& v = m.positions[m.triangles[t][k]];
    p[size_t(k)] = {v.x(), v.y(), v.z()};
  }
  std::sort(p.begin(), p.end());
  return std::string(reinterpret_cast<const char*>(p.data()), sizeof p);
}

/// Output triangle by its key (corner positions).
using CornerIndex = std::unordered_map<std::string, uint32_t>;

/// Used-texel mask of each input texture: texel centres inside some triangle.
std::vector<std::vector<uint8_t>> used_texel_masks(const TexturedMesh& in) {
  std::vector<std::vector<uint8_t>> used(in.textures.size());
  for (size_t i = 0; i < in.textures.size(); ++i) used[i].assign(in.textures[i].image.pixels.size(), 0);
  for (size_t t = 0; t < in.num_triangles(); ++t) {
    const Image* img = image_of(in, t);
    if (!img) continue;
    const size_t tex = size_t(in.materials[size_t(in.face_material[t])].texture);
    Vec2 p[3];
    for (int k = 0; k < 3; ++k) p[k] = {in.sampled_uv(t, k).x() * img->width, (1 - in.sampled_uv(t, k).y()) * img->height};
    scan_triangle(p[0], p[1], p[2], 0, img->width, 0, img->height, EdgeRule::kInclusive,
                  [&](long x, long y, double, double, double) { used[tex][size_t(y) * size_t(img->width) + size_t(x)] = 1; });
  }
  return used;
}

/// The Jacobian from a triangle's 3D plane (a local frame) to its 2D corners q.
Eigen::Matrix2d jacobian(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec2& q0, const Vec2& q1, const Vec2& q2) {
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const Vec3 x = e1.normalized(), n = e1.cross(e2), y = n.normalized().cross(x);
  Eigen::Matrix2d P;
  P << e1.dot(x), e2.dot(x), e1.dot(y), e2.dot(y);
  Eigen::Matrix2d Q;
  Q << (q1 - q0).x(), (q2 - q0).x(), (q1 - q0).y(), (q2 - q0).y();
  return Eigen::Matrix2d(Q * P.inverse());
}

/// sigma1 / sigma2 of a Jacobian (1e9 where it collapses).
double anisotropy(const Eigen::Matrix2d& J) {
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(J);
  const auto sv = svd.singularValues();
  return sv(1) > 0 ? sv(0) / sv(1) : 1e9;
}

/// Prints the area-weighted anisotropy of the input's and the output's maps relative to 3D, and of the
/// output's relative to the input's.
void print_anisotropy(const TexturedMesh& in, const TexturedMesh& out, const CornerIndex& index) {
  std::vector<std::pair<double, double>> ri, ro, rio;
  for (size_t t = 0; t < in.num_triangles(); ++t) {
    const auto it = index.find(key(in, t));
    if (it == index.end()) continue;
    const uint32_t o = it->second;
    const Vec3 &p0 = in.positions[in.triangles[t][0]], &p1 = in.positions[in.triangles[t][1]], &p2 = in.positions[in.triangles[t][2]];
    const double a = triangle_area(p0, p1, p2);
    if (!(a > 0)) continue;
    Vec2 qo[3];
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        if (in.positions[in.triangles[t][k]] == out.positions[out.triangles[o][j]]) qo[k] = out.sampled_uv(o, j);
    const Image* ii = image_of(in, t);
    const double sx = ii ? ii->width : 1, sy = ii ? ii->height : 1;
    auto px = [&](Vec2 q) { return Vec2(q.x() * sx, q.y() * sy); };
    const Eigen::Matrix2d Ji = jacobian(p0, p1, p2, px(in.sampled_uv(t, 0)), px(in.sampled_uv(t, 1)), px(in.sampled_uv(t, 2)));
    const Eigen::Matrix2d Jo = jacobian(p0, p1, p2, qo[0], qo[1], qo[2]);
    if (std::abs(Ji.determinant()) < 1e-300) continue;
    ri.push_back({anisotropy(Ji), a}), ro.push_back({anisotropy(Jo), a}), rio.push_back({anisotropy(Jo * Ji.inverse()), a});
  }
  fmt::print(
      "anisotropy sigma1/sigma2 (P50 / P90): input vs 3D {:.2f} / {:.2f}; output vs 3D {:.2f} / {:.2f}; output vs input {:.2f} / {:.2f}\n",
      weighted_quantile(ri, 0.5), weighted_quantile(ri, 0.9), weighted_quantile(ro, 0.5), weighted_quantile(ro, 0.9),
      weighted_quantile(rio, 0.5), weighted_quantile(rio, 0.9));
}

struct Bin {
  double se = 0;
  size_t n = 0;
};

/// The samples' squared error, in all, split by chart edge / interior, and by density ratio bin.
struct ErrorBins {
  Bin all, edge, interior;
  std::map<int, Bin> by_ratio, by_ratio_edge;  // log2 bins of the linear density ratio, half an octave wide
};

/// Whether the input's bilinear sample at uv of triangle t reads a texel outside the used region.
bool reads_outside_used(const TexturedMesh& in, size_t t, const Vec2& uv, const std::vector<std::vector<uint8_t>>& used) {
  const Image* img = image_of(in, t);
  if (!img) return false;
  const size_t tex = size_t(in.materials[size_t(in.face_material[t])].texture);
  const double x = uv.x() * img->width - 0.5, y = (1 - uv.y()) * img->height - 0.5;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  bool at_edge = false;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int xx = std::clamp(x0 + dx, 0, img->width - 1), yy = std::clamp(y0 + dy, 0, img->height - 1);
      at_edge |= !used[tex][size_t(yy) * size_t(img->width) + size_t(xx)];
    }
  return at_edge;
}

/// Linear texel-density ratio output / input of output triangle o and input triangle t (0: unknown).
double density_ratio(const TexturedMesh& in, size_t t, const TexturedMesh& out, uint32_t o) {
  const Image* oi = image_of(out, o);
  const Image* ii = image_of(in, t);
  if (!oi || !ii) return 0;
  const double ai = std::abs(signed_area(in.sampled_uv(t, 0), in.sampled_uv(t, 1), in.sampled_uv(t, 2))) * ii->width * ii->height;
  const double ao = std::abs(signed_area(out.sampled_uv(o, 0), out.sampled_uv(o, 1), out.sampled_uv(o, 2))) * oi->width * oi->height;
  return ai > 0 ? std::sqrt(ao / ai) : 0;
}

/// Samples the input surface uniformly by area (docs/metrics.md's seed) and bins each sample's squared error.
ErrorBins sample_errors(const TexturedMesh& in, const TexturedMesh& out, const CornerIndex& index,
                        const std::vector<std::vector<uint8_t>>& used, size_t samples) {
  std::vector<double> cdf(in.num_triangles());
  double acc = 0;
  for (size_t t = 0; t < in.num_triangles(); ++t) cdf[t] = acc += triangle_area(in.positions, in.triangles[t]);
  std::mt19937_64 rng(20240606);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  ErrorBins bins;
  for (size_t s = 0; s < samples; ++s) {
    const size_t t = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), uni(rng) * acc) - cdf.begin()), cdf.size() - 1);
    double r1 = uni(rng), r2 = uni(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const double b[3] = {1 - r1 - r2, r1, r2};
    const Vec2 uin = b[0] * in.sampled_uv(t, 0) + b[1] * in.sampled_uv(t, 1) + b[2] * in.sampled_uv(t, 2);
    const auto it = index.find(key(in, t));
    if (it == index.end()) continue;
    const uint32_t o = it->second;
    Vec2 uout = Vec2::Zero();  // the output corners matched to the input's by position
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        if (in.positions[in.triangles[t][k]] == out.positions[out.triangles[o][j]]) uout += b[k] * out.sampled_uv(o, j);
    const auto ci = colour(in, t, uin), co = colour(out, o, uout);
    double se = 0;
    for (int c = 0; c < 3; ++c) se += (ci[size_t(c)] - co[size_t(c)]) * (ci[size_t(c)] - co[size_t(c)]);
    const bool at_edge = reads_outside_used(in, t, uin, used);
    const double ratio = density_ratio(in, t, out, o);
    const int bin = ratio > 0 ? int(std::floor(2 * std::log2(ratio))) : -99;
    (at_edge ? bins.edge : bins.interior).se += se, (at_edge ? bins.edge : bins.interior).n++;
    bins.all.se += se, bins.all.n++;
    auto& bb = at_edge ? bins.by_ratio_edge[bin] : bins.by_ratio[bin];
    bb.se += se, bb.n++;
  }
  return bins;
}

double psnr(double se, size_t n) { return n && se > 0 ? 10 * std::log10(255.0 * 255 * 3 * double(n) / se) : 99.0; }

void print_error_bins(ErrorBins& b) {
  const Bin& all = b.all;
  fmt::print("all: {:.2f} dB over {} samples\n", psnr(all.se, all.n), all.n);
  fmt::print("input chart edge (a tap outside the used texels): {:.1f}% of samples, {:.1f}% of squared error, {:.2f} dB\n",
             100.0 * double(b.edge.n) / double(all.n), 100 * b.edge.se / all.se, psnr(b.edge.se, b.edge.n));
  fmt::print("interior: {:.2f} dB; PSNR without edge samples\n", psnr(b.interior.se, b.interior.n));
  fmt::print("linear density ratio out/in | samples % | error share % | dB (interior) | edge samples % | edge error share % | dB (edge)\n");
  std::set<int> keys;
  for (auto& [k, v] : b.by_ratio) keys.insert(k);
  for (auto& [k, v] : b.by_ratio_edge) keys.insert(k);
  for (int k : keys) {
    const Bin a = b.by_ratio[k], e = b.by_ratio_edge[k];
    fmt::print("{:5.2f}..{:5.2f} | {:5.1f} | {:5.1f} | {:6.2f} | {:5.1f} | {:5.1f} | {:6.2f}\n", std::exp2(k / 2.0),
               std::exp2((k + 1) / 2.0), 100.0 * double(a.n + e.n) / double(all.n), 100 * a.se / all.se, psnr(a.se, a.n),
               100.0 * double(e.n) / double(all.n), 100 * e.se / all.se, psnr(e.se, e.n));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    fmt::print(stderr, "usage: {} INPUT.obj OUTPUT.obj [SAMPLES]\n", argv[0]);
    return 2;
  }
  const TexturedMesh in = read_obj(argv[1]), out = read_obj(argv[2]);
  const size_t samples = argc > 3 ? size_t(std::stoul(argv[3])) : 200000;
  CornerIndex index;
  for (uint32_t t = 0; t < out.num_triangles(); ++t) index.emplace(key(out, t), t);
  const auto used = used_texel_masks(in);
  print_anisotropy(in, out, index);
  ErrorBins bins = sample_errors(in, out, index, used, samples);
  print_error_bins(bins);
}
