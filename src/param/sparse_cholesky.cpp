#include "param/sparse_cholesky.hpp"

namespace tightex {

std::mutex& blas_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace tightex
