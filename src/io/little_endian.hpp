// Little-endian binary output, shared by the writers of binary formats (PLY, GLB).
#pragma once
#include <bit>
#include <cstring>
#include <string>
#include <utility>

namespace tightex {

/// Appends the bytes of `value` in little-endian order.
template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  out.append(bytes, sizeof(T));
}

}  // namespace tightex
