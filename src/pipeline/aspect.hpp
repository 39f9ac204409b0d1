// The texture's shape (beyond the paper, session 7): which width/height of the rectangle keeps the most
// of the input's texture for the same texel budget.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/mesh.hpp"
#include "bake/bake.hpp"
#include "core/surface.hpp"
#include "layout/layout.hpp"

namespace tightex {

/// An estimate of the colour error that a map of a disk leaves when baked into a w x h texel rectangle:
/// the disk's real faces are baked (bake_texture as bake_plan places them: the unit square's corners on
/// the corner texels' centres; without the least-squares fit, a fifth of the bake's time, which lifts
/// every map alike) and the result read back bilinearly at `samples` points spread uniformly by 3D area,
/// against the input's own bilinear colour there, as METRICS.md's surface PSNR compares.
/// `uv`: per disk vertex, in the unit square; faces without an input triangle (Surface::input_face)
/// (kNone: scaffolding, not sampled). Returns the mean squared error per RGB channel in 8-bit levels,
/// or -1 when no face has loaded texture pixels. Deterministic (fixed seed): two maps of the same disk
/// are compared at the same surface points. Measured against the surface PSNR of the finished run, an
/// estimate that simulated the texels by point sampling (no footprint filter) ranked meshroom_esp32cam's
/// 2:1 map 1 dB above its square (real: 0.5 dB below); the real bake ranks them right.
double resampling_mse(const TexturedMesh& input, const Surface& disk, const std::vector<Vec2>& uv, int w, int h, size_t samples);

/// The bake's view of disk face f (not scaffolding): its input triangle's material and texture
/// coordinates, its 3D area, and its corners' texel positions in `rect` for the map `uv`.
BakeTriangle bake_triangle(const TexturedMesh& input, const Surface& disk, uint32_t f, const std::vector<Vec2>& uv, const Rect& rect);

}  // namespace tightex
