#include "pipeline/tight_input.hpp"

#include <fmt/format.h>

#include <numeric>

#include "report/metrics.hpp"

namespace tightex {

namespace {

/// Union-find root with path halving.
uint32_t root(std::vector<uint32_t>& parent, uint32_t f) {
  while (parent[f] != f) f = parent[f] = parent[parent[f]];
  return f;
}

/// The input coordinate of corner k of component face f.
const Vec2& input_uv(const TexturedMesh& input, const Surface& s, uint32_t f, uint32_t k) {
  return input.corner_uv[3 * size_t(s.input_face[f]) + s.input_corner[3 * size_t(f) + k]];
}

/// Whether input triangle t samples an image of known size read from a file (loaded or not yet).
bool samples_an_image(const TexturedMesh& input, uint32_t t) {
  const int32_t mat = input.face_material[t];
  if (mat < 0) return false;
  const int tex = input.materials[size_t(mat)].texture;
  if (tex < 0 || input.textures[size_t(tex)].from_vertex_colours) return false;
  const auto [w, h] = texture_size(input, tex);
  return w > 0 && h > 0;
}

/// Whether component s is one chart of `input`: every face samples an image, and the faces are joined
/// through interior edges with the same material and the same coordinates on both sides.
bool one_chart(const TexturedMesh& input, const Surface& s) {
  const uint32_t nf = uint32_t(s.num_faces());
  if (nf == 0 || s.input_face.size() != nf) return false;
  for (uint32_t f = 0; f < nf; ++f)
    if (s.input_face[f] == kNone || !samples_an_image(input, s.input_face[f])) return false;
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  size_t charts = nf;
  for (uint32_t h = 0; h < s.opposite.size(); ++h) {
    const uint32_t o = s.opposite[h];
    if (o == kNone || o < h) continue;
    const uint32_t f = h / 3, g = o / 3;
    // h runs a -> b in f, o runs b -> a in g.
    const bool same = input.face_material[s.input_face[f]] == input.face_material[s.input_face[g]] &&
                      input_uv(input, s, f, h % 3) == input_uv(input, s, g, (o % 3 + 1) % 3) &&
                      input_uv(input, s, f, (h % 3 + 1) % 3) == input_uv(input, s, g, o % 3);
    if (!same) continue;
    const uint32_t a = root(parent, f), b = root(parent, g);
    if (a != b) parent[a] = b, --charts;
  }
  return charts == 1;
}

}  // namespace

double tight_utilization(const TexturedMesh& input, const std::vector<Surface>& components) {
  if (components.empty()) return 0;
  for (const Surface& s : components)
    if (!one_chart(input, s)) return 0;
  const double used = measure_texture_space(input).utilization;
  return used >= kTightUtilization ? used : 0;
}

std::string keep_tight_reason(double utilization, const Options& options, const TextureBudget& budget) {
  if (!(utilization > 0) || !budget.is_default || options.layout != Layout::kAtlas) return "";
  return fmt::format(
      "the input is already one chart per surface filling its texture ({:.1f}% of its texels used), which a new map "
      "could only resample (a budget given with --size or --texels maps it anyway)",
      100 * utilization);
}

}  // namespace tightex
