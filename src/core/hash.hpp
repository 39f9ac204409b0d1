// A 64-bit mixing function for hashes and fixed pseudo-random orders.
#pragma once
#include <cstdint>

namespace tightex {

/// splitmix64's finaliser of x + the golden ratio: a well-mixed 64-bit hash of `x`.
constexpr uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace tightex
