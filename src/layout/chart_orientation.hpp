// How a chart turns the input texture's axes: a triangle's affine map from input texels to output texels.
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "core/mesh.hpp"
#include "core/stage_stats.hpp"

namespace tightex {

/// Where a triangle's affine map from its input texels to its output texels takes the input's u axis
/// (1, 0) and v axis (0, 1): corner k's input uv `in_uv[k]` times `in_texels` (the image's width and
/// height) goes to `out_uv[k]` times `out_texels`, uv "v up" on both sides. nullopt where either
/// triangle has no texture area. docs/metrics.md's texture axes angle reads it.
std::optional<std::array<Vec2, 2>> texel_axes_images(const std::array<Vec2, 3>& in_uv, const Vec2& in_texels,
                                                     const std::array<Vec2, 3>& out_uv, const Vec2& out_texels);

}  // namespace tightex
