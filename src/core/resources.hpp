// What the process has used of the machine, for the report.
#pragma once

namespace tightex {

/// The process's peak resident set size so far, in MiB (getrusage's ru_maxrss, which Linux gives in
/// KiB). Never throws; 0 if the system does not report it.
double peak_rss_mib();

}  // namespace tightex
