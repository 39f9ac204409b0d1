// texture_vertex_colours: a vertex-coloured model's colours as a texture, so that the rest of the
// pipeline (density, bake, measure) reads them as it reads any input texture.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "core/image.hpp"
#include "tightex/io.hpp"

namespace tightex {

namespace {

/// Whether triangle t takes its colour from its corners: it has corner colours and no texture. A
/// material that binds other maps (a glass with its roughness and thickness images, no base colour
/// texture) keeps its triangles' own texture coordinates, which those maps read: its triangles are not
/// given a colour texture, and are written as they came.
bool takes_corner_colours(const TexturedMesh& mesh, size_t t) {
  const int32_t m = mesh.face_material[t];
  if (m < 0) return true;
  const Material& material = mesh.materials[size_t(m)];
  return material.texture < 0 && std::all_of(material.maps.begin(), material.maps.end(), [](int map) { return map < 0; });
}

/// The material's constant colour (linear), which multiplies the corner colours in linear light (as
/// glTF's baseColorFactor multiplies COLOR_0, and as an untextured face's Kd is its colour).
std::array<double, 3> face_factor(const TexturedMesh& mesh, size_t t) {
  const int32_t m = mesh.face_material[t];
  return m < 0 ? std::array<double, 3>{1.0, 1.0, 1.0} : mesh.materials[size_t(m)].kd;
}

uint8_t to_byte(double x) { return uint8_t(std::lround(std::clamp(x, 0.0, 1.0) * 255.0)); }

/// Writes triangle t's cell: its three corners' colours at the texel centres its corners sit on, and
/// the fourth texel the linear extrapolation c1 + c2 - c0 (clamped to [0, 1]), so that bilinear
/// sampling inside the triangle gives the colours' linear interpolation.
void fill_cell(const TexturedMesh& mesh, size_t t, int x, int y, Image& image) {
  const std::array<double, 3> kd = face_factor(mesh, t);
  std::array<std::array<double, 4>, 3> c;
  for (int k = 0; k < 3; ++k)
    for (int ch = 0; ch < 4; ++ch) {
      const double stored = mesh.corner_color[3 * t + size_t(k)][size_t(ch)];
      c[size_t(k)][size_t(ch)] = ch == 3 || kd[size_t(ch)] == 1.0 ? stored : linear_to_srgb(srgb_to_linear(stored) * kd[size_t(ch)]);
    }
  auto texel = [&](const std::array<double, 4>& v) { return Rgba8{to_byte(v[0]), to_byte(v[1]), to_byte(v[2]), to_byte(v[3])}; };
  std::array<double, 4> fourth;
  for (size_t ch = 0; ch < 4; ++ch) fourth[ch] = c[1][ch] + c[2][ch] - c[0][ch];
  image.at(x, y + 1) = texel(c[0]);
  image.at(x + 1, y + 1) = texel(c[1]);
  image.at(x, y) = texel(c[2]);
  image.at(x + 1, y) = texel(fourth);
}

}  // namespace

size_t texture_vertex_colours(TexturedMesh& mesh, size_t max_pixels) {
  if (mesh.corner_color.empty()) return 0;
  std::vector<uint32_t> coloured;
  for (size_t t = 0; t < mesh.num_triangles(); ++t)
    if (takes_corner_colours(mesh, t)) coloured.push_back(uint32_t(t));
  if (coloured.empty()) return 0;
  // A square grid of 2 x 2 texel cells, one triangle each.
  const size_t columns = size_t(std::ceil(std::sqrt(double(coloured.size()))));
  const size_t rows = (coloured.size() + columns - 1) / columns;
  if (2 * columns > 65536 || 4 * columns * rows > max_pixels)
    fail_input("{}: {} vertex-coloured triangles need a {} x {} texture, more than --max-memory allows", mesh.source, coloured.size(),
               2 * columns, 2 * rows);
  Texture texture;
  texture.path =
      (std::filesystem::path(mesh.source).parent_path() / (std::filesystem::path(mesh.source).stem().string() + "_colours.png")).string();
  texture.image = Image(int(2 * columns), int(2 * rows), Rgba8{0, 0, 0, 255});
  texture.from_vertex_colours = true;
  const double W = double(texture.image.width), H = double(texture.image.height);
  // Per material of the coloured triangles (and one, "vertex_colours", for those without), a copy that
  // reads the colours: its name and scalars kept, its colour factor baked into them (white).
  std::vector<int32_t> colour_material(mesh.materials.size() + 1, -1);
  auto material_of = [&](int32_t m) {
    int32_t& made = colour_material[size_t(m + 1)];
    if (made >= 0) return made;
    Material material;
    if (m >= 0) material = mesh.materials[size_t(m)];
    if (m < 0) material.name = "vertex_colours";
    material.kd = {1.0, 1.0, 1.0};
    material.texture = int(mesh.textures.size());
    made = int32_t(mesh.materials.size());
    mesh.materials.push_back(std::move(material));
    return made;
  };
  for (size_t i = 0; i < coloured.size(); ++i) {
    const size_t t = coloured[i];
    const int x = int(2 * (i % columns)), y = int(2 * (i / columns));
    fill_cell(mesh, t, x, y, texture.image);
    // Corners 0, 1, 2 at the centres of texels (x, y+1), (x+1, y+1), (x, y): counter-clockwise in UV.
    const int corner_x[3] = {x, x + 1, x}, corner_y[3] = {y + 1, y + 1, y};
    for (int k = 0; k < 3; ++k) mesh.corner_uv[3 * t + size_t(k)] = Vec2((corner_x[k] + 0.5) / W, 1.0 - (corner_y[k] + 0.5) / H);
    mesh.face_material[t] = material_of(mesh.face_material[t]);
  }
  mesh.textures.push_back(std::move(texture));
  return coloured.size();
}

}  // namespace tightex
