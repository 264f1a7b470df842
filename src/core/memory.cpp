#include "core/memory.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <unistd.h>

namespace ff::core {
namespace {
// Reads one "Key:   123 kB" line of /proc/self/status.
double status_kib(const char* key) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0.0;
  char line[256];
  double kib = 0.0;
  const std::size_t len = std::strlen(key);
  while (std::fgets(line, sizeof line, f)) {
    if (std::strncmp(line, key, len) == 0 && line[len] == ':') {
      kib = std::strtod(line + len + 1, nullptr);
      break;
    }
  }
  std::fclose(f);
  return kib;
}
}  // namespace

double peak_rss_mib() { return status_kib("VmHWM") / 1024.0; }
double current_rss_mib() { return status_kib("VmRSS") / 1024.0; }
double machine_memory_mib() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGESIZE);
  double mib = pages > 0 && size > 0 ? double(pages) * double(size) / (1024.0 * 1024.0) : 0.0;
  // cgroup v2: "max" or a byte count.
  if (std::FILE* f = std::fopen("/sys/fs/cgroup/memory.max", "r")) {
    char line[64] = {0};
    if (std::fgets(line, sizeof line, f) && line[0] >= '0' && line[0] <= '9') {
      const double limit = std::strtod(line, nullptr) / (1024.0 * 1024.0);
      if (limit > 0.0 && (mib == 0.0 || limit < mib)) mib = limit;
    }
    std::fclose(f);
  }
  return mib;
}

}  // namespace ff::core
