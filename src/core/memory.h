#pragma once
// Process memory figures for metrics (METHOD.md §d.4): peak resident set size from the kernel.
namespace ff::core {

/// Peak resident set size of this process in MiB (Linux VmHWM), 0 if unknown.
double peak_rss_mib();
/// Current resident set size in MiB (Linux VmRSS), 0 if unknown.
double current_rss_mib();
/// The memory this process may use in MiB: the machine's physical memory, or the cgroup's limit (a container)
/// when that is lower; 0 if unknown.
double machine_memory_mib();

}  // namespace ff::core
