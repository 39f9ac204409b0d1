// tightex_make_demo: writes a synthetic, scan-like textured model so tightex can demo itself without
// downloads.
//
//   tightex_make_demo OUTDIR [--seed N] [--segments N]
//
// writes OUTDIR/vase.obj, OUTDIR/vase.mtl and OUTDIR/vase_texture.png. The model imitates typical
// photogrammetry output:
//  * a vase (surface of revolution with a belly, a neck and a flared lip), open at the top (the rim is
//    one boundary loop) and closed at the bottom by a flat base disk, with small random jitter on the
//    vertex positions (near-equilateral triangles: staggered rings, row spacing proportional to the
//    local radius);
//  * a few small holes in the side wall and a small floating fragment (a spherical cap) beside it;
//  * a fragmented UV atlas: hundreds of irregular charts (grown over the faces from random seeds),
//    each flattened locally, randomly rotated, packed as rectangles with random gaps into a
//    2048x2048 texture (low utilization), a 2-texel gutter around every chart and flat dark grey
//    elsewhere;
//  * the texture holds a procedural "true" surface colour, a function of the 3D position (hue bands
//    with height, meridian and ring lines, a 3D checker and value noise), so colour fidelity of a
//    re-parameterized result can be judged by eye.
// Positions are shared (one `v` per vertex) while texture coordinates differ across chart borders,
// as in real OBJ exports. The output depends only on --seed and --segments (std::mt19937, and no
// implementation-defined distributions).
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <numbers>
#include <queue>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/image.hpp"
#include "io/image_io.hpp"

namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

constexpr int kTextureSize = 2048;
constexpr int kGutter = 2;            // texels of dilated colour around every chart
constexpr int kMargin = kGutter + 1;  // reserved border inside every packed rectangle
constexpr tightex::Rgba8 kBackground{48, 48, 48, 255};
constexpr double kHeight = 1.9;  // vase height (model units)

// ---------------------------------------------------------------------------------------------
// Deterministic random numbers: std::mt19937 output is fully specified; the std distributions are
// not, so the few we need are written out here.
class Rng {
 public:
  explicit Rng(uint32_t seed) : gen_(seed) {}
  double uniform() { return double(gen_()) * (1.0 / 4294967296.0); }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int index(int n) { return std::min(n - 1, int(uniform() * n)); }  // [0, n)
  int integer(int lo, int hi) { return lo + index(hi - lo + 1); }   // [lo, hi]
  uint32_t raw() { return gen_(); }

 private:
  std::mt19937 gen_;
};

// ---------------------------------------------------------------------------------------------
// The vase profile: radius as a function of t = z / height in [0, 1]. Belly near t = 0.37, neck near
// t = 0.9, a flared lip at the top.
double profile_radius(double t) {
  const double body = 0.5 + 0.25 * std::sin(2.0 * kPi * 0.8 * t - 0.3);
  const double lip = (1.0 - t) / 0.07;
  return body + 0.1 * std::exp(-lip * lip);
}

// Tabulated profile: arc length s(t) and sigma(t) = integral ds / r (rows are spaced evenly in sigma,
// which makes the row spacing proportional to the local radius, hence near-equilateral triangles).
struct Profile {
  std::vector<double> t, s, sigma;
  explicit Profile(int samples = 20000) {
    t.resize(samples + 1);
    s.assign(samples + 1, 0.0);
    sigma.assign(samples + 1, 0.0);
    for (int k = 0; k <= samples; ++k) t[k] = double(k) / samples;
    for (int k = 1; k <= samples; ++k) {
      const double tm = 0.5 * (t[k - 1] + t[k]);
      const double dr = profile_radius(t[k]) - profile_radius(t[k - 1]);
      const double dz = kHeight * (t[k] - t[k - 1]);
      const double ds = std::hypot(dr, dz);
      s[k] = s[k - 1] + ds;
      sigma[k] = sigma[k - 1] + ds / profile_radius(tm);
    }
  }
  double total_sigma() const { return sigma.back(); }
  // Parameter t where sigma reaches the given value (linear interpolation in the table).
  double t_at_sigma(double value) const {
    const auto it = std::lower_bound(sigma.begin(), sigma.end(), value);
    if (it == sigma.begin()) return 0.0;
    if (it == sigma.end()) return 1.0;
    const size_t k = size_t(it - sigma.begin());
    const double f = (value - sigma[k - 1]) / std::max(1e-300, sigma[k] - sigma[k - 1]);
    return t[k - 1] + f * (t[k] - t[k - 1]);
  }
  double s_at_t(double value) const {
    const double x = std::clamp(value, 0.0, 1.0) * double(t.size() - 1);
    const size_t k = std::min(t.size() - 2, size_t(x));
    return s[k] + (x - double(k)) * (s[k + 1] - s[k]);
  }
};

// ---------------------------------------------------------------------------------------------
// The "true" surface colour, a function of the 3D position only.
uint32_t hash3(int x, int y, int z) {
  uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ uint32_t(z) * 0xcb1ab31fu;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  h *= 0x27d4eb2du;
  h ^= h >> 16;
  return h;
}

