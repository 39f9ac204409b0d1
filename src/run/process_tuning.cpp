#include "run/process_tuning.hpp"

#include <malloc.h>

#include <limits>
#include <mutex>

namespace tightex {

void keep_freed_memory_for_reuse() {
  static std::once_flag once;
  std::call_once(once, [] {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
    mallopt(M_TOP_PAD, 256 << 20);
  });
}

}  // namespace tightex
