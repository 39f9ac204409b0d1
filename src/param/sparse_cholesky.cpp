#include "param/sparse_cholesky.hpp"

#include <dlfcn.h>
#include <sys/mman.h>

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tightex {

std::mutex& blas_mutex() {
  static std::mutex m;
  return m;
}

std::mutex& metis_mutex() {
  static std::mutex m;
  return m;
}

namespace {
/// Whether use_serial_dense_kernels() has run on this thread: libgomp opens no team on it any more.
thread_local bool omp_serial = false;
}  // namespace

void use_serial_dense_kernels() {
  using SetThreads = void (*)(int);
  static std::once_flag blas_once;
  std::call_once(blas_once, [] {
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
  });
  if (omp_serial) return;
  omp_serial = true;
  // CHOLMOD asks for an explicit team size in places, which omp_set_num_threads does not cap; with
  // no active level allowed, every parallel region runs on the thread that meets it. Both are
  // per-thread settings in libgomp (OpenMP 5's data environment), hence on each thread that factorises.
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))) set(0);
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"))) set(1);
}

namespace detail {

namespace {
/// Factors smaller than this many entries (32 MB) are left to their factorisation's own faults.
constexpr size_t kTouchInParallelFrom = size_t(1) << 22;

/// Advises the whole 2 MiB pages inside [p, p + bytes) as transparent huge pages.
void advise_huge_pages(void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}
}  // namespace

void OrderedCholmod::allocate_supernodal_factor() {
  cholmod_factor* factor = m_cholmodFactor;
  if (!factor || !factor->is_super || factor->xtype != CHOLMOD_PATTERN || factor->xsize < kTouchInParallelFrom) return;
  if (!cholmod_change_factor(CHOLMOD_REAL, true, true, true, true, factor, &cholmod()) || !factor->x) return;
  double* x = static_cast<double*>(factor->x);
  advise_huge_pages(x, factor->xsize * sizeof(double));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, factor->xsize, size_t(1) << 18),
                    [&](const tbb::blocked_range<size_t>& r) { std::fill(x + r.begin(), x + r.end(), 0.0); });
}

}  // namespace detail

std::vector<int> nested_dissection_order(const Surface& mesh) {
  const int n = int(mesh.num_vertices());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(size_t(n) + mesh.opposite.size() / 2 + 1);
  for (int v = 0; v < n; ++v) entries.emplace_back(v, v, 1.0);
  for (uint32_t h = 0; h < mesh.opposite.size(); ++h) {
    const uint32_t o = mesh.opposite[h];
    if (o != kNone && o < h) continue;
    const int a = int(mesh.from(h)), b = int(mesh.to(h));
    if (a != b) entries.emplace_back(std::max(a, b), std::min(a, b), 1.0);
  }
  Eigen::SparseMatrix<double> pattern(n, n);
  pattern.setFromTriplets(entries.begin(), entries.end());
  cholmod_common common;
  cholmod_start(&common);
  common.print = 0;
  const Eigen::SparseMatrix<double>& lower = pattern;
  cholmod_sparse view = Eigen::viewAsCholmod(lower.selfadjointView<Eigen::Lower>());
  std::vector<int> order(static_cast<size_t>(n));
  bool ok = false;
  {
    const std::lock_guard<std::mutex> lock(metis_mutex());
    ok = cholmod_metis(&view, nullptr, 0, 0, order.data(), &common);
  }
  cholmod_finish(&common);
  if (!ok) order.clear();
  return order;
}

std::shared_ptr<const std::vector<int>> vertex_order_from(const Surface& mesh, size_t from) {
  if (mesh.num_vertices() < from) return nullptr;
  std::vector<int> order = nested_dissection_order(mesh);
  if (order.empty()) return nullptr;
  return std::make_shared<const std::vector<int>>(std::move(order));
}

bool SparseCholesky::permute_into_factor_order(const Matrix& a) {
  const int* perm = solver_.permutation();
  if (perm == nullptr || !a.isCompressed()) return false;
  const int n = int(a.rows());
  permutation_.assign(perm, perm + n);
  std::vector<int> position(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) position[size_t(permutation_[size_t(k)])] = k;
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  // Entry (row, col) of the lower triangle goes to (max, min) of their positions: lower again.
  std::vector<int> start(size_t(n) + 1, 0);
  for (int col = 0; col < n; ++col)
    for (int p = outer[col]; p < outer[col + 1]; ++p) ++start[size_t(std::min(position[size_t(inner[p])], position[size_t(col)])) + 1];
  for (int col = 0; col < n; ++col) start[size_t(col) + 1] += start[size_t(col)];
  std::vector<std::pair<int, int>> entries(size_t(a.nonZeros()));  // (new row, index in a's values)
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int col = 0; col < n; ++col)
    for (int p = outer[col]; p < outer[col + 1]; ++p) {
      const int r = position[size_t(inner[p])], c = position[size_t(col)];
      entries[size_t(fill[size_t(std::min(r, c))]++)] = {std::max(r, c), p};
    }
  permuted_.resize(n, n);
  permuted_.resizeNonZeros(a.nonZeros());
  slot_.resize(entries.size());
  for (int col = 0; col < n; ++col) {
    std::sort(entries.begin() + start[size_t(col)], entries.begin() + start[size_t(col) + 1]);
    permuted_.outerIndexPtr()[col] = start[size_t(col)];
  }
  permuted_.outerIndexPtr()[n] = start[size_t(n)];
  for (size_t p = 0; p < entries.size(); ++p) {
    permuted_.innerIndexPtr()[p] = entries[p].first;
    permuted_.valuePtr()[p] = 0.0;
    slot_[size_t(entries[p].second)] = int(p);
  }
  solver_.analyzePatternAsOrdered(permuted_);
  return solver_.info() == Eigen::Success;
}

std::vector<int> order_of_unknowns(const std::vector<int>& vertex_order, const std::vector<int>& unknown, int per_vertex) {
  std::vector<int> order;
  order.reserve(unknown.size());
  for (int v : vertex_order)
    for (int j = 0; j < per_vertex; ++j)
      if (const int k = unknown[size_t(v) * size_t(per_vertex) + size_t(j)]; k >= 0) order.push_back(k);
  return order;
}

}  // namespace tightex

/// Every parallel region CHOLMOD's supernodal factorisation meets (several per supernode: millions per
/// factorisation at 850k unknowns) costs libgomp a team's allocation and a futex wake at its closing
/// barrier even when it runs on one thread: most of the process's kernel time (BENCHMARKS.md). On a
/// thread that use_serial_dense_kernels() has set, where libgomp would run the region on that thread
/// alone anyway, the region's body is called directly; on any other thread libgomp's own runs. The
/// body's worksharing and barriers then meet no team, which libgomp treats as a team of one.
extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned num_threads, unsigned flags) {
  using Parallel = void (*)(void (*)(void*), void*, unsigned, unsigned);
  static const auto next = reinterpret_cast<Parallel>(dlsym(RTLD_NEXT, "GOMP_parallel"));
  if (tightex::omp_serial || !next)
    body(data);
  else
    next(body, data, num_threads, flags);
}
