// A catalogue of small textured meshes generated in code, one per situation the pipeline must handle:
// closed surfaces of genus 0, 1 and 2, open surfaces with one, two and three boundary loops,
// non-manifold input (bowtie vertex, an edge shared by three sheets), zero-area and duplicated
// triangles, obtuse triangles whose cotangent weights go negative, and tiny floaters.
//
// Every generator returns a complete TexturedMesh: positions, triangles counter-clockwise seen from
// outside (for the closed ones: positive enclosed volume), corner_uv = a planar projection of (x, y)
// into [0.05, 0.95] (inside the texture, so a repeat sampler never blends across its border),
// face_material all 0, one Material with texture 0, one Texture with a generated 64x64 image, and
// source = the generator's name.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.hpp"

namespace tightex::testing {

// ---- textures ----

/// A smooth colour gradient: red grows with u, green with v (OBJ convention: row 0 is v = 1), blue
/// constant. Bilinear samples of it are an affine function of uv, so a bake can reproduce it closely.
inline Image gradient_image(int w = 64, int h = 64) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = (x + 0.5) / w, v = 1.0 - (y + 0.5) / h;
      img.at(x, y) = Rgba8{uint8_t(std::lround(255 * u)), uint8_t(std::lround(255 * v)), 128, 255};
    }
  return img;
}

/// A checker of `cell`-texel squares in two colours (high frequency: hard to bake exactly).
inline Image checker_image(int w = 64, int h = 64, int cell = 8) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = ((x / cell + y / cell) % 2) ? Rgba8{230, 60, 40, 255} : Rgba8{30, 90, 200, 255};
  return img;
}

// ---- assembling a mesh ----

/// Wraps raw geometry into a TexturedMesh as described at the top of this file.
inline TexturedMesh make_textured(std::string name, std::vector<Vec3> positions, std::vector<Tri> triangles,
                                  Image image = gradient_image()) {
  TexturedMesh m;
  m.source = std::move(name);
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const Tri& f : m.triangles)
    for (uint32_t v : f) {
      const Vec3& p = m.positions[v];
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    }
  if (m.triangles.empty()) x0 = y0 = 0, x1 = y1 = 1;
  const double sx = std::max(x1 - x0, 1e-12), sy = std::max(y1 - y0, 1e-12);
  m.corner_uv.reserve(3 * m.triangles.size());
  for (const Tri& f : m.triangles)
    for (uint32_t v : f) {
      const Vec3& p = m.positions[v];
      m.corner_uv.push_back(Vec2(0.05 + 0.9 * (p.x() - x0) / sx, 0.05 + 0.9 * (p.y() - y0) / sy));
    }
  m.face_material.assign(m.triangles.size(), 0);
  Material mat;
  mat.name = "material0";
  mat.texture = 0;
  m.materials.push_back(mat);
  Texture tex;
  tex.path = m.source + ".png";
  tex.image = std::move(image);
  m.textures.push_back(std::move(tex));
  return m;
}

/// Raw geometry, before it is wrapped.
struct Geometry {
  std::vector<Vec3> positions;
  std::vector<Tri> triangles;

  uint32_t add(const Vec3& p) {
    positions.push_back(p);
    return uint32_t(positions.size() - 1);
  }
  /// Appends another geometry moved by `offset`.
  void append(const Geometry& g, const Vec3& offset = Vec3::Zero()) {
    const uint32_t base = uint32_t(positions.size());
    for (const Vec3& p : g.positions) positions.push_back(p + offset);
    for (const Tri& f : g.triangles) triangles.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
};

/// A grid of nu x nv vertices from f(i, j); (i, j) must be a positively oriented chart (d/di x d/dj
/// points outward). wrap_u / wrap_v join the last column / row to the first (no duplicated vertices).
inline Geometry param_grid(int nu, int nv, bool wrap_u, bool wrap_v, const std::function<Vec3(int, int)>& f) {
  Geometry g;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) g.add(f(i, j));
  auto id = [&](int i, int j) { return uint32_t((j % nv) * nu + (i % nu)); };
  const int cu = wrap_u ? nu : nu - 1, cv = wrap_v ? nv : nv - 1;
  for (int j = 0; j < cv; ++j)
    for (int i = 0; i < cu; ++i) {
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      g.triangles.push_back({a, b, c});
      g.triangles.push_back({a, c, d});
    }
  return g;
}

// ---- geometry generators ----

