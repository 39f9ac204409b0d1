// The new texture (paper §4.3, Alg. 3): every output triangle is scan-converted in the new texture
// space and each texel takes the colour of the original texture through the original UVs.
#pragma once
#include <array>
#include <vector>

#include "core/mesh.hpp"
#include "layout/layout.hpp"

namespace tightex {

/// One triangle to bake: where it lands (pixel coordinates, x right, y down, texel centres at +0.5)
/// and where its colour comes from (texture coordinates in the input, after the material's -s/-o).
struct BakeTriangle {
  uint32_t image = 0;
  std::array<Vec2, 3> target_px;
  std::array<Vec2, 3> source_uv;
  int32_t material = -1;  // input material (-1: none, white)
};

struct BakeStats {
  size_t texels_filled = 0;   // texel centres inside some triangle
  size_t texels_dilated = 0;  // texels of a rectangle that no triangle covers (scaffolding, rounding)
};

/// Fills `images` (allocated by the caller). Texels whose centre lies inside a triangle (edges
/// included) get the bilinear sample of the input texture at the interpolated original UV; texels of a
/// rectangle in `rects` that no triangle covers are then filled by dilation from their covered
/// neighbours, within the same rectangle only (no bleeding between charts). Parallel over tiles of
/// the output with oneTBB; each tile processes its triangles in order, so the result is the same for
/// any thread count.
void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles,
                  const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats);

}  // namespace tightex
