// An 8-bit RGBA image, rows top to bottom (row 0 is v = 1 in OBJ convention).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tightex {

struct Rgba8 {
  uint8_t r = 0, g = 0, b = 0, a = 255;
  bool operator==(const Rgba8&) const = default;
};

/// The allocator of Image's pixels: a texture's blocks of 2 MiB and more are aligned and advised as
/// transparent huge pages, which saves most of their page faults (docs/decisions.md).
struct PixelAllocator {
  using value_type = Rgba8;
  template <typename U>
  struct rebind {  // a vector of pixels only
    using other = PixelAllocator;
  };
  PixelAllocator() = default;
  Rgba8* allocate(size_t n);
  void deallocate(Rgba8* p, size_t n);
  bool operator==(const PixelAllocator&) const { return true; }
};

struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgba8, PixelAllocator> pixels;  // width * height, row-major, top row first

  Image() = default;
  Image(int w, int h, Rgba8 fill = {}) : width(w), height(h), pixels(size_t(w) * size_t(h), fill) {}
  bool empty() const { return width <= 0 || height <= 0; }
  Rgba8& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  const Rgba8& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

}  // namespace tightex
