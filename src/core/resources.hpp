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

}  // namespace tightex
