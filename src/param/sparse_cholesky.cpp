#include "param/sparse_cholesky.hpp"

#include <dlfcn.h>

namespace tightex {

std::mutex& blas_mutex() {
  static std::mutex m;
  return m;
}

void use_serial_dense_kernels() {
  using SetThreads = void (*)(int);
  static std::once_flag blas_once;
  std::call_once(blas_once, [] {
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
  });
  thread_local bool omp_done = false;
  if (omp_done) return;
  omp_done = true;
  // CHOLMOD asks for an explicit team size in places, which omp_set_num_threads does not cap; with
  // no active level allowed, every parallel region runs on the thread that meets it. Both are
  // per-thread settings in libgomp (OpenMP 5's data environment), hence on each thread that factorises.
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))) set(0);
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"))) set(1);
}

}  // namespace tightex