/// Flat disk of radius `radius` in the z = 0 plane (normal +z): a centre vertex and `rings` rings of
/// `segments` vertices each. 2 * rings - 1 times `segments` triangles.
inline Geometry disk_geometry(int rings = 10, int segments = 32, double radius = 1.0) {
  Geometry g;
  g.add(Vec3::Zero());
  for (int r = 1; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double a = 2 * std::numbers::pi * s / segments, rr = radius * r / rings;
      g.add(Vec3(rr * std::cos(a), rr * std::sin(a), 0));
    }
  auto id = [&](int r, int s) { return r == 0 ? 0u : uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) g.triangles.push_back({0, id(1, s), id(1, s + 1)});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = id(r, s), b = id(r, s + 1), c = id(r + 1, s + 1), d = id(r + 1, s);
      g.triangles.push_back({a, d, c});
      g.triangles.push_back({a, c, b});
    }
  return g;
}

/// UV sphere: two poles and stacks - 1 rings of `slices` vertices. 2 * slices * (stacks - 1) triangles
/// (32 x 32: 1984).
inline Geometry sphere_geometry(int stacks = 32, int slices = 32, double radius = 1.0) {
  Geometry g;
  const uint32_t north = g.add(Vec3(0, 0, radius));
  for (int i = 1; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const double phi = std::numbers::pi * i / stacks, theta = 2 * std::numbers::pi * j / slices;
      g.add(radius * Vec3(std::sin(phi) * std::cos(theta), std::sin(phi) * std::sin(theta), std::cos(phi)));
    }
  const uint32_t south = g.add(Vec3(0, 0, -radius));
  auto id = [&](int i, int j) { return uint32_t(1 + (i - 1) * slices + (j % slices)); };
  for (int j = 0; j < slices; ++j) g.triangles.push_back({north, id(1, j), id(1, j + 1)});
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      // (phi, theta) is positively oriented: d/dphi x d/dtheta points outward.
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      g.triangles.push_back({a, b, c});
      g.triangles.push_back({a, c, d});
    }
  for (int j = 0; j < slices; ++j) g.triangles.push_back({south, id(stacks - 1, j + 1), id(stacks - 1, j)});
  return g;
}

/// Open cylinder around the z axis: `rings` rings of `segments` vertices, two boundary loops.
inline Geometry cylinder_geometry(int rings = 12, int segments = 32, double radius = 0.5, double height = 2.0) {
  return param_grid(segments, rings, true, false, [&](int i, int j) {
    const double a = 2 * std::numbers::pi * i / segments;
    return Vec3(radius * std::cos(a), radius * std::sin(a), -height / 2 + height * j / (rings - 1));
  });
}

/// Torus around the z axis (major radius R, minor radius r), nu x nv vertices.
inline Geometry torus_geometry(int nu = 48, int nv = 24, double R = 1.0, double r = 0.4) {
  return param_grid(nu, nv, true, true, [&](int i, int j) {
    const double t = 2 * std::numbers::pi * i / nu, p = 2 * std::numbers::pi * j / nv;
    return Vec3((R + r * std::cos(p)) * std::cos(t), (R + r * std::cos(p)) * std::sin(t), r * std::sin(p));
  });
}

/// The surface of a polycube: the union of the given unit voxels, each voxel face subdivided into
/// k x k squares (two triangles each), scaled by `scale`. Vertices on shared lattice points are shared.
/// The voxel set must not touch itself along an edge or at a corner only (or the surface is not
/// manifold).
inline Geometry polycube_geometry(const std::vector<std::array<int, 3>>& voxels, int k, double scale) {
  auto filled = [&](std::array<int, 3> v) { return std::find(voxels.begin(), voxels.end(), v) != voxels.end(); };
  Geometry g;
  std::vector<std::pair<std::array<long, 3>, uint32_t>> lattice;  // small: linear search is fine
  auto vertex = [&](std::array<long, 3> p) {
    for (const auto& [q, id] : lattice)
      if (q == p) return id;
    const uint32_t id = g.add(scale * Vec3(double(p[0]), double(p[1]), double(p[2])) / double(k));
    lattice.push_back({p, id});
    return id;
  };
  for (const auto& v : voxels)
    for (int axis = 0; axis < 3; ++axis)
      for (int sign : {1, -1}) {
        std::array<int, 3> n = v;
        n[size_t(axis)] += sign;
        if (filled(n)) continue;
        // The face lies at axis coordinate v[axis] + (sign > 0); (b, c) = the next two axes cyclically,
        // so e_b x e_c = e_axis.
        const int b = (axis + 1) % 3, c = (axis + 2) % 3;
        for (int i = 0; i < k; ++i)
          for (int j = 0; j < k; ++j) {
            auto at = [&](int di, int dj) {
              std::array<long, 3> p{};
              p[size_t(axis)] = long(v[size_t(axis)] + (sign > 0)) * k;
              p[size_t(b)] = long(v[size_t(b)]) * k + i + di;
              p[size_t(c)] = long(v[size_t(c)]) * k + j + dj;
              return vertex(p);
            };
            const uint32_t p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
            if (sign > 0) {
              g.triangles.push_back({p00, p10, p11});
              g.triangles.push_back({p00, p11, p01});
            } else {
              g.triangles.push_back({p00, p11, p10});
              g.triangles.push_back({p00, p01, p11});
            }
          }
      }
  return g;
}

