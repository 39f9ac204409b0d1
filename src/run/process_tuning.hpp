// Process-wide settings a run wants, made by the library (run, optimize) rather than by the command's
// main(), so that the command, a program using the library and the Python module run alike.
#pragma once

namespace tightex {

/// glibc's allocator told, once per process, to keep freed memory for the next allocation instead of
/// giving it back to the kernel: a run allocates and frees arrays the size of the surface at every
/// step, and each page taken again from the kernel costs a page fault and its zeroing. Blocks up to
/// 32 MiB (glibc's largest threshold) come from the heap, which is never trimmed and grows 256 MiB at a
/// time (address space, not memory, until written). Figures: BENCHMARKS.md, "Where the default run's
/// time goes". Changes speed and memory held, never a byte of the output.
void keep_freed_memory_for_reuse();

}  // namespace tightex
