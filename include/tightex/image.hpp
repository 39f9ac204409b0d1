// An 8-bit RGBA image, rows top to bottom (row 0 is v = 1 in OBJ convention).
#pragma once
#include <sys/mman.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

namespace tightex {

/// Allocator for large flat buffers (textures, coverage masks): blocks of 2 MiB and more are aligned to
/// 2 MiB and advised as transparent huge pages, which saves most of their page faults
/// (docs/decisions.md). Where huge pages are off the advice is ignored.
template <typename T>
struct LargeBufferAllocator {
  using value_type = T;
  static constexpr size_t kHuge = size_t(2) << 20;
  LargeBufferAllocator() = default;
  template <typename U>
  LargeBufferAllocator(const LargeBufferAllocator<U>&) {}
  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kHuge) return std::allocator<T>().allocate(n);
    const size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
    void* p = std::aligned_alloc(kHuge, rounded);
    if (!p) throw std::bad_alloc();
    madvise(p, rounded, MADV_HUGEPAGE);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) < kHuge) return std::allocator<T>().deallocate(p, n);
    std::free(p);
  }
  template <typename U>
  bool operator==(const LargeBufferAllocator<U>&) const {
    return true;
  }
};

struct Rgba8 {
  uint8_t r = 0, g = 0, b = 0, a = 255;
  bool operator==(const Rgba8&) const = default;
};

struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgba8, LargeBufferAllocator<Rgba8>> pixels;  // width * height, row-major, top row first

  Image() = default;
  Image(int w, int h, Rgba8 fill = {}) : width(w), height(h), pixels(size_t(w) * size_t(h), fill) {}
  bool empty() const { return width <= 0 || height <= 0; }
  Rgba8& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  const Rgba8& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

}  // namespace tightex