/// Genus 2: the surface of a 5 x 3 x 1 slab of voxels with the voxels (1, 1) and (3, 1) taken out.
inline Geometry double_torus_geometry(int k = 3) {
  std::vector<std::array<int, 3>> voxels;
  for (int x = 0; x < 5; ++x)
    for (int y = 0; y < 3; ++y)
      if (!(y == 1 && (x == 1 || x == 3))) voxels.push_back({x, y, 0});
  return polycube_geometry(voxels, k, 0.5);
}

/// Genus 25 (many small handles): an 11 x 11 x 1 slab of voxels with every (odd, odd) voxel taken out.
inline Geometry holey_slab_geometry(int k = 1) {
  std::vector<std::array<int, 3>> voxels;
  for (int x = 0; x < 11; ++x)
    for (int y = 0; y < 11; ++y)
      if (!(x % 2 == 1 && y % 2 == 1)) voxels.push_back({x, y, 0});
  return polycube_geometry(voxels, k, 0.2);
}

// ---- the catalogue (TexturedMesh generators) ----

inline TexturedMesh disk() {
  auto g = disk_geometry();
  return make_textured("disk", g.positions, g.triangles);
}

inline TexturedMesh sphere() {
  auto g = sphere_geometry();
  return make_textured("sphere", g.positions, g.triangles);
}

inline TexturedMesh open_cylinder() {
  auto g = cylinder_geometry();
  return make_textured("open_cylinder", g.positions, g.triangles);
}

/// Number of caps sphere_with_holes() cuts out.
constexpr int kSphereHoles = 3;

/// The UV sphere with three holes: two caps removed (every triangle touching a vertex within chord
/// distance 0.35 of the cap's centre) and one tiny hole (the 6 triangles around a single vertex, about
/// 0.2% of the area: small enough for HoleMode::kFill to cap). The vertices of the removed triangles
/// stay in `positions`, unused.
inline TexturedMesh sphere_with_holes() {
  Geometry g = sphere_geometry();
  const Vec3 caps[2] = {Vec3(0, 0, 1), Vec3(1, 0, 0)};
  const Vec3 tiny = Vec3(-0.5, 0.8, -0.35).normalized();
  std::vector<char> removed(g.positions.size(), 0);
  size_t nearest = 0;
  for (size_t v = 0; v < g.positions.size(); ++v) {
    for (const Vec3& c : caps) removed[v] |= (g.positions[v] - c).norm() < 0.35;
    if ((g.positions[v] - tiny).norm() < (g.positions[nearest] - tiny).norm()) nearest = v;
  }
  removed[nearest] = 1;
  std::vector<Tri> kept;
  for (const Tri& f : g.triangles)
    if (!removed[f[0]] && !removed[f[1]] && !removed[f[2]]) kept.push_back(f);
  return make_textured("sphere_with_holes", g.positions, kept);
}

inline TexturedMesh torus() {
  auto g = torus_geometry();
  return make_textured("torus", g.positions, g.triangles);
}

inline TexturedMesh double_torus() {
  auto g = double_torus_geometry();
  return make_textured("double_torus", g.positions, g.triangles);
}

/// Two fans of 4 triangles in the z = 0 plane sharing only their apex: a bowtie (non-manifold) vertex.
inline TexturedMesh bowtie() {
  Geometry g;
  const uint32_t apex = g.add(Vec3::Zero());
  for (double start : {20.0, 200.0}) {
    std::vector<uint32_t> rim;
    for (int s = 0; s <= 4; ++s) {
      const double a = (start + 35.0 * s) * std::numbers::pi / 180.0;
      rim.push_back(g.add(Vec3(std::cos(a), std::sin(a), 0)));
    }
    for (int s = 0; s < 4; ++s) g.triangles.push_back({apex, rim[size_t(s)], rim[size_t(s) + 1]});
  }
  return make_textured("bowtie", g.positions, g.triangles);
}

