// A picture that shows what changed: the input's texture page(s) beside the output texture.
#pragma once
#include "core/mesh.hpp"

namespace tightex {

/// The input's textures (left, side by side) and the output's (right), each box-filtered to `height`
/// pixels tall, on a dark background with a gap between them.
Image make_preview(const TexturedMesh& input, const TexturedMesh& output, int height = 512);

}  // namespace tightex
