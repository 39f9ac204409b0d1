// Vertex-coloured variants of textured models, made by the tests' own code (no scanner in CI writes
// them): each vertex takes the mean of its texture at the corners that share it, as a scanner that
// colours vertices from its photographs would, and the model is written as PLY (red green blue as
// uchar) or OBJ (v x y z r g b).
#pragma once
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/image.hpp"
#include "core/mesh.hpp"

namespace tightex::testing {

/// `textured` without texture: per vertex the mean texture colour of its corners (in [0, 1]), copied
/// to corner_color; no materials, no textures, corner_uv all (0, 0).
inline TexturedMesh vertex_coloured(const TexturedMesh& textured) {
  std::vector<std::array<double, 4>> sum(textured.num_vertices(), {0, 0, 0, 0});
  for (size_t t = 0; t < textured.num_triangles(); ++t) {
    const int32_t m = textured.face_material[t];
    const int tex = m < 0 ? -1 : textured.materials[size_t(m)].texture;
    for (int k = 0; k < 3; ++k) {
      std::array<double, 4>& s = sum[textured.triangles[t][size_t(k)]];
      std::array<float, 4> c{255, 255, 255, 255};
      if (tex >= 0) {
        const Vec2 uv = textured.sampled_uv(t, k);
        c = sample_bilinear(textured.textures[size_t(tex)].image, uv.x(), uv.y());
      }
      for (int ch = 0; ch < 3; ++ch) s[size_t(ch)] += c[size_t(ch)] / 255.0;
      s[3] += 1;
    }
  }
  TexturedMesh m;
  m.source = textured.source;
  m.positions = textured.positions;
  m.triangles = textured.triangles;
  m.corner_uv.assign(3 * m.num_triangles(), Vec2::Zero());
  m.face_material.assign(m.num_triangles(), -1);
  for (const Tri& t : m.triangles)
    for (const uint32_t v : t) {
      const std::array<double, 4>& s = sum[v];
      m.corner_color.push_back({float(s[0] / s[3]), float(s[1] / s[3]), float(s[2] / s[3]), 1.0f});
    }
  return m;
}

/// The vertex colours of a mesh made by vertex_coloured (one per vertex: the first corner's).
inline std::vector<std::array<float, 4>> colours_per_vertex(const TexturedMesh& m) {
  std::vector<std::array<float, 4>> c(m.num_vertices(), {0, 0, 0, 1});
  for (size_t t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) c[m.triangles[t][size_t(k)]] = m.corner_color[3 * t + size_t(k)];
  return c;
}

inline uint8_t colour_byte(float x) { return uint8_t(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); }

/// Writes `m` (from vertex_coloured) as a binary little-endian PLY with uchar vertex colours.
inline void write_vertex_coloured_ply(const TexturedMesh& m, const std::string& path) {
  std::ofstream f(path, std::ios::binary);
  f << "ply\nformat binary_little_endian 1.0\nelement vertex " << m.num_vertices()
    << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
    << "element face " << m.num_triangles() << "\nproperty list uchar int vertex_indices\nend_header\n";
  const auto colours = colours_per_vertex(m);
  for (size_t v = 0; v < m.num_vertices(); ++v) {
    for (int k = 0; k < 3; ++k) {
      const float x = float(m.positions[v][k]);
      f.write(reinterpret_cast<const char*>(&x), 4);
    }
    for (int ch = 0; ch < 3; ++ch) f.put(char(colour_byte(colours[v][size_t(ch)])));
  }
  for (const Tri& t : m.triangles) {
    f.put(char(3));
    for (const uint32_t v : t) {
      const int32_t i = int32_t(v);
      f.write(reinterpret_cast<const char*>(&i), 4);
    }
  }
}

/// Writes `m` (from vertex_coloured) as an OBJ with `v x y z r g b` (r g b in [0, 1]) and no vt.
inline void write_vertex_coloured_obj(const TexturedMesh& m, const std::string& path) {
  std::ofstream f(path);
  const auto colours = colours_per_vertex(m);
  char line[256];
  for (size_t v = 0; v < m.num_vertices(); ++v) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.6f %.6f %.6f\n", m.positions[v].x(), m.positions[v].y(), m.positions[v].z(),
                  colours[v][0], colours[v][1], colours[v][2]);
    f << line;
  }
  for (const Tri& t : m.triangles) f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

}  // namespace tightex::testing
