// An 8-bit RGBA image, rows top to bottom (row 0 is v = 1 in OBJ convention).
#pragma once
#include <array>
#include <cstdint>

#include "tightex/image.hpp"

namespace tightex {

/// Bilinear sample at texture coordinates (u right, v up, OBJ convention); coordinates outside
/// [0,1] wrap (repeat), as a renderer's default sampler does. Returns linear-blended 8-bit values
/// as floats in [0,255].
std::array<float, 4> sample_bilinear(const Image& image, double u, double v);

}  // namespace tightex
