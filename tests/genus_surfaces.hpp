// Generated surfaces of any genus whose UV atlas gives every triangle its own texture space: the
// paper's extreme case (Fig. 9, a vase "formed by individual triangles, each with its own distinct
// texture space"). Used by tests/test_genus.cpp and written to OBJ by tools/make_genus.cpp.
//
// Two families of closed polycube surfaces, gently bent so that no two triangles are congruent in the
// same way (cotangent weights vary), each vertex-manifold by construction:
//  * perforated_plate(g): a plate with g through-holes in a grid: big, real handles;
//  * arched_block(g): a thick block with g small arches (staples) standing on its top face: a
//    sphere-like body with g tiny handles, the topological noise of a scan.
// per_triangle_atlas() then gives each triangle a square cell of its own in a grid over the texture
// (a similar copy of the triangle, 2-texel gutter), and paints every cell with a smooth colour
// function of the 3D position (extrapolated into the gutter, so bilinear samples at a triangle's edge
// stay true). Where a re-parameterized result keeps the resolution, its surface PSNR is high; where it
// crowds a region, the colour there blurs and the PSNR drops.
#pragma once
#include <cmath>
#include <numbers>
#include <string>

#include "mesh_catalogue.hpp"

namespace tightex::testing {

/// The genera the tests and tools/make_genus.cpp cover: plates, and arched blocks (up to the genus 38
/// that phone scans reach from reconstruction noise).
inline constexpr int kPlateGenera[] = {1, 2, 3, 5, 8, 13, 25};
inline constexpr int kArchGenera[] = {1, 5, 25, 38};

/// Smooth bend of a polycube: z is lifted by a low dome over (x, y), x and y stay. The lift depends on
/// (x, y) only, so the map is injective and the surface stays embedded.
inline void bend(Geometry& g, double amplitude) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const Vec3& p : g.positions) x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  for (Vec3& p : g.positions) {
    const double s = (p.x() - x0) / std::max(x1 - x0, 1e-12), t = (p.y() - y0) / std::max(y1 - y0, 1e-12);
    p.z() += amplitude * (std::sin(std::numbers::pi * s) * std::sin(std::numbers::pi * t) + 0.3 * s * t);
  }
}

/// A plate (thickness one voxel) of (2 cols + 1) x (2 rows + 1) voxels, cols = ceil(sqrt(genus)),
/// with the first `genus` (odd, odd) voxels in row order taken out: genus through-holes, each face of
/// a voxel split into k x k squares.
inline Geometry perforated_plate_geometry(int genus, int k = 2) {
  const int cols = std::max(1, int(std::ceil(std::sqrt(double(genus))))), rows = std::max(1, (genus + cols - 1) / cols);
  std::vector<std::array<int, 3>> voxels;
  for (int y = 0; y <= 2 * rows; ++y)
    for (int x = 0; x <= 2 * cols; ++x) {
      const bool hole = x % 2 == 1 && y % 2 == 1 && (y / 2) * cols + x / 2 < genus;
      if (!hole) voxels.push_back({x, y, 0});
    }
  Geometry g = polycube_geometry(voxels, k, 0.2);
  bend(g, 0.15 * 0.2 * (2 * cols + 1));
  return g;
}

/// A block of (4 cols + 1) x (2 rows + 1) x 2 voxels with `genus` arches on its top face: voxels
/// (x, y, 2), (x, y, 3), (x + 1, y, 3), (x + 2, y, 3), (x + 2, y, 2) over the empty (x + 1, y, 2), at
/// x = 1 + 4 i, y = 1 + 2 j. Arches are two voxels apart, so none touches another.
inline Geometry arched_block_geometry(int genus, int k = 1) {
  const int cols = std::max(1, int(std::ceil(std::sqrt(double(genus))))), rows = std::max(1, (genus + cols - 1) / cols);
  std::vector<std::array<int, 3>> voxels;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y <= 2 * rows; ++y)
      for (int x = 0; x <= 4 * cols; ++x) voxels.push_back({x, y, z});
  for (int a = 0; a < genus; ++a) {
    const int x = 1 + 4 * (a % cols), y = 1 + 2 * (a / cols);
    for (auto v : {std::array{x, y, 2}, {x, y, 3}, {x + 1, y, 3}, {x + 2, y, 3}, {x + 2, y, 2}}) voxels.push_back(v);
  }
  Geometry g = polycube_geometry(voxels, k, 0.2);
  bend(g, 0.1 * 0.2 * (4 * cols + 1));
  return g;
}

