// What each fuzz harness does with one input, shared by the libFuzzer entry points (fuzz_*.cpp, clang)
// and by the corpus replay test (tests/test_fuzz_corpus.cpp, the normal build), so a file checked into
// fuzz/corpus/ is a regression test on every build.
//
// Each run_* returns kAccepted or kRefused (an InputError: the expected answer to bad input) and checks
// what the entry point promises about what it returns; a broken promise throws Violation. Any other
// exception (InternalError, bad_alloc, ...) propagates to the caller, which treats it as a finding.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "fuzz_common.hpp"
#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex_fuzz {

using namespace tightex;

enum class Outcome { kAccepted, kRefused };

/// A returned value that breaks the function's documented guarantee.
class Violation : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

inline void require(bool ok, const std::string& what) {
  if (!ok) throw Violation(what);
}

// ---------------------------------------------------------------------------------------------------
// fuzz_obj: the OBJ/MTL reader.
//
// Input: OBJ text, optionally followed by kMtlSeparator and MTL text. The OBJ is written as in.obj, the
// MTL (when there is one) as m.mtl, into a folder that also holds textures the MTL can name: t.png
// (4x4 RGBA), t.jpg, bad.png (corrupt), "sub dir/t 2.png", and a folder d/.

inline constexpr std::string_view kMtlSeparator = "\n#---mtl---\n";

inline const fs::path& obj_dir() {
  static const fs::path dir = [] {
    const fs::path d = scratch_dir("fuzz_obj");
    Image img(4, 4);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) img.at(x, y) = {uint8_t(x * 60), uint8_t(y * 60), 128, uint8_t(255 - x)};
    save_image((d / "t.png").string(), img, ImageFormat::kPng);
    save_image((d / "t.jpg").string(), img, ImageFormat::kJpeg);
    fs::create_directories(d / "sub dir");
    fs::create_directories(d / "d");
    save_image((d / "sub dir" / "t 2.png").string(), img, ImageFormat::kPng);
    write_file(d / "bad.png", "\x89PNG\r\n\x1a\n garbage");
    return d;
  }();
  return dir;
}

/// The guarantees read_obj (and read_ply) documents (tightex/io.hpp).
inline void check_mesh(const TexturedMesh& m, bool textures_loaded) {
  require(!m.triangles.empty(), "the reader returned no triangles");
  for (const Vec3& p : m.positions) require(p.allFinite() && p.cwiseAbs().maxCoeff() <= 1e15, "position not finite or absurd");
  for (const Tri& t : m.triangles)
    for (uint32_t v : t) require(v < m.positions.size(), "vertex index out of range");
  require(m.corner_uv.size() == 3 * m.triangles.size(), "corner_uv is not 3 per triangle");
  for (const Vec2& uv : m.corner_uv) require(uv.allFinite(), "texture coordinate not finite");
  require(m.corner_normal.empty() || m.corner_normal.size() == 3 * m.triangles.size(), "corner_normal is not 3 per triangle");
  for (const Vec3& n : m.corner_normal) require(n.allFinite(), "normal not finite");
  require(m.face_material.size() == m.triangles.size(), "face_material is not 1 per triangle");
  for (int32_t f : m.face_material) require(f >= -1 && f < int32_t(m.materials.size()), "face material out of range");
  for (const Material& mat : m.materials) {
    require(mat.texture >= -1 && mat.texture < int(m.textures.size()), "material texture out of range");
    for (double d : mat.uv_scale) require(std::isfinite(d), "map_Kd -s not finite");
    for (double d : mat.uv_offset) require(std::isfinite(d), "map_Kd -o not finite");
  }
  for (const Texture& t : m.textures) {
    if (!textures_loaded) continue;
    require(!t.image.empty() && t.image.pixels.size() == size_t(t.image.width) * size_t(t.image.height), "texture not loaded");
  }
}

