#include "run/memory_guard.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>

#include "core/error.hpp"
#include "core/memory_model.hpp"

namespace tightex {

namespace {

/// The output images baked per base colour texel: the base colour's and one per map slot some
/// material binds (a slot may share another's image, or be baked larger: one each is the estimate).
double output_images(const TexturedMesh& geometry) {
  std::array<bool, kMaterialSlots> bound{};
  for (const Material& m : geometry.materials)
    for (size_t s = 0; s < kMaterialSlots; ++s) bound[s] = bound[s] || m.maps[s] >= 0;
  return 1.0 + double(std::count(bound.begin(), bound.end(), true));
}

}  // namespace

void MemoryGuard::check(double bytes, const std::string& what) const {
  if (bytes / double(1 << 20) > limit_mib)
    fail_input("{}: {} needs about {:.0f} MiB, more than the limit of {:.0f} MiB (--max-memory)", input, what, bytes / double(1 << 20),
               limit_mib);
}

MemoryGuard memory_guard(const std::string& input, const Options& options) {
  MemoryGuard guard;
  guard.input = input;
  guard.limit_mib = memory_limit_mib(options.max_memory_mib);
  return guard;
}

void check_texture_headers(const MemoryGuard& guard, const TexturedMesh& geometry) {
  for (const Texture& t : geometry.textures)
    guard.check(double(t.width) * double(t.height) * 4.0, fmt::format("texture {} ({} x {} pixels)", t.path, t.width, t.height));
}

MemoryGuard check_memory(const std::string& input, const Options& options, const TexturedMesh& geometry, int side) {
  MemoryGuard guard = memory_guard(input, options);
  // The maps made at once: where the limit does not leave room for every large one together, one large
  // map (at most a piece of max_piece_faces) beside a smaller one per other thread (pipeline/plan).
  const double faces = double(geometry.num_triangles());
  const double pieces = options.max_piece_faces > 0 ? double(options.max_piece_faces) : faces;
  const double beside = double(std::max(1, tbb::this_task_arena::max_concurrency()) - 1) * double(kLargeMapFaces);
  guard.estimate = kRunBaseBytes + faces * kBytesPerTriangle + std::min(faces, pieces + beside) * kBytesPerMappedTriangle;
  for (const Texture& t : geometry.textures) guard.estimate += double(t.width) * double(t.height) * 4.0;
  guard.output_images = output_images(geometry);
  if (options.layout == Layout::kAtlas) guard.estimate += double(side) * double(side) * kBytesPerOutputTexel * guard.output_images;
  guard.check(guard.estimate, "this model at this --size");
  return guard;
}

void check_per_component_memory(const MemoryGuard& guard, const Plan& plan) {
  double out_texels = 0;
  for (const auto& [w, h] : plan.texture_sizes()) out_texels += double(w) * double(h);
  guard.check(guard.estimate + out_texels * kBytesPerOutputTexel * guard.output_images, "this model's per-component textures");
}

bool fits_larger_textures(const MemoryGuard& guard, const std::vector<std::pair<int, int>>& pages, double scale) {
  double added = 0;
  for (const auto& [w, h] : pages) added += (scale * scale - 1) * double(w) * double(h) * kBytesPerOutputTexel * guard.output_images;
  return (guard.estimate + added) / double(1 << 20) <= guard.limit_mib;
}

}  // namespace tightex
