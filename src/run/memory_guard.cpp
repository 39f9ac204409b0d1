#include "run/memory_guard.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>

#include "core/error.hpp"

namespace tightex {

namespace {

/// Memory a run needs whatever the model (the process, its pools, the other maps' images and the
/// report's pictures), per input triangle (the mesh and its stages, with components of at most
/// Options::max_piece_faces) and per output texel and image (RGBA and the bake's coverage masks), in
/// bytes: at or above the peaks measured from 1k to 10M triangles (BENCHMARKS.md, "Memory").
constexpr double kBaseBytes = 256.0 * (1 << 20);
constexpr double kBytesPerTriangle = 1500.0;
constexpr double kBytesPerOutputTexel = 7.0;

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
  guard.limit_mib = options.max_memory_mib > 0
                        ? options.max_memory_mib
                        : 0.9 * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE)) / double(1 << 20);
  return guard;
}

void check_texture_headers(const MemoryGuard& guard, const TexturedMesh& geometry) {
  for (const Texture& t : geometry.textures)
    guard.check(double(t.width) * double(t.height) * 4.0, fmt::format("texture {} ({} x {} pixels)", t.path, t.width, t.height));
}

MemoryGuard check_memory(const std::string& input, const Options& options, const TexturedMesh& geometry, int side) {
  MemoryGuard guard = memory_guard(input, options);
  guard.estimate = kBaseBytes + double(geometry.num_triangles()) * kBytesPerTriangle;
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

}  // namespace tightex
