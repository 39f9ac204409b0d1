// The resource guard of a run: the memory it will need, estimated from the model's geometry and its
// images' headers before any pixel is allocated, against Options::max_memory_mib (default 90% of RAM).
#pragma once
#include <string>

#include "tightex/tightex.hpp"

namespace tightex {

/// The limit and the estimate of one run.
struct MemoryGuard {
  std::string input;  // the model's name, for the error
  double limit_mib = 0;
  /// The memory before the per-component output textures: decoded input textures (RGBA), the mesh and
  /// its stages, and for the atlas the output texture.
  double estimate = 0;
  /// Output images per base colour texel (output_images).
  double output_images = 1;

  /// Throws InputError naming `what` if `bytes` is above the limit.
  void check(double bytes, const std::string& what) const;
};

/// The guard for a run of `input` (a file or mesh name): Options::max_memory_mib, or 90% of this
/// machine's memory.
MemoryGuard memory_guard(const std::string& input, const Options& options);

/// Refuses, from the image headers alone, a texture whose decoded pixels would not fit the limit (a
/// hostile header can declare 200000 x 200000 pixels); before anything is sized by those pixels.
void check_texture_headers(const MemoryGuard& guard, const TexturedMesh& geometry);

/// Checks the memory `geometry` needs at texture side `side` (the atlas layout's output texture
/// included; the per-component layout's once the plan has sized them: check_per_component_memory).
/// Returns the guard with its estimate. Throws InputError above the limit.
MemoryGuard check_memory(const std::string& input, const Options& options, const TexturedMesh& geometry, int side);

/// Checks the memory of the per-component layout's output textures, now that the plan has sized them.
void check_per_component_memory(const MemoryGuard& guard, const Plan& plan);

/// Whether the output textures `pages` (width, height) made `scale` times larger a side still fit the
/// guard's limit beside its estimate (a --target-psnr that grows the texels).
bool fits_larger_textures(const MemoryGuard& guard, const std::vector<std::pair<int, int>>& pages, double scale);

}  // namespace tightex