double value_noise(const Vec3& p) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int ix = int(fx), iy = int(fy), iz = int(fz);
  auto fade = [](double v) { return v * v * (3.0 - 2.0 * v); };
  const double tx = fade(p.x() - fx), ty = fade(p.y() - fy), tz = fade(p.z() - fz);
  auto corner = [&](int dx, int dy, int dz) { return double(hash3(ix + dx, iy + dy, iz + dz)) * (1.0 / 4294967295.0); };
  auto lerp = [](double a, double b, double f) { return a + (b - a) * f; };
  const double x00 = lerp(corner(0, 0, 0), corner(1, 0, 0), tx);
  const double x10 = lerp(corner(0, 1, 0), corner(1, 1, 0), tx);
  const double x01 = lerp(corner(0, 0, 1), corner(1, 0, 1), tx);
  const double x11 = lerp(corner(0, 1, 1), corner(1, 1, 1), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

double smoothstep(double e0, double e1, double x) {
  const double f = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return f * f * (3.0 - 2.0 * f);
}

Vec3 hsv_to_rgb(double h, double s, double v) {
  h = (h - std::floor(h)) * 6.0;
  const int sector = std::min(5, int(h));
  const double f = h - sector;
  const double p = v * (1.0 - s), q = v * (1.0 - s * f), t = v * (1.0 - s * (1.0 - f));
  switch (sector) {
    case 0:
      return {v, t, p};
    case 1:
      return {q, v, p};
    case 2:
      return {p, v, t};
    case 3:
      return {p, q, v};
    case 4:
      return {t, p, v};
    default:
      return {v, p, q};
  }
}

Vec3 surface_colour(const Vec3& p) {
  const double theta = std::atan2(p.y(), p.x());
  const double rxy = std::hypot(p.x(), p.y());
  // Hue bands varying with height (and a little with the distance from the axis, for the base).
  const double hue = 0.42 * p.z() + 0.18 * rxy + 0.04 * std::sin(3.0 * theta + 4.0 * p.z()) + 0.02;
  double sat = 0.72 + 0.12 * std::sin(5.0 * theta);
  double val = 0.86;
  // A 3D checker modulates the brightness.
  const double cell = 0.065;
  const long parity = long(std::floor(p.x() / cell)) + long(std::floor(p.y() / cell)) + long(std::floor(p.z() / cell));
  if (parity & 1) val *= 0.8;
  // Two octaves of value noise (grain).
  val += 0.10 * (value_noise(p * 18.0) - 0.5) + 0.06 * (value_noise(p * 70.0 + Vec3(7.1, 3.3, 1.7)) - 0.5);
  sat += 0.10 * (value_noise(p * 9.0 + Vec3(2.5, 9.1, 4.4)) - 0.5);
  Vec3 rgb = hsv_to_rgb(hue, std::clamp(sat, 0.0, 1.0), std::clamp(val, 0.0, 1.0));
  // Dark meridian lines every 10 degrees (constant width in model units).
  const double step = 2.0 * kPi / 36.0;
  const double dtheta = std::abs(theta - step * std::round(theta / step));
  const double meridian = 1.0 - smoothstep(0.0035, 0.0065, rxy * dtheta);
  rgb *= 1.0 - 0.75 * meridian;
  // Light rings: spheres around a point below the base (horizontal-ish circles on the side,
  // concentric circles on the base).
  const double d = (p - Vec3(0.0, 0.0, -0.3)).norm();
  const double ring_step = 0.09;
  const double ring = 1.0 - smoothstep(0.003, 0.006, std::abs(d - ring_step * std::round(d / ring_step)));
  rgb = rgb * (1.0 - 0.7 * ring) + Vec3(1.0, 1.0, 0.95) * (0.7 * ring);
  return rgb;
}

// ---------------------------------------------------------------------------------------------
// The mesh under construction.
enum Region : int { kSide = 0, kBase = 1, kFragment = 2 };

struct Vertex {
  Vec3 p;                     // jittered position
  bool on_side = false;       // has side parameters (side rings, including the bottom ring)
  double theta = 0.0;         // side: angle
  double s = 0.0;             // side: arc length along the profile
  double r = 0.0;             // side: unjittered radius
  double dt = 0.0, ds = 0.0;  // side: tangential jitter (along the theta and profile directions)
};

struct Face {
  std::array<int, 3> v;
  int region;
};

struct Fragment {
  Vec3 centre;     // sphere centre
  Vec3 n, e1, e2;  // pole direction and tangent frame (e1 x e2 = n)
  double radius = 0.0;
};

uint64_t edge_key(int a, int b) { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); }

// Boundary loops of the face set; `manifold` is false when an edge is used twice in the same
// direction or a vertex has two outgoing boundary edges (a pinch).
struct Topology {
  int boundary_loops = 0;
  bool manifold = true;
};

Topology check_topology(const std::vector<Face>& faces, const std::vector<char>& alive, size_t num_vertices) {
  Topology topo;
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(faces.size() * 4);
  for (size_t f = 0; f < faces.size(); ++f) {
    if (!alive[f]) continue;
    for (int k = 0; k < 3; ++k) {
      if (++directed[edge_key(faces[f].v[k], faces[f].v[(k + 1) % 3])] > 1) topo.manifold = false;
    }
  }
  std::vector<int> next(num_vertices, -1);
  for (const auto& [key, count] : directed) {
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    if (directed.count(edge_key(b, a))) continue;
    if (next[a] != -1) topo.manifold = false;
    next[a] = b;
  }
  if (!topo.manifold) return topo;
  std::vector<char> seen(num_vertices, 0);
  for (size_t v = 0; v < num_vertices; ++v) {
    if (next[v] == -1 || seen[v]) continue;
    ++topo.boundary_loops;
    int w = int(v);
    while (w != -1 && !seen[w]) {
      seen[w] = 1;
      w = next[w];
    }
  }
  return topo;
}