inline Outcome run_obj(const uint8_t* data, size_t size) {
  const fs::path& dir = obj_dir();
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  const size_t sep = in.find(kMtlSeparator);
  write_file(dir / "in.obj", in.substr(0, sep));
  std::error_code ec;
  if (sep != std::string_view::npos)
    write_file(dir / "m.mtl", in.substr(sep + kMtlSeparator.size()));
  else
    fs::remove(dir / "m.mtl", ec);
  const std::string path = (dir / "in.obj").string();
  ModelReadOptions options;
  options.max_texture_pixels = size_t(1) << 20;
  options.load_textures = false;
  // Parsed as one stretch and with every line a stretch of its own (read_obj_in_chunks): the same
  // mesh or the same message.
  std::string by_line_error;
  TexturedMesh by_line;
  try {
    by_line = read_obj_in_chunks(path, options, nullptr, 1);
  } catch (const InputError& e) {
    by_line_error = e.what();
  }
  try {
    const TexturedMesh mesh = read_obj_in_chunks(path, options, nullptr, size_t(-1));
    check_mesh(mesh, false);
    require(by_line_error.empty(), "refused only when cut into lines: " + by_line_error);
    require(mesh.positions == by_line.positions && mesh.triangles == by_line.triangles && mesh.corner_uv == by_line.corner_uv &&
                mesh.corner_normal == by_line.corner_normal && mesh.corner_color == by_line.corner_color &&
                mesh.face_material == by_line.face_material && mesh.materials.size() == by_line.materials.size(),
            "a different mesh when cut into lines");
  } catch (const InputError& e) {
    require(by_line_error == e.what(), std::string("a different message when cut into lines: ") + e.what() + " / " + by_line_error);
    return Outcome::kRefused;
  }
  // The same file with its textures: parsing is the same, so only texture loading can refuse it now.
  options.load_textures = true;
  try {
    check_mesh(read_obj(path, options), true);
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  return Outcome::kAccepted;
}

// ---------------------------------------------------------------------------------------------------
// fuzz_ply: the PLY reader.
//
// Input: a PLY file (any format), written as in.ply into the fuzz_obj folder, whose textures a
// `comment TextureFile` line can name (t.png, t.jpg, bad.png, "sub dir/t 2.png", the folder d/).

inline Outcome run_ply(const uint8_t* data, size_t size) {
  const fs::path& dir = obj_dir();
  write_file(dir / "in.ply", std::string_view(reinterpret_cast<const char*>(data), size));
  const std::string path = (dir / "in.ply").string();
  ModelReadOptions options;
  options.max_texture_pixels = size_t(1) << 20;
  options.load_textures = false;
  try {
    check_mesh(read_ply(path, options), false);
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  // Parsing is the same with the textures, so only texture loading can refuse it now.
  options.load_textures = true;
  try {
    check_mesh(read_ply(path, options), true);
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  return Outcome::kAccepted;
}

// ---------------------------------------------------------------------------------------------------
// fuzz_gltf: the glTF reader, and the writer on what it read.
//
// Input: a .glb or .gltf file (by content: a GLB starts with "glTF"), written as in.glb into the fuzz_obj
// folder, whose files a URI can name (t.png, t.jpg, bad.png, "sub%20dir/t%202.png", the folder d/).
// What is read is written back by write_gltf as a GLB (each triangle its own input triangle), which
// must read back with as many triangles.

inline Outcome run_gltf(const uint8_t* data, size_t size) {
  const fs::path& dir = obj_dir();
  write_file(dir / "in.glb", std::string_view(reinterpret_cast<const char*>(data), size));
  const std::string path = (dir / "in.glb").string();
  ModelReadOptions options;
  options.max_texture_pixels = size_t(1) << 20;
  options.load_textures = false;
  try {
    check_mesh(read_gltf(path, options), false);
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  // The scene in world space too (an OBJ or PLY output's reading): the same document, every instance.
  ModelReadOptions flat = options;
  flat.flatten_scene = true;
  try {
    const TexturedMesh world = read_gltf(path, flat);
    check_mesh(world, false);
    require(world.source_mesh.size() == world.num_triangles(), "a flattened scene without a source mesh per triangle");
  } catch (const InputError&) {
    // A scene whose instances hold too many triangles may be refused flattened alone.
  }
  options.load_textures = true;
  TexturedMesh mesh;
  try {
    mesh = read_gltf(path, options);
    check_mesh(mesh, true);
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  mesh.input_triangle.resize(mesh.num_triangles());
  for (uint32_t t = 0; t < uint32_t(mesh.num_triangles()); ++t) mesh.input_triangle[t] = t;
  const fs::path out = dir / "out";
  write_gltf(mesh, out.string(), "out", ImageFormat::kPng, GltfContainer::kGlb);
  const TexturedMesh back = read_gltf((out / "out.glb").string(), options);
  require(back.num_triangles() == mesh.num_triangles(), "the written glTF reads back with another triangle count");
  return Outcome::kAccepted;
}

// ---------------------------------------------------------------------------------------------------
// fuzz_image: decode_image on the raw bytes (PNG, JPEG by content; BMP, TGA, PSD, GIF, PNM via stb), and
// image_dimensions (the header-only size the memory guard uses) on the same bytes as a file.

inline constexpr size_t kImageMaxPixels = size_t(1) << 20;

inline Outcome run_image(const uint8_t* data, size_t size) {
  const fs::path file = scratch_dir("fuzz_image") / "image";
  write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  const auto [w, h] = image_dimensions(file.string());
  try {
    const Image img = decode_image(data, size, "fuzz-image", kImageMaxPixels);
    require(img.width > 0 && img.height > 0 && size_t(img.width) * size_t(img.height) <= kImageMaxPixels, "decoded image has a bad size");
    require(img.pixels.size() == size_t(img.width) * size_t(img.height), "pixel count is not width x height");
    // The memory guard trusts the header: it must not give a size other than the one decoded.
    require((w == 0 && h == 0) || (w == img.width && h == img.height), "image_dimensions " + std::to_string(w) + "x" + std::to_string(h) +
                                                                           " but decoded " + std::to_string(img.width) + "x" +
                                                                           std::to_string(img.height));
  } catch (const InputError&) {
    return Outcome::kRefused;
  }
  return Outcome::kAccepted;
}

// ---------------------------------------------------------------------------------------------------
// fuzz_pipeline: tightex::optimize and measure on a tiny mesh made from the bytes (missing bytes read as 0):
//   byte 0  flags: bit 0 per-component layout, bit 1 holes cut, bit 2 textured, bit 3 1x1 texture,
//           bits 4-5 size (64, 16, 8, 128), bit 6 UVs in [-1, 2] instead of [0, 1], bit 7 -s/-o follow
//   byte 1  vertex count - 3 (mod 62): 3..64 vertices
//   byte 2  triangle count - 1 (mod 64): 1..64 triangles
//   byte 3  bits 0-2 coordinate scale: 1, 1e-3, 1e3, 1e-12, 1e12, 1e-150, 6e13, 1e-300;
//           bits 3-4 map: detail, area, texel, harmonic; bits 5-6 (mod 3) times every triangle is split in
//           four at its edges' midpoints, after the bytes are read (up to 1024 triangles: the area map's
//           density-equalising flow starts at 100 faces)
//   [bit 7] 4 bytes: map_Kd -s u v, -o u v, each (int8 / 16) or an extreme value
//   vertices: 3 signed bytes each, coordinate = int8 / 8 * scale
//   triangles: 3 bytes each, vertex index mod count
//   corner UVs: 2 bytes each, byte / 255 (mapped to [-1, 2] with bit 6)

struct PipelineOutcome {
  Outcome outcome = Outcome::kAccepted;
  size_t lost = 0, flipped = 0;
  /// Components the method could not map, kept with their input UVs (Plan::kept); their triangles may
  /// be flipped or outside [0,1] as the input's were, so `flipped` is not counted when kept > 0.
  size_t kept = 0;
  std::string kept_reason;
};

inline TexturedMesh mesh_from_bytes(const uint8_t* data, size_t size, Options& options) {
  size_t at = 0;
  auto byte = [&]() -> uint8_t { return at < size ? data[at++] : 0; };
  const uint8_t flags = byte();
  const size_t nv = 3 + byte() % 62, nt = 1 + byte() % 64;
  static constexpr double kScales[8] = {1, 1e-3, 1e3, 1e-12, 1e12, 1e-150, 6e13, 1e-300};
  const uint8_t shape = byte();
  const double scale = kScales[shape % 8];
  static constexpr MapKind kMaps[4] = {MapKind::kDetail, MapKind::kArea, MapKind::kTexel, MapKind::kHarmonic};
  options.map = kMaps[(shape >> 3) & 3];
  const int splits = ((shape >> 5) & 3) % 3;
  options.layout = (flags & 1) ? Layout::kPerComponent : Layout::kAtlas;
  options.holes = (flags & 2) ? HoleMode::kCut : HoleMode::kFill;
  static constexpr int kSizes[4] = {64, 16, 8, 128};
  options.size = kSizes[(flags >> 4) & 3];
  // The docs/metrics.md figures are measured below with fewer PSNR samples: optimize's own measure takes
  // 200k samples, which costs ~90% of a run under the sanitizers and covers no more code.
  options.measure = false;

  TexturedMesh m;
  m.source = "fuzz-mesh";
  Material mat;
  mat.name = "m";
  if (flags & 0x80) {
    auto value = [&]() -> double {
      const auto b = static_cast<int8_t>(byte());
      static constexpr double kExtreme[4] = {1e300, -1e300, 1e-300, 0.0};
      return b >= -124 ? b / 16.0 : kExtreme[b + 128];
    };
    mat.uv_scale = {value(), value()};
    mat.uv_offset = {value(), value()};
  }
  for (size_t v = 0; v < nv; ++v) {
    const double x = static_cast<int8_t>(byte()), y = static_cast<int8_t>(byte()), z = static_cast<int8_t>(byte());
    m.positions.emplace_back(x / 8 * scale, y / 8 * scale, z / 8 * scale);
  }
  for (size_t t = 0; t < nt; ++t) m.triangles.push_back({uint32_t(byte() % nv), uint32_t(byte() % nv), uint32_t(byte() % nv)});
  for (size_t c = 0; c < 3 * nt; ++c) {
    double u = byte() / 255.0, v = byte() / 255.0;
    if (flags & 0x40) u = 3 * u - 1, v = 3 * v - 1;
    m.corner_uv.emplace_back(u, v);
  }
  for (int round = 0; round < splits; ++round) {
    // Each triangle in four: a vertex at each edge's midpoint (shared by the edge's triangles, keyed by
    // its two vertices; a repeated index gives a coincident vertex), texture coordinates per corner.
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto [it, added] = midpoint.try_emplace({key.first, key.second}, uint32_t(m.positions.size()));
      if (added) m.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
      return it->second;
    };
    std::vector<Tri> triangles;
    std::vector<Vec2> uvs;
    for (size_t t = 0; t < m.triangles.size(); ++t) {
      const Tri& c = m.triangles[t];
      const Vec2* u = &m.corner_uv[3 * t];
      const uint32_t ab = mid(c[0], c[1]), bc = mid(c[1], c[2]), ca = mid(c[2], c[0]);
      const Vec2 uab = 0.5 * (u[0] + u[1]), ubc = 0.5 * (u[1] + u[2]), uca = 0.5 * (u[2] + u[0]);
      triangles.insert(triangles.end(), {Tri{c[0], ab, ca}, Tri{ab, c[1], bc}, Tri{ca, bc, c[2]}, Tri{ab, bc, ca}});
      uvs.insert(uvs.end(), {u[0], uab, uca, uab, u[1], ubc, uca, ubc, u[2], uab, ubc, uca});
    }
    m.triangles.swap(triangles);
    m.corner_uv.swap(uvs);
  }
  const size_t nt_all = m.triangles.size();
  if (flags & 4) {
    Image img(4, 4);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) img.at(x, y) = {uint8_t(x * 60 + 10), uint8_t(y * 60 + 10), 128, 255};
    if (flags & 8) img = Image(1, 1, img.at(1, 2));
    m.textures.push_back(Texture{"fuzz-texture", std::move(img)});
    mat.texture = 0;
    m.materials.push_back(mat);
    m.face_material.assign(nt_all, 0);
  } else {
    m.face_material.assign(nt_all, -1);
  }
  return m;
}

inline PipelineOutcome run_pipeline(const uint8_t* data, size_t size) {
  Options options;
  const TexturedMesh mesh = mesh_from_bytes(data, size, options);
  PipelineOutcome out;
  try {
    const Result r = optimize(mesh, options);
    const TexturedMesh& o = r.output;
    for (const auto& c : report_json(r.report)["components"])
      if (c["kept_original_uvs"].get<bool>()) {
        if (out.kept++ == 0) out.kept_reason = c["kept_reason"].get<std::string>();
      }
    require(o.corner_uv.size() == 3 * o.triangles.size(), "output corner_uv is not 3 per triangle");
    require(o.face_material.size() == o.triangles.size(), "output face_material is not 1 per triangle");
    for (size_t t = 0; t < o.triangles.size(); ++t) {
      require(o.face_material[t] >= 0 && size_t(o.face_material[t]) < o.materials.size(), "output material out of range");
      if (o.materials[size_t(o.face_material[t])].name.rfind("kept_", 0) == 0) continue;  // input UVs, kept
      for (int k = 0; k < 3; ++k) {
        const Vec2& uv = o.corner_uv[3 * t + size_t(k)];
        require(uv.allFinite() && uv.minCoeff() >= 0 && uv.maxCoeff() <= 1, "output texture coordinate outside [0,1]");
      }
    }
    for (const Texture& t : o.textures) require(!t.image.empty(), "output texture empty");
    const Metrics m = measure(mesh, o, 2000);
    (void)to_json(m);
    out.lost = m.lost_triangles;
    out.flipped = out.kept > 0 ? 0 : m.flipped;
  } catch (const InputError&) {
    out.outcome = Outcome::kRefused;
  }
  return out;
}

}  // namespace tightex_fuzz
