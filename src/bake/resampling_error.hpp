// How much of the input's colour a map keeps: its real faces baked and read back at points on the
// surface, without writing anything. The pipeline chooses between candidate maps with it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bake/bake.hpp"
#include "core/mesh.hpp"
#include "core/surface.hpp"
#include "layout/layout.hpp"

namespace tightex {

/// An estimate of the colour error that a map of a disk leaves when baked into a w x h texel rectangle:
/// the disk's real faces are baked (bake_texture as bake_plan places them: the unit square's corners on
/// the corner texels' centres; without the least-squares fit, a fifth of the bake's time, which lifts
/// every map alike) and the result read back bilinearly at `samples` points spread by 3D area
/// (stratified: jittered along the faces' cumulative area, so they come in face order), against the
/// input's own bilinear colour there, as docs/metrics.md's surface PSNR compares.
/// `uv`: per disk vertex, in the unit square; faces without an input triangle (Surface::input_face)
/// (kNone: scaffolding, not sampled). Returns the mean squared error per RGB channel in 8-bit levels,
/// or -1 when no face has loaded texture pixels. Deterministic (fixed seed): two maps of the same disk
/// are compared at the same surface points. It bakes for real (footprint filter included): a point-sampled
/// simulation ranks maps of different shapes wrongly (docs/decisions.md).
double resampling_mse(const TexturedMesh& input, const Surface& disk, const std::vector<Vec2>& uv, int w, int h, size_t samples);

/// The bake's view of disk face f (not scaffolding): its input triangle's material and texture
/// coordinates, its 3D area, and its corners' texel positions in `rect` for the map `uv`.
BakeTriangle bake_triangle(const TexturedMesh& input, const Surface& disk, uint32_t f, const std::vector<Vec2>& uv, const Rect& rect);

}  // namespace tightex
