// What a run holds in memory, for the guard's estimate (run/memory_guard) and for the choice between
// mapping the large components at once or one after another (pipeline/plan). The figures are bounds
// on the peaks measured from 1k to 10M triangles (BENCHMARKS.md, "The guard's estimate").
#pragma once
#include <cstddef>

namespace tightex {

/// What a run of any size holds: the process, its thread pools, the report's pictures, the kept heap.
constexpr double kRunBaseBytes = 256.0 * (1 << 20);
/// Per input triangle, held through the run: the model, its prepared surface, the output model.
constexpr double kBytesPerTriangle = 300.0;
/// Per triangle of a component while it is mapped: its surface, disk, coarse copies and systems.
constexpr double kBytesPerMappedTriangle = 700.0;
/// Per output texel and image: RGBA and the bake's coverage masks.
constexpr double kBytesPerOutputTexel = 7.0;
/// Components of at least this many triangles are large maps: mapped at once only where the memory
/// limit leaves room for all of them (large_maps_at_once), else one after another. Smaller ones are
/// mapped beside them, one per thread.
constexpr size_t kLargeMapFaces = 1000000;

/// The memory a run may use, in MiB: `max_memory_mib` where positive, else 90% of this machine's.
double memory_limit_mib(double max_memory_mib);

/// Whether the large maps of `large_faces` triangles in all may be made at once by a process that has
/// held `held_mib` so far, within `limit_mib`: their factorisations take turns on BLAS anyway (one
/// large map keeps both cores of a small machine busy), so at once saves only the time their other
/// work overlaps, for the memory of all of them together.
inline bool large_maps_at_once(double large_faces, double held_mib, double limit_mib) {
  return held_mib + large_faces * kBytesPerMappedTriangle / double(1 << 20) <= limit_mib;
}

}  // namespace tightex