// Triangulates the annulus between two concentric rings of vertex ids whose angles increase
// counter-clockwise (seen from +z); emits counter-clockwise triangles (normal +z).
void stitch_rings(const std::vector<int>& inner, const std::vector<double>& inner_angle, const std::vector<int>& outer,
                  const std::vector<double>& outer_angle, std::vector<std::array<int, 3>>& out) {
  const size_t na = inner.size(), nb = outer.size();
  auto angle = [](const std::vector<double>& a, size_t i) { return a[i % a.size()] + 2.0 * kPi * double(i / a.size()); };
  size_t ia = 0, ib = 0;
  while (ia < na || ib < nb) {
    const bool advance_outer = ia == na || (ib < nb && angle(outer_angle, ib + 1) <= angle(inner_angle, ia + 1));
    if (advance_outer) {
      out.push_back({inner[ia % na], outer[ib % nb], outer[(ib + 1) % nb]});
      ++ib;
    } else {
      out.push_back({inner[ia % na], outer[ib % nb], inner[(ia + 1) % na]});
      ++ia;
    }
  }
}

struct Model {
  std::vector<Vertex> vertices;
  std::vector<Face> faces;
  Fragment fragment;
  int holes = 0;
};

// Vertex id of side row j, column i (i wraps around the n columns).
int side_id(int n, int j, int i) { return j * n + ((i % n) + n) % n; }

// The side's rows (rings): rows + 1 of them, from the bottom crease (row 0) to the rim.
struct SideRows {
  int rows = 0;
  std::vector<double> row_radius;  // unjittered radius of every row
};

// Makes the side's vertices: staggered rings of n, evenly spaced in sigma, with tangential and
// normal jitter.
SideRows add_side_vertices(int n, Rng& rng, std::vector<Vertex>& verts) {
  const double dtheta = 2.0 * kPi / n;
  const Profile profile;
  const int rows = std::max(2, int(std::lround(profile.total_sigma() / (dtheta * std::sqrt(3.0) / 2.0))));
  std::vector<double> row_radius(rows + 1);
  for (int j = 0; j <= rows; ++j) {
    const double t = profile.t_at_sigma(profile.total_sigma() * j / rows);
    const double r = profile_radius(t), z = kHeight * t;
    const double s = profile.s_at_t(t);
    row_radius[j] = r;
    // Profile tangent (dr, dz) in the r-z plane, normalised.
    const double h = 1e-5;
    Vec2 tangent(profile_radius(std::min(1.0, t + h)) - profile_radius(std::max(0.0, t - h)),
                 kHeight * (std::min(1.0, t + h) - std::max(0.0, t - h)));
    tangent.normalize();
    const double spacing = r * dtheta;
    for (int i = 0; i < n; ++i) {
      const double theta = dtheta * (i + 0.5 * (j & 1));
      const Vec3 radial(std::cos(theta), std::sin(theta), 0.0);
      const Vec3 t_dir(-std::sin(theta), std::cos(theta), 0.0);
      const Vec3 s_dir = tangent.x() * radial + Vec3(0, 0, tangent.y());
      const Vec3 n_dir = tangent.y() * radial - Vec3(0, 0, tangent.x());
      Vertex v;
      v.on_side = true;
      v.theta = theta;
      v.s = s;
      v.r = r;
      v.dt = rng.uniform(-0.12, 0.12) * spacing;
      v.ds = rng.uniform(-0.12, 0.12) * spacing;
      const double dn = rng.uniform(-0.06, 0.06) * spacing;
      if (j == 0) v.ds = 0.0;  // keep the bottom crease in the base plane
      v.p = r * radial + Vec3(0, 0, z) + v.dt * t_dir + v.ds * s_dir + dn * n_dir;
      verts.push_back(v);
    }
  }
  return {rows, std::move(row_radius)};
}

// Makes the side's faces: two triangles between every pair of neighbouring columns of
// consecutive rows, following the stagger.
void add_side_faces(int n, int rows, std::vector<Face>& faces) {
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < n; ++i) {
      if ((j & 1) == 0) {
        faces.push_back({{side_id(n, j, i), side_id(n, j, i + 1), side_id(n, j + 1, i)}, kSide});
        faces.push_back({{side_id(n, j, i + 1), side_id(n, j + 1, i + 1), side_id(n, j + 1, i)}, kSide});
      } else {
        faces.push_back({{side_id(n, j, i), side_id(n, j + 1, i + 1), side_id(n, j + 1, i)}, kSide});
        faces.push_back({{side_id(n, j, i), side_id(n, j, i + 1), side_id(n, j + 1, i + 1)}, kSide});
      }
    }
  }
}

// Makes the base disk: concentric rings down to a centre vertex; the outer ring is the side's
// row 0 (radius r0).
void add_base(int n, double r0, Rng& rng, Model& model) {
  auto& verts = model.vertices;
  const double dtheta = 2.0 * kPi / n;
  const double spacing = r0 * dtheta;
  const int rings = std::max(1, int(std::lround(n / (kPi * std::sqrt(3.0)))));
  std::vector<int> ring_ids(n);
  std::vector<double> ring_angles(n);
  for (int i = 0; i < n; ++i) {
    ring_ids[i] = side_id(n, 0, i);
    ring_angles[i] = dtheta * i;
  }
  std::vector<std::array<int, 3>> tris;
  for (int k = rings - 1; k >= 0; --k) {
    std::vector<int> ids;
    std::vector<double> angles;
    const int count = k == 0 ? 1 : std::max(6, int(std::lround(double(n) * k / rings)));
    const double phase = k == 0 ? 0.0 : rng.uniform();
    for (int i = 0; i < count; ++i) {
      const double a = 2.0 * kPi * (i + phase) / count;
      const double rho = r0 * k / rings;
      Vertex v;
      v.p = Vec3(rho * std::cos(a), rho * std::sin(a), 0.0) +
            Vec3(rng.uniform(-0.12, 0.12) * spacing, rng.uniform(-0.12, 0.12) * spacing, rng.uniform(-0.06, 0.06) * spacing);
      ids.push_back(int(verts.size()));
      angles.push_back(a);
      verts.push_back(v);
    }
    if (k == 0) {
      // Fan from the centre to the innermost ring.
      const size_t m = ring_ids.size();
      for (size_t i = 0; i < m; ++i) tris.push_back({ids[0], ring_ids[i], ring_ids[(i + 1) % m]});
    } else {
      stitch_rings(ids, angles, ring_ids, ring_angles, tris);
    }
    ring_ids = std::move(ids);
    ring_angles = std::move(angles);
  }
  // The base faces down: flip the counter-clockwise (+z) triangles.
  for (const auto& t : tris) model.faces.push_back({{t[0], t[2], t[1]}, kBase});
}

