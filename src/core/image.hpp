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

/// sample_bilinear in linear light: red, green and blue of each of the four texels decoded from sRGB
/// before they are blended; the result's colour channels are linear intensities scaled to [0,255]
/// (alpha as stored). Encode with srgb_encode_255.
std::array<float, 4> sample_bilinear_linear_light(const Image& image, double u, double v);

/// The 8-bit sRGB value (as a float in [0,255], unrounded) of a linear intensity given in [0,255].
float srgb_encode_255(float linear);

/// sRGB encoding of a linear intensity in [0, 1] (clamped), and its inverse.
double linear_to_srgb(double linear);
double srgb_to_linear(double encoded);

}  // namespace tightex
