#include "core/resources.hpp"

#include "core/memory_model.hpp"

#include <sys/resource.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace tightex {

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

CpuTimes process_cpu_times() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return {};
  auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return {seconds(u.ru_utime), seconds(u.ru_stime)};
}

void release_free_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

double memory_limit_mib(double max_memory_mib) {
  if (max_memory_mib > 0) return max_memory_mib;
  return 0.9 * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE)) / double(1 << 20);
}

}  // namespace tightex