/// Segments of the edge the three sheets of non_manifold_edge() share.
constexpr int kSpineSegments = 4;

/// Three 4 x kSpineSegments sheets (32 triangles each) at 120 degrees around the z axis, sharing the
/// vertices (and so every edge) of the spine x = y = 0: kSpineSegments edges with three triangles each.
inline TexturedMesh non_manifold_edge() {
  Geometry g;
  const int n = 4, m = kSpineSegments;
  std::vector<uint32_t> spine;
  for (int j = 0; j <= m; ++j) spine.push_back(g.add(Vec3(0, 0, double(j) / m)));
  for (int sheet = 0; sheet < 3; ++sheet) {
    const double a = 2 * std::numbers::pi * sheet / 3 + 0.3;
    const Vec3 dir(std::cos(a), std::sin(a), 0);
    std::vector<uint32_t> id((n + 1) * (m + 1));
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i <= n; ++i)
        id[size_t(j * (n + 1) + i)] = i == 0 ? spine[size_t(j)] : g.add(dir * (double(i) / n) + Vec3(0, 0, double(j) / m));
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t p00 = id[size_t(j * (n + 1) + i)], p10 = id[size_t(j * (n + 1) + i + 1)],
                       p11 = id[size_t((j + 1) * (n + 1) + i + 1)], p01 = id[size_t((j + 1) * (n + 1) + i)];
        g.triangles.push_back({p00, p10, p11});
        g.triangles.push_back({p00, p11, p01});
      }
  }
  return make_textured("non_manifold_edge", g.positions, g.triangles);
}

/// What degenerate_disk() adds to its 6 x 16 disk.
constexpr size_t kAddedZeroArea = 4;
constexpr size_t kAddedDuplicates = 6;

/// A 6-ring, 16-segment disk plus kAddedZeroArea zero-area triangles (a repeated index, one vertex
/// three times, three exactly collinear new vertices, two indices of bit-equal positions) and
/// kAddedDuplicates duplicates (verbatim copies, a copy twice, a cyclic rotation, a copy through a
/// second vertex at a bit-equal position). Only the 176 disk triangles carry area.
inline TexturedMesh degenerate_disk() {
  Geometry g = disk_geometry(6, 16);
  const std::vector<Tri> base = g.triangles;
  // zero area
  g.triangles.push_back({base[3][0], base[3][1], base[3][0]});
  g.triangles.push_back({base[5][2], base[5][2], base[5][2]});
  const uint32_t c0 = g.add(Vec3(2, 0, 0.5)), c1 = g.add(Vec3(3, 0, 0.5)), c2 = g.add(Vec3(4, 0, 0.5));
  g.triangles.push_back({c0, c1, c2});
  const uint32_t twin5 = g.add(g.positions[5]);  // same position as vertex 5: welded into it
  g.triangles.push_back({5, twin5, 7});
  // duplicates
  g.triangles.push_back(base[0]);
  g.triangles.push_back(base[10]);
  g.triangles.push_back(base[10]);
  g.triangles.push_back(base[20]);
  g.triangles.push_back({base[30][1], base[30][2], base[30][0]});
  const Tri t40 = base[40];
  const uint32_t twin = g.add(g.positions[t40[1]]);
  g.triangles.push_back({t40[0], twin, t40[2]});
  return make_textured("degenerate_disk", g.positions, g.triangles);
}

/// A 20 x 12 grid sheared by 4 (x += 4 y) with a gentle bump in z: every triangle has an angle near
/// 166 degrees opposite the long diagonal, whose cotangent weight is therefore negative.
inline TexturedMesh obtuse_strip() {
  const int nu = 21, nv = 13;
  auto g = param_grid(nu, nv, false, false, [&](int i, int j) {
    const double x = double(i) / (nu - 1), y = double(j) / (nv - 1) * 0.6;
    return Vec3(x + 4.0 * y, y, 0.15 * std::sin(3 * x) * std::cos(4 * y));
  });
  return make_textured("obtuse_strip", g.positions, g.triangles);
}

inline TexturedMesh single_triangle() {
  return make_textured("single_triangle", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 0.8, 0.1)}, {Tri{0, 1, 2}});
}

inline TexturedMesh two_triangles() {
  return make_textured("two_triangles", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0.2), Vec3(0, 1, 0)}, {Tri{0, 1, 2}, Tri{0, 2, 3}});
}

