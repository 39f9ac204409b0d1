#include "core/image.hpp"

#include <algorithm>
#include <cmath>

#include "core/large_buffer.hpp"

namespace tightex {

Rgba8 *PixelAllocator::allocate(size_t n) { return LargeBufferAllocator<Rgba8>().allocate(n); }
void PixelAllocator::deallocate(Rgba8 *p, size_t n) { LargeBufferAllocator<Rgba8>().deallocate(p, n); }

namespace {
inline int wrap(int i, int n) {
  int r = i % n;
  return r < 0 ? r + n : r;
}

/// Linear intensity in [0,255] of each 8-bit sRGB value.
const std::array<float, 256> &srgb_decode_table() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const double c = i / 255.0;
      t[size_t(i)] = float(255.0 * (c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4)));
    }
    return t;
  }();
  return table;
}
}  // namespace

double linear_to_srgb(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

double srgb_to_linear(double encoded) {
  const double c = std::clamp(encoded, 0.0, 1.0);
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

float srgb_encode_255(float linear) {
  // A table of 4096 steps over [0, 255] read linearly: within 0.01 of an 8-bit level of the formula
  // above the darkest steps, where the curve is steepest, and far closer beyond.
  constexpr int kSteps = 4096;
  static const std::array<float, kSteps + 1> table = [] {
    std::array<float, kSteps + 1> t{};
    for (int i = 0; i <= kSteps; ++i) {
      const double c = double(i) / kSteps;
      t[size_t(i)] = float(255.0 * (c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055));
    }
    return t;
  }();
  const float x = linear > 0 ? std::min(linear / 255.0f, 1.0f) * kSteps : 0.0f;  // NaN reads as 0
  const int i = std::min(int(x), kSteps - 1);
  return table[size_t(i)] + (x - float(i)) * (table[size_t(i) + 1] - table[size_t(i)]);
}

std::array<float, 4> sample_bilinear_linear_light(const Image &image, double u, double v) {
  const double x = u * image.width - 0.5;
  const double y = (1.0 - v) * image.height - 0.5;
  if (!std::isfinite(x) || !std::isfinite(y) || image.empty()) return {0, 0, 0, 0};
  const double fx = std::floor(x), fy = std::floor(y), lim = 1e9;
  const float tx = float(x - fx), ty = float(y - fy);
  const int x0 = wrap(int(std::fmod(std::clamp(fx, -lim, lim), double(image.width))), image.width);
  const int y0 = wrap(int(std::fmod(std::clamp(fy, -lim, lim), double(image.height))), image.height);
  const int x1 = x0 + 1 == image.width ? 0 : x0 + 1;
  const int y1 = y0 + 1 == image.height ? 0 : y0 + 1;
  const Rgba8 *p[4] = {&image.at(x0, y0), &image.at(x1, y0), &image.at(x0, y1), &image.at(x1, y1)};
  const float w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
  const auto &lin = srgb_decode_table();
  std::array<float, 4> out{0, 0, 0, 0};
  for (int k = 0; k < 4; ++k) {
    out[0] += w[k] * lin[p[k]->r], out[1] += w[k] * lin[p[k]->g], out[2] += w[k] * lin[p[k]->b];
    out[3] += w[k] * float(p[k]->a);
  }
  return out;
}

std::array<float, 4> sample_bilinear(const Image &image, double u, double v) {
  const double x = u * image.width - 0.5;
  const double y = (1.0 - v) * image.height - 0.5;
  if (!std::isfinite(x) || !std::isfinite(y) || image.empty()) return {0, 0, 0, 0};  // no texel to read (int(NaN) is undefined)
  const double fx = std::floor(x), fy = std::floor(y);
  const float tx = float(x - fx), ty = float(y - fy);
  // floor of huge values is clamped before the int conversion, so absurd UVs cannot overflow.
  const double lim = 1e9;
  if (fx >= 0 && fy >= 0 && fx < image.width - 1 && fy < image.height - 1) {  // common case: no wrap
    const size_t i0 = size_t(fy) * size_t(image.width) + size_t(fx);
    const Rgba8 &p00 = image.pixels[i0], &p10 = image.pixels[i0 + 1], &p01 = image.pixels[i0 + size_t(image.width)],
                &p11 = image.pixels[i0 + size_t(image.width) + 1];
    const float w00 = (1 - tx) * (1 - ty), w10 = tx * (1 - ty), w01 = (1 - tx) * ty, w11 = tx * ty;
    return {w00 * p00.r + w10 * p10.r + w01 * p01.r + w11 * p11.r, w00 * p00.g + w10 * p10.g + w01 * p01.g + w11 * p11.g,
            w00 * p00.b + w10 * p10.b + w01 * p01.b + w11 * p11.b, w00 * p00.a + w10 * p10.a + w01 * p01.a + w11 * p11.a};
  }
  const int x0 = wrap(int(std::fmod(std::clamp(fx, -lim, lim), double(image.width))), image.width);
  const int y0 = wrap(int(std::fmod(std::clamp(fy, -lim, lim), double(image.height))), image.height);
  const int x1 = x0 + 1 == image.width ? 0 : x0 + 1;
  const int y1 = y0 + 1 == image.height ? 0 : y0 + 1;
  const Rgba8 &p00 = image.at(x0, y0), &p10 = image.at(x1, y0), &p01 = image.at(x0, y1), &p11 = image.at(x1, y1);
  const float w00 = (1 - tx) * (1 - ty), w10 = tx * (1 - ty), w01 = (1 - tx) * ty, w11 = tx * ty;
  return {w00 * p00.r + w10 * p10.r + w01 * p01.r + w11 * p11.r, w00 * p00.g + w10 * p10.g + w01 * p01.g + w11 * p11.g,
          w00 * p00.b + w10 * p10.b + w01 * p01.b + w11 * p11.b, w00 * p00.a + w10 * p10.a + w01 * p01.a + w11 * p11.a};
}

}  // namespace tightex