// An elliptical patch on the side wall: semi-axes radius * aspect along axis_a and radius along
// axis_b (both tangent to the wall).
struct Ellipse {
  Vec3 c, axis_a, axis_b;
  double radius = 0.0, aspect = 1.0;
  bool contains(const Vec3& p) const {
    const Vec3 d = p - c;
    const double a = d.dot(axis_a) / (radius * aspect), b = d.dot(axis_b) / radius;
    return a * a + b * b < 1.0 && d.norm() < 2.0 * radius * aspect;
  }
};

// The live side faces (among the first num_side_faces) with a corner inside the patch.
std::vector<size_t> faces_in_patch(const Model& model, const std::vector<char>& alive, size_t num_side_faces, const Ellipse& patch) {
  std::vector<size_t> found;
  for (size_t f = 0; f < num_side_faces; ++f) {
    if (!alive[f]) continue;
    const auto& v = model.faces[f].v;
    const auto& verts = model.vertices;
    if (patch.contains(verts[v[0]].p) || patch.contains(verts[v[1]].p) || patch.contains(verts[v[2]].p)) {
      found.push_back(f);
    }
  }
  return found;
}

// Makes the holes: removes (clears in `alive`) a few small elliptical patches of side faces, each a
// few dozen triangles, far apart, each adding exactly one boundary loop to a manifold mesh.
void cut_holes(int n, const SideRows& side, size_t num_side_faces, Rng& rng, Model& model, std::vector<char>& alive) {
  const auto& verts = model.vertices;
  const int rows = side.rows;
  const double dtheta = 2.0 * kPi / n;
  const int wanted = rng.integer(3, 4);
  std::vector<Vec3> centres;
  int expected_loops = 1;  // the rim
  for (int attempt = 0; attempt < 200 && model.holes < wanted; ++attempt) {
    const int j = rng.integer(int(0.15 * rows), std::max(int(0.15 * rows), int(0.85 * rows)));
    const int i = rng.index(n);
    const Vec3 c = verts[side_id(n, j, i)].p;
    bool far = true;
    for (const auto& o : centres) far = far && (o - c).norm() > 0.45;
    if (!far) continue;
    const double spacing = side.row_radius[j] * dtheta;
    const double radius = rng.uniform(1.6, 2.4) * spacing;
    const double aspect = rng.uniform(1.0, 1.6);
    const double orient = rng.uniform(0.0, kPi);
    const Vec3 t_dir(-std::sin(verts[side_id(n, j, i)].theta), std::cos(verts[side_id(n, j, i)].theta), 0.0);
    const Vec3 axis_a = std::cos(orient) * t_dir + std::sin(orient) * Vec3(0, 0, 1);
    const Vec3 axis_b = -std::sin(orient) * t_dir + std::cos(orient) * Vec3(0, 0, 1);
    const Ellipse patch{c, axis_a, axis_b, radius, aspect};
    const std::vector<size_t> removed = faces_in_patch(model, alive, num_side_faces, patch);
    // A few dozen triangles each, and never a large part of a coarse mesh.
    if (removed.size() < 20 || removed.size() > std::min<size_t>(90, num_side_faces / 50)) continue;
    for (size_t f : removed) alive[f] = 0;
    const Topology topo = check_topology(model.faces, alive, verts.size());
    if (!topo.manifold || topo.boundary_loops != expected_loops + 1) {
      for (size_t f : removed) alive[f] = 1;
      continue;
    }
    ++expected_loops;
    ++model.holes;
    centres.push_back(c);
  }
}

// Makes the fragment's sphere and tangent frame: radius 0.2, the cap's apex at a random angle
// beside the vase, its pole tilted randomly from +z.
Fragment make_fragment_frame(Rng& rng) {
  Fragment frag;
  const double psi = rng.uniform(0.0, 2.0 * kPi);
  const Vec3 apex(1.2 * std::cos(psi), 1.2 * std::sin(psi), 0.18);
  frag.n = (Vec3(0, 0, 1) + Vec3(rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), 0.0)).normalized();
  frag.e1 = frag.n.cross(Vec3(1, 0, 0)).normalized();
  frag.e2 = frag.n.cross(frag.e1);
  frag.e1 = frag.e2.cross(frag.n);  // right-handed: e1 x e2 = n
  frag.radius = 0.2;
  frag.centre = apex - frag.radius * frag.n;
  return frag;
}

