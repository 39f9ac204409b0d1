#include "core/resources.hpp"

#include <sys/resource.h>

namespace tightex {

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

}  // namespace tightex
