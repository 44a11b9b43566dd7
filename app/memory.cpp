#include "memory.h"

#include <sys/resource.h>

#include <algorithm>
#include <fstream>
#include <limits>

namespace crumple::app {

namespace {

// The value in kB after `key` in a /proc file such as /proc/meminfo, in bytes; `fallback` if absent.
std::uint64_t proc_kb(const char* file, const std::string& key, std::uint64_t fallback) {
  std::ifstream in(file);
  std::string name;
  std::uint64_t kb = 0;
  while (in >> name) {
    if (name == key && in >> kb) return kb * 1024;
    in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return fallback;
}

// What the soft limit `resource` leaves after `used` bytes (unlimited: the largest value).
std::uint64_t left_under(int resource, std::uint64_t used) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) {
    return std::numeric_limits<std::uint64_t>::max();
  }
  return limit.rlim_cur > used ? limit.rlim_cur - used : 0;
}

}  // namespace

std::uint64_t estimate_run_bytes(const std::string& backend, std::size_t vertices, bool resident) {
  const std::uint64_t program = std::uint64_t{64} << 20;
  if (resident && backend == "fast") return 7000 * std::uint64_t(vertices) + program;
  const std::uint64_t per_vertex = backend == "fast" ? 1600 : 1000;
  return 2 * per_vertex * vertices + program;
}

std::uint64_t available_bytes() {
  constexpr std::uint64_t kUnknown = std::numeric_limits<std::uint64_t>::max();
  const std::uint64_t system = proc_kb("/proc/meminfo", "MemAvailable:", kUnknown);
  const std::uint64_t address = left_under(RLIMIT_AS, proc_kb("/proc/self/status", "VmSize:", 0));
  const std::uint64_t data = left_under(RLIMIT_DATA, proc_kb("/proc/self/status", "VmData:", 0));
  return std::min({system, address, data});
}

}  // namespace crumple::app
