// An 8-bit RGBA image, rows top to bottom (row 0 is v = 1 in OBJ convention).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace tightex {

struct Rgba8 {
  uint8_t r = 0, g = 0, b = 0, a = 255;
  bool operator==(const Rgba8&) const = default;
};

struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgba8> pixels;  // width * height, row-major, top row first

  Image() = default;
  Image(int w, int h, Rgba8 fill = {}) : width(w), height(h), pixels(size_t(w) * size_t(h), fill) {}
  bool empty() const { return width <= 0 || height <= 0; }
  Rgba8& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  const Rgba8& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

/// Bilinear sample at texture coordinates (u right, v up, OBJ convention); coordinates outside
/// [0,1] wrap (repeat), as a renderer's default sampler does. Returns linear-blended 8-bit values
/// as floats in [0,255].
std::array<float, 4> sample_bilinear(const Image& image, double u, double v);

}  // namespace tightex
