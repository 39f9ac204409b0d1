// A picture that shows what changed: the input's texture page(s) beside the output texture.
#pragma once
#include "core/mesh.hpp"

namespace tightex {

/// `src` resized to `height` pixels tall (at most its own height; the width keeps the aspect ratio),
/// each output pixel the mean of the source texels under it. Requires a non-empty image.
Image box_shrink(const Image& src, int height);

/// The input's textures (left, side by side) and the output's (right), each box-filtered to `height`
/// pixels tall, on a dark background with a gap between them.
Image make_preview(const TexturedMesh& input, const TexturedMesh& output, int height = 512);

}  // namespace tightex