/// Several components in one mesh: a torus, a small disk and two tiny floaters (a triangle and a quad).
inline TexturedMesh multi_component() {
  Geometry g = torus_geometry(32, 16);
  g.append(disk_geometry(4, 12, 0.5), Vec3(3, 0, 0));
  Geometry tri;
  tri.positions = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.03, 0.08, 0.01)};
  tri.triangles = {Tri{0, 1, 2}};
  g.append(tri, Vec3(0, 3, 0));
  Geometry quad;
  quad.positions = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.1, 0.1, 0.02), Vec3(0, 0.1, 0)};
  quad.triangles = {Tri{0, 1, 2}, Tri{0, 2, 3}};
  g.append(quad, Vec3(-3, 0, 0));
  return make_textured("multi_component", g.positions, g.triangles);
}

/// Number of handles of holey_slab().
constexpr int kSlabHandles = 25;

inline TexturedMesh holey_slab() {
  auto g = holey_slab_geometry();
  return make_textured("holey_slab", g.positions, g.triangles);
}

/// A deep disk: the open cylinder with its bottom end capped by a fan (a cup, or a vase), so its far
/// end lies much deeper than a flat disk of the same perimeter would reach.
inline TexturedMesh cup() {
  const int segments = 32;
  Geometry g = cylinder_geometry(12, segments, 0.5, 2.0);
  const uint32_t centre = g.add(Vec3(0, 0, -1.0));
  for (int i = 0; i < segments; ++i) g.triangles.push_back({centre, uint32_t((i + 1) % segments), uint32_t(i)});
  return make_textured("cup", g.positions, g.triangles);
}

/// A Mobius strip of 2 x 40 triangles, consistently oriented everywhere except across the one edge
/// where the strip closes with a half twist (no orientation can avoid such an edge).
inline TexturedMesh mobius_strip() {
  const int n = 40;
  Geometry g;
  for (int i = 0; i < n; ++i)
    for (double w : {-0.3, 0.3}) {
      const double t = 2 * std::numbers::pi * i / n;
      g.add(Vec3((1 + w * std::cos(t / 2)) * std::cos(t), (1 + w * std::cos(t / 2)) * std::sin(t), w * std::sin(t / 2)));
    }
  for (int i = 0; i < n; ++i) {
    const uint32_t a = uint32_t(2 * i), b = a + 1;
    // After a full turn the half twist swaps the strip's two sides: vertex (t = 2 pi, w) is (0, -w).
    const uint32_t c = i + 1 < n ? a + 2 : 1, d = i + 1 < n ? a + 3 : 0;
    g.triangles.push_back({a, c, d});
    g.triangles.push_back({a, d, b});
  }
  return make_textured("mobius_strip", g.positions, g.triangles);
}

/// Number of floaters sphere_with_floaters() scatters around its sphere.
constexpr int kFloaters = 150;

/// A UV sphere (16 x 16) and kFloaters tiny separate triangles (sides ~0.02) on a helix around it:
/// a scan with its usual debris, kFloaters + 1 components of very unequal area.
inline TexturedMesh sphere_with_floaters() {
  Geometry g = sphere_geometry(16, 16);
  for (int i = 0; i < kFloaters; ++i) {
    const double a = 2 * std::numbers::pi * i / 37.0, z = -1.5 + 3.0 * i / kFloaters;
    const Vec3 c(2 * std::cos(a), 2 * std::sin(a), z);
    Geometry t;
    t.positions = {Vec3(0, 0, 0), Vec3(0.02, 0, 0), Vec3(0.005, 0.015, 0.004)};
    t.triangles = {Tri{0, 1, 2}};
    g.append(t, c);
  }
  return make_textured("sphere_with_floaters", g.positions, g.triangles);
}

/// Every catalogue entry by name, in a fixed order.
inline std::vector<std::pair<std::string, std::function<TexturedMesh()>>> catalogue() {
  return {{"disk", disk},
          {"sphere", sphere},
          {"open_cylinder", open_cylinder},
          {"sphere_with_holes", sphere_with_holes},
          {"torus", torus},
          {"double_torus", double_torus},
          {"holey_slab", holey_slab},
          {"bowtie", bowtie},
          {"non_manifold_edge", non_manifold_edge},
          {"degenerate_disk", degenerate_disk},
          {"obtuse_strip", obtuse_strip},
          {"single_triangle", single_triangle},
          {"two_triangles", two_triangles},
          {"multi_component", multi_component},
          {"cup", cup},
          {"mobius_strip", mobius_strip},
          {"sphere_with_floaters", sphere_with_floaters}};
}

}  // namespace tightex::testing