// Makes the floating fragment: a small jittered spherical cap beside the vase (one boundary loop),
// its faces alive.
void add_fragment(Rng& rng, Model& model, std::vector<char>& alive) {
  model.fragment = make_fragment_frame(rng);
  const Fragment& frag = model.fragment;
  auto& verts = model.vertices;
  const int rings = 6;
  const double alpha_max = 1.0;
  const double spacing = frag.radius * alpha_max / rings;
  auto cap_point = [&](double alpha, double phi) {
    return frag.centre + frag.radius * (std::sin(alpha) * (std::cos(phi) * frag.e1 + std::sin(phi) * frag.e2) + std::cos(alpha) * frag.n);
  };
  auto jittered = [&](const Vec3& p) {
    const Vec3 radial = (p - frag.centre).normalized();
    Vec3 j(rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12));
    j -= radial * (j.dot(radial) * 0.5);  // less jitter along the normal
    return Vec3(p + j * spacing);
  };
  Vertex centre_vertex;
  centre_vertex.p = jittered(cap_point(0.0, 0.0));
  std::vector<int> prev_ids{int(verts.size())};
  std::vector<double> prev_angles{0.0};
  verts.push_back(centre_vertex);
  std::vector<std::array<int, 3>> tris;
  for (int k = 1; k <= rings; ++k) {
    const int count = 6 * k;
    const double phase = rng.uniform();
    std::vector<int> ids;
    std::vector<double> angles;
    for (int i = 0; i < count; ++i) {
      const double phi = 2.0 * kPi * (i + phase) / count;
      Vertex v;
      v.p = jittered(cap_point(alpha_max * k / rings, phi));
      ids.push_back(int(verts.size()));
      angles.push_back(phi);
      verts.push_back(v);
    }
    if (k == 1) {
      for (int i = 0; i < count; ++i) tris.push_back({prev_ids[0], ids[i], ids[(i + 1) % count]});
    } else {
      stitch_rings(prev_ids, prev_angles, ids, angles, tris);
    }
    prev_ids = std::move(ids);
    prev_angles = std::move(angles);
  }
  for (const auto& t : tris) {
    model.faces.push_back({t, kFragment});
    alive.push_back(1);
  }
}

// Renumbers the kept vertices (and the kept faces' references) from first-use order to the
// original vertex order (rows bottom to top); remap maps original ids to first-use ids or -1.
void restore_vertex_order(const std::vector<int>& remap, std::vector<Face>& kept, std::vector<Vertex>& kept_vertices) {
  std::vector<int> order;
  for (size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] != -1) order.push_back(remap[v]);
  }
  std::vector<int> final_id(kept_vertices.size());
  std::vector<Vertex> sorted(kept_vertices.size());
  for (size_t k = 0; k < order.size(); ++k) {
    final_id[order[k]] = int(k);
    sorted[k] = kept_vertices[order[k]];
  }
  for (auto& f : kept) {
    for (int& v : f.v) v = final_id[v];
  }
  kept_vertices = std::move(sorted);
}

// Compacts the model: drops the removed faces and the vertices only they used.
void compact(Model& model, const std::vector<char>& alive) {
  const auto& verts = model.vertices;
  const auto& faces = model.faces;
  std::vector<int> remap(verts.size(), -1);
  std::vector<Face> kept;
  for (size_t f = 0; f < faces.size(); ++f) {
    if (alive[f]) kept.push_back(faces[f]);
  }
  std::vector<Vertex> kept_vertices;
  for (auto& f : kept) {
    for (int& v : f.v) {
      if (remap[v] == -1) {
        remap[v] = int(kept_vertices.size());
        kept_vertices.push_back(verts[v]);
      }
      v = remap[v];
    }
  }
  restore_vertex_order(remap, kept, kept_vertices);
  model.vertices = std::move(kept_vertices);
  model.faces = std::move(kept);
}

// The whole model: side, base disk, holes and floating fragment, compacted.
Model build_model(int segments, Rng& rng) {
  Model model;
  const int n = segments;
  const SideRows side = add_side_vertices(n, rng, model.vertices);
  add_side_faces(n, side.rows, model.faces);
  const size_t num_side_faces = model.faces.size();
  add_base(n, side.row_radius[0], rng, model);
  std::vector<char> alive(model.faces.size(), 1);
  cut_holes(n, side, num_side_faces, rng, model, alive);
  add_fragment(rng, model, alive);
  compact(model, alive);
  return model;
}

// ---------------------------------------------------------------------------------------------
// Charts: grown over the faces from random seeds by a Dijkstra front with a random speed per
// chart (a weighted Voronoi partition: irregular charts of varying size, each connected). Charts
// never cross from one region (side, base, fragment) to another.
std::vector<int> grow_charts(const Model& model, int wanted, Rng& rng, int& num_charts) {
  const auto& faces = model.faces;
  const size_t nf = faces.size();
  std::unordered_map<uint64_t, int> edge_face;
  edge_face.reserve(nf * 4);
  for (size_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) edge_face[edge_key(faces[f].v[k], faces[f].v[(k + 1) % 3])] = int(f);
  }
  std::vector<std::array<int, 3>> neighbour(nf);
  std::vector<Vec3> centroid(nf);
  for (size_t f = 0; f < nf; ++f) {
    const auto& v = faces[f].v;
    centroid[f] = (model.vertices[v[0]].p + model.vertices[v[1]].p + model.vertices[v[2]].p) / 3.0;
    for (int k = 0; k < 3; ++k) {
      const auto it = edge_face.find(edge_key(v[(k + 1) % 3], v[k]));
      const int g = it == edge_face.end() ? -1 : it->second;
      neighbour[f][k] = (g >= 0 && faces[g].region == faces[f].region) ? g : -1;
    }
  }
  std::vector<int> label(nf, -1);
  std::vector<double> dist(nf, std::numeric_limits<double>::infinity());
  std::vector<double> speed;
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  auto add_seed = [&](int f) {
    label[f] = int(speed.size());
    speed.push_back(rng.uniform(0.55, 1.5));
    dist[f] = 0.0;
    queue.push({0.0, f});
  };
  auto run = [&] {
    while (!queue.empty()) {
      const auto [d, f] = queue.top();
      queue.pop();
      if (d > dist[f]) continue;
      for (int g : neighbour[f]) {
        if (g < 0) continue;
        const double nd = d + (centroid[g] - centroid[f]).norm() / speed[label[f]];
        if (nd < dist[g]) {
          dist[g] = nd;
          label[g] = label[f];
          queue.push({nd, g});
        }
      }
    }
  };
  for (int c = 0; c < wanted; ++c) {
    const int f = rng.index(int(nf));
    if (label[f] == -1) add_seed(f);
  }
  run();
  // Components (or regions) that received no seed get their own charts.
  for (size_t f = 0; f < nf; ++f) {
    if (label[f] == -1) {
      add_seed(int(f));
      run();
    }
  }
  num_charts = int(speed.size());
  return label;
}

