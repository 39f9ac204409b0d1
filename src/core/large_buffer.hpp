// An allocator for large flat buffers (textures, coverage masks).
#pragma once
#include <sys/mman.h>

#include <cstdlib>
#include <memory>
#include <new>

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

}  // namespace tightex