/// The true surface colour: smooth in 3D, about two periods across the model's bounding box in each
/// channel, different in each channel, so a colour at the wrong place scores low.
struct SurfaceColour {
  Vec3 lo, extent;
  explicit SurfaceColour(const std::vector<Vec3>& positions) {
    Vec3 hi = Vec3::Constant(-1e300);
    lo = Vec3::Constant(1e300);
    for (const Vec3& p : positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    extent = (hi - lo).cwiseMax(Vec3::Constant(1e-12));
  }
  Rgba8 operator()(const Vec3& p) const {
    const Vec3 q = (p - lo).cwiseQuotient(extent);
    const double two_pi = 2 * std::numbers::pi;
    auto byte = [](double x) { return uint8_t(std::lround(std::clamp(127.5 + 110.0 * x, 0.0, 255.0))); };
    return Rgba8{byte(std::sin(two_pi * (2.0 * q.x() + 0.7 * q.z()))), byte(std::sin(two_pi * 2.0 * q.y() + 1.0)),
                 byte(std::cos(two_pi * 1.5 * (q.x() + q.y() + q.z()))), 255};
  }
};

/// Wraps geometry as a TexturedMesh (see make_textured for the fields) whose atlas gives every
/// triangle its own `cell` x `cell` texel square in a grid (row-major from the top left), the
/// triangle's similar copy fitted inside a 2-texel gutter, and the texture painted per cell with
/// SurfaceColour of the barycentric 3D point (extrapolated over the whole cell).
inline TexturedMesh per_triangle_atlas(std::string name, const Geometry& g, int cell = 16) {
  TexturedMesh m = make_textured(std::move(name), g.positions, g.triangles, Image(1, 1));
  const size_t n = m.num_triangles();
  const int cols = std::max(1, int(std::ceil(std::sqrt(double(n))))), rows = int((n + size_t(cols) - 1) / size_t(cols));
  const int W = cols * cell, H = rows * cell;
  constexpr double kGutter = 2.0;
  Image img(W, H, Rgba8{0, 0, 0, 255});
  const SurfaceColour colour(m.positions);
  for (size_t t = 0; t < n; ++t) {
    const Vec3 &a = m.positions[m.triangles[t][0]], &b = m.positions[m.triangles[t][1]], &c = m.positions[m.triangles[t][2]];
    // Isometric copy: a at the origin, b on the x axis, c above it (counter-clockwise).
    const Vec3 e1 = b - a, e2 = c - a;
    const double l1 = e1.norm();
    std::array<Vec2, 3> p{Vec2(0, 0), Vec2(l1, 0), Vec2(e2.dot(e1) / l1, e1.cross(e2).norm() / l1)};
    Vec2 lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]), hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
    const double scale = (cell - 2 * kGutter) / std::max((hi - lo).maxCoeff(), 1e-300);
    // Cell (cx, cy) in texels, y down; the copy in texel coordinates (x right, y up inside the cell).
    const int cx = int(t % size_t(cols)), cy = int(t / size_t(cols));
    std::array<Vec2, 3> px;  // texel coordinates, x right, y down (image rows)
    for (int k = 0; k < 3; ++k) {
      const Vec2 q = (p[size_t(k)] - lo) * scale;
      px[size_t(k)] = Vec2(cx * cell + kGutter + q.x(), (cy + 1) * cell - kGutter - q.y());
      m.corner_uv[3 * t + size_t(k)] = Vec2(px[size_t(k)].x() / W, 1.0 - px[size_t(k)].y() / H);
    }
    // Paint the cell: barycentric coordinates of each texel centre (in the y-down frame the triangle
    // is clockwise; barycentrics do not care).
    const double det = (px[1] - px[0]).x() * (px[2] - px[0]).y() - (px[1] - px[0]).y() * (px[2] - px[0]).x();
    for (int y = cy * cell; y < (cy + 1) * cell; ++y)
      for (int x = cx * cell; x < (cx + 1) * cell; ++x) {
        const Vec2 d = Vec2(x + 0.5, y + 0.5) - px[0];
        const double l1b = (d.x() * (px[2] - px[0]).y() - d.y() * (px[2] - px[0]).x()) / det;
        const double l2b = ((px[1] - px[0]).x() * d.y() - (px[1] - px[0]).y() * d.x()) / det;
        img.at(x, y) = colour((1 - l1b - l2b) * a + l1b * b + l2b * c);
      }
  }
  m.textures[0].image = std::move(img);
  return m;
}

inline TexturedMesh perforated_plate(int genus) {
  return per_triangle_atlas("plate_g" + std::to_string(genus), perforated_plate_geometry(genus));
}

inline TexturedMesh arched_block(int genus) { return per_triangle_atlas("arches_g" + std::to_string(genus), arched_block_geometry(genus)); }

}  // namespace tightex::testing