// ---------------------------------------------------------------------------------------------
// Rectangle packing: shelves, tallest first, with random gaps and a random vertical offset inside
// the shelf. Returns false when the charts do not fit at this texel density.
struct Placement {
  int x = 0, y = 0, w = 0, h = 0;
};

bool pack_shelves(const std::vector<Vec2>& extent, const std::vector<int>& order, double density, uint32_t gap_seed,
                  std::vector<Placement>& out) {
  Rng gaps(gap_seed);
  out.assign(extent.size(), {});
  const int edge = 4;
  int x = edge + gaps.integer(0, 12), y = edge + gaps.integer(0, 12), shelf = 0;
  for (int c : order) {
    Placement& p = out[c];
    p.w = int(std::ceil(extent[c].x() * density)) + 2 * kMargin + 1;
    p.h = int(std::ceil(extent[c].y() * density)) + 2 * kMargin + 1;
    if (p.w > kTextureSize - 2 * edge) return false;
    const int gap_x = gaps.integer(2, 16), gap_y = gaps.integer(2, 16), jitter = gaps.integer(0, 1 << 20);
    if (x + p.w + edge > kTextureSize) {
      y += shelf + gap_y;
      x = edge + gaps.integer(0, 20);
      shelf = 0;
    }
    if (shelf == 0) shelf = p.h;  // tallest first: the first rectangle sets the shelf height
    p.x = x;
    p.y = y + jitter % (std::max(0, shelf - p.h) + 1);
    x += p.w + gap_x;
    if (y + shelf + edge > kTextureSize) return false;
  }
  return true;
}

double wrap_angle(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a <= -kPi) a += 2.0 * kPi;
  return a;
}

struct Atlas {
  std::vector<Vec2> uv;                     // vt entries
  std::vector<std::array<int, 3>> face_uv;  // per face, indices into uv
  tightex::Image image;
  int charts = 0;
  double utilization = 0.0;  // texels whose centre lies in a triangle / all texels
  double density = 0.0;      // texels per model unit
  int flipped = 0;           // UV triangles with non-positive area (should be 0)
};

// Chart-local coordinates (model units) of a vertex in a chart of the given region; theta0 is the
// chart's reference angle (side charts).
Vec2 local_uv(const Vertex& vx, int region, double theta0, const Fragment& frag) {
  if (region == kSide) {
    // Cylindrical coordinates (theta * r, arc length), exact to first order locally.
    return Vec2(wrap_angle(vx.theta - theta0) * vx.r + vx.dt, vx.s + vx.ds);
  }
  if (region == kBase) return Vec2(-vx.p.x(), vx.p.y());  // seen from below
  // Azimuthal equidistant projection of the cap around its pole.
  const Vec3 q = vx.p - frag.centre;
  const double alpha = std::acos(std::clamp(q.normalized().dot(frag.n), -1.0, 1.0));
  const double phi = std::atan2(q.dot(frag.e2), q.dot(frag.e1));
  return frag.radius * alpha * Vec2(std::cos(phi), std::sin(phi));
}

// Makes the texture coordinates, one per (chart, vertex) pair, flattened locally (model units),
// and the faces' references to them; returns the chart of every texture coordinate.
std::vector<int> flatten_charts(const Model& model, const std::vector<std::vector<int>>& chart_faces, Atlas& atlas) {
  const auto& faces = model.faces;
  const auto& verts = model.vertices;
  atlas.face_uv.resize(faces.size());
  std::vector<int> chart_of_uv;
  for (int c = 0; c < int(chart_faces.size()); ++c) {
    const int region = faces[chart_faces[c][0]].region;
    const double theta0 = verts[faces[chart_faces[c][0]].v[0]].theta;
    std::unordered_map<int, int> local;
    for (int f : chart_faces[c]) {
      for (int k = 0; k < 3; ++k) {
        const int v = faces[f].v[k];
        auto [it, inserted] = local.try_emplace(v, int(atlas.uv.size()));
        if (inserted) {
          atlas.uv.push_back(local_uv(verts[v], region, theta0, model.fragment));
          chart_of_uv.push_back(c);
        }
        atlas.face_uv[f][k] = it->second;
      }
    }
  }
  return chart_of_uv;
}

// Per chart, the bounding box of its chart-local coordinates.
struct ChartBoxes {
  std::vector<Vec2> lo, hi;
};

// Rotates every chart by a random angle (in place in `uv`) and makes the charts' bounding boxes.
ChartBoxes rotate_charts(int nc, const std::vector<int>& chart_of_uv, Rng& rng, std::vector<Vec2>& uv) {
  std::vector<Vec2> lo(nc, Vec2::Constant(1e300)), hi(nc, Vec2::Constant(-1e300));
  std::vector<Eigen::Matrix2d> rotation(nc);
  for (int c = 0; c < nc; ++c) rotation[c] = Eigen::Rotation2Dd(rng.uniform(0.0, 2.0 * kPi)).toRotationMatrix();
  for (size_t k = 0; k < uv.size(); ++k) {
    const int c = chart_of_uv[k];
    uv[k] = rotation[c] * uv[k];
    lo[c] = lo[c].cwiseMin(uv[k]);
    hi[c] = hi[c].cwiseMax(uv[k]);
  }
  return {std::move(lo), std::move(hi)};
}

