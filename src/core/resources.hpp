// What the process has used of the machine, for the report.
#pragma once

namespace tightex {

/// The process's peak resident set size so far, in MiB (getrusage's ru_maxrss, which Linux gives in
/// KiB). Never throws; 0 if the system does not report it.
double peak_rss_mib();

/// The CPU time the process has used so far, all its threads together, in seconds.
struct CpuTimes {
  double user = 0;  // in the program
  double sys = 0;   // in the kernel on its behalf (system calls, page faults)
};

/// getrusage's CPU times of the whole process. Never throws; zeros if the system does not report them.
CpuTimes process_cpu_times();

/// Hands the memory the allocator holds free back to the system (glibc: malloc_trim; elsewhere
/// nothing): for a stage that has freed its arrays before the next allocates others. What a thread's
/// arena freed is out of reach of the other threads' allocations, and the command keeps freed memory
/// instead of trimming it (src/cli/main.cpp), so it would stay resident beneath the next stage's peak.
void release_free_memory();

}  // namespace tightex
