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

/// Whether component s is one chart of `input`: every face samples a loaded image, and the faces are
/// joined through interior edges with the same material and the same coordinates on both sides.
bool one_chart(const TexturedMesh& input, const Surface& s) {
  const uint32_t nf = uint32_t(s.num_faces());
  if (nf == 0 || s.input_face.size() != nf) return false;
  for (uint32_t f = 0; f < nf; ++f)
    if (s.input_face[f] == kNone || image_of(input, s.input_face[f]) == nullptr) return false;
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

std::string already_tight(const TexturedMesh& input, const Options& options, const TextureBudget& budget,
                          const std::vector<Surface>& components) {
  if (!budget.is_default || options.layout != Layout::kAtlas || components.empty()) return "";
  for (const Surface& s : components)
    if (!one_chart(input, s)) return "";
  const double used = measure_texture_space(input).utilization;
  if (!(used >= kTightUtilization)) return "";
  return fmt::format(
      "the input is already one chart per surface filling its texture ({:.1f}% of its texels used), which a new map "
      "could only resample (a budget given with --size or --texels maps it anyway)",
      100 * used);
}

}  // namespace tightex