// Makes the charts' placements in the texture: shelves, tallest first, at the largest uniform
// texel density at which they fit (stored in `density`).
std::vector<Placement> pack_charts(const std::vector<Vec2>& extent, Rng& rng, double& density) {
  const int nc = int(extent.size());
  std::vector<int> order(nc);
  for (int c = 0; c < nc; ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return extent[a].y() > extent[b].y(); });
  const uint32_t gap_seed = rng.raw();
  double area = 0.0;
  for (const auto& e : extent) area += e.x() * e.y();
  double d_lo = 1.0, d_hi = kTextureSize / std::sqrt(area);
  std::vector<Placement> place;
  for (int it = 0; it < 50; ++it) {
    const double mid = 0.5 * (d_lo + d_hi);
    (pack_shelves(extent, order, mid, gap_seed, place) ? d_lo : d_hi) = mid;
  }
  density = d_lo;
  if (!pack_shelves(extent, order, d_lo, gap_seed, place)) {
    throw std::runtime_error("internal error: the charts do not fit in the texture");
  }
  return place;
}

// Converts the chart-local coordinates to OBJ texture coordinates at the charts' placements (texel
// positions, v up; image row 0 is v = 1).
void to_texture_coords(const std::vector<int>& chart_of_uv, const ChartBoxes& box, const std::vector<Placement>& place, double density,
                       std::vector<Vec2>& uv) {
  for (size_t k = 0; k < uv.size(); ++k) {
    const int c = chart_of_uv[k];
    const double x = place[c].x + kMargin + (uv[k].x() - box.lo[c].x()) * density;
    const double y = place[c].y + kMargin + (box.hi[c].y() - uv[k].y()) * density;
    uv[k] = Vec2(x / kTextureSize, 1.0 - y / kTextureSize);
  }
}

// The texture under construction, per texel: mask 0 = empty, 1 = inside a chart, 2.. = gutter
// pass; colour in [0, 1] where the mask is set.
struct Canvas {
  std::vector<uint8_t> mask;
  std::vector<Vec3> colour;
};

// Colours the texels whose centre lies in face f's UV triangle with the surface colour; counts the
// face in atlas.flipped if its UV triangle is not clockwise in image space. Returns how many texels
// were newly covered.
size_t rasterize_face(const Model& model, int f, Atlas& atlas, Canvas& canvas) {
  const int size = kTextureSize;
  std::array<Vec2, 3> q;
  for (int k = 0; k < 3; ++k) {
    const Vec2& uv = atlas.uv[atlas.face_uv[f][k]];
    q[k] = Vec2(uv.x() * size, (1.0 - uv.y()) * size);
  }
  const double area2 = (q[1] - q[0]).x() * (q[2] - q[0]).y() - (q[1] - q[0]).y() * (q[2] - q[0]).x();
  if (area2 >= 0.0) ++atlas.flipped;  // image y points down: counter-clockwise UV is negative here
  if (area2 == 0.0) return 0;
  const int x0 = std::max(0, int(std::floor(std::min({q[0].x(), q[1].x(), q[2].x()}))));
  const int x1 = std::min(size - 1, int(std::ceil(std::max({q[0].x(), q[1].x(), q[2].x()}))));
  const int y0 = std::max(0, int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()}))));
  const int y1 = std::min(size - 1, int(std::ceil(std::max({q[0].y(), q[1].y(), q[2].y()}))));
  const auto& verts = model.vertices;
  const Vec3& p0 = verts[model.faces[f].v[0]].p;
  const Vec3& p1 = verts[model.faces[f].v[1]].p;
  const Vec3& p2 = verts[model.faces[f].v[2]].p;
  size_t covered = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const Vec2 c(x + 0.5, y + 0.5);
      auto edge = [&](const Vec2& a, const Vec2& b) { return ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x()) / area2; };
      const double b0 = edge(q[1], q[2]), b1 = edge(q[2], q[0]), b2 = edge(q[0], q[1]);
      if (b0 < -1e-9 || b1 < -1e-9 || b2 < -1e-9) continue;
      const size_t idx = size_t(y) * size + x;
      if (canvas.mask[idx] == 0) ++covered;
      canvas.mask[idx] = 1;
      canvas.colour[idx] = surface_colour(b0 * p0 + b1 * p1 + b2 * p2);
    }
  }
  return covered;
}

// Makes the charts' texels: every texel whose centre lies in a chart triangle, coloured; sets
// atlas.utilization and atlas.flipped.
Canvas rasterize(const Model& model, Atlas& atlas) {
  const int size = kTextureSize;
  Canvas canvas{std::vector<uint8_t>(size_t(size) * size, 0), std::vector<Vec3>(size_t(size) * size, Vec3::Zero())};
  size_t covered = 0;
  for (int f = 0; f < int(model.faces.size()); ++f) covered += rasterize_face(model, f, atlas, canvas);
  atlas.utilization = double(covered) / (double(size) * size);
  return canvas;
}

// Makes the gutter: dilates each chart by kGutter texels (average of the already coloured
// 8-neighbours).
void add_gutter(Canvas& canvas) {
  const int size = kTextureSize;
  auto& mask = canvas.mask;
  auto& colour = canvas.colour;
  for (int pass = 1; pass <= kGutter; ++pass) {
    std::vector<std::pair<size_t, Vec3>> grown;
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const size_t idx = size_t(y) * size + x;
        if (mask[idx] != 0) continue;
        Vec3 sum = Vec3::Zero();
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
            const size_t nidx = size_t(ny) * size + nx;
            if (mask[nidx] != 0 && mask[nidx] <= pass) {
              sum += colour[nidx];
              ++count;
            }
          }
        }
        if (count > 0) grown.emplace_back(idx, sum / count);
      }
    }
    for (const auto& [idx, c] : grown) {
      mask[idx] = uint8_t(pass + 1);
      colour[idx] = c;
    }
  }
}

// Makes the texture image: the canvas's coloured texels (charts and gutters), flat background
// elsewhere.
tightex::Image paint_texture(const Canvas& canvas) {
  tightex::Image image(kTextureSize, kTextureSize, kBackground);
  for (size_t idx = 0; idx < canvas.mask.size(); ++idx) {
    if (canvas.mask[idx] == 0) continue;
    auto to8 = [](double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
    const Vec3& c = canvas.colour[idx];
    image.pixels[idx] = {to8(c.x()), to8(c.y()), to8(c.z()), 255};
  }
  return image;
}

// The fragmented atlas of the model: charts, flattened, rotated, packed and rasterized with a
// gutter.
Atlas build_atlas(const Model& model, Rng& rng) {
  Atlas atlas;
  const int nf = int(model.faces.size());
  const int wanted = std::clamp(nf / 70, std::min(300, std::max(1, nf / 8)), 600);
  const std::vector<int> label = grow_charts(model, wanted, rng, atlas.charts);
  const int nc = atlas.charts;
  std::vector<std::vector<int>> chart_faces(nc);
  for (int f = 0; f < nf; ++f) chart_faces[label[f]].push_back(f);

  const std::vector<int> chart_of_uv = flatten_charts(model, chart_faces, atlas);
  const ChartBoxes box = rotate_charts(nc, chart_of_uv, rng, atlas.uv);
  std::vector<Vec2> extent(nc);
  for (int c = 0; c < nc; ++c) extent[c] = box.hi[c] - box.lo[c];
  const std::vector<Placement> place = pack_charts(extent, rng, atlas.density);
  to_texture_coords(chart_of_uv, box, place, atlas.density, atlas.uv);

  Canvas canvas = rasterize(model, atlas);
  add_gutter(canvas);
  atlas.image = paint_texture(canvas);
  return atlas;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  FILE* file = std::fopen(path.string().c_str(), "wb");
  if (!file) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
  const size_t written = std::fwrite(text.data(), 1, text.size(), file);
  if (std::fclose(file) != 0 || written != text.size()) {
    throw std::runtime_error(fmt::format("cannot write {}", path.string()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Writes a synthetic scan-like textured model (vase.obj, vase.mtl, vase_texture.png) "
      "with a fragmented texture atlas, for demonstrating tightex."};
  std::string outdir;
  uint32_t seed = 1;
  int segments = 128;
  app.add_option("OUTDIR", outdir, "Output folder (created if missing)")->required();
  app.add_option("--seed", seed, "Random seed (the output is a function of the seed)")->capture_default_str();
  app.add_option("--segments", segments, "Vertices around the vase (sets the resolution; 128 gives ~30k triangles)")
      ->check(CLI::Range(12, 1024))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    const auto start = std::chrono::steady_clock::now();
    const std::filesystem::path dir(outdir);
    std::filesystem::create_directories(dir);

    Rng rng(seed);
    const Model model = build_model(segments, rng);
    Atlas atlas = build_atlas(model, rng);
    if (atlas.flipped != 0) {
      throw std::runtime_error(fmt::format("internal error: {} flipped UV triangles", atlas.flipped));
    }

    // OBJ: one v per vertex, one vt per (chart, vertex), faces as v/vt.
    std::string obj;
    obj.reserve(size_t(80) * (model.vertices.size() + atlas.uv.size() + model.faces.size()) + 256);
    auto out = std::back_inserter(obj);
    fmt::format_to(out, "# tightex_make_demo --seed {} --segments {}\n", seed, segments);
    fmt::format_to(out, "# {} vertices, {} texture coordinates, {} triangles, {} charts\n", model.vertices.size(), atlas.uv.size(),
                   model.faces.size(), atlas.charts);
    fmt::format_to(out, "mtllib vase.mtl\no vase\n");
    for (const auto& v : model.vertices) fmt::format_to(out, "v {:.9g} {:.9g} {:.9g}\n", v.p.x(), v.p.y(), v.p.z());
    for (const auto& t : atlas.uv) fmt::format_to(out, "vt {:.9g} {:.9g}\n", t.x(), t.y());
    fmt::format_to(out, "usemtl material0\n");
    for (size_t f = 0; f < model.faces.size(); ++f) {
      const auto& v = model.faces[f].v;
      const auto& t = atlas.face_uv[f];
      fmt::format_to(out, "f {}/{} {}/{} {}/{}\n", v[0] + 1, t[0] + 1, v[1] + 1, t[1] + 1, v[2] + 1, t[2] + 1);
    }
    write_text(dir / "vase.obj", obj);
    write_text(dir / "vase.mtl",
               "# tightex_make_demo\nnewmtl material0\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\n"
               "map_Kd vase_texture.png\n");
    tightex::save_image((dir / "vase_texture.png").string(), atlas.image, tightex::ImageFormat::kPng);

    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print(
        "wrote {}: {} vertices, {} triangles, {} holes + 1 floating fragment, {} charts, "
        "texture {}x{} ({:.1f}% used, {:.0f} texels/unit), {:.2f} s\n",
        (dir / "vase.obj").string(), model.vertices.size(), model.faces.size(), model.holes, atlas.charts, kTextureSize, kTextureSize,
        100.0 * atlas.utilization, atlas.density, seconds);
  } catch (const std::exception& e) {
    fmt::print(stderr, "tightex_make_demo: {}\n", e.what());
    return 1;
  }
  return 0;
}
