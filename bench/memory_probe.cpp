// crumple_memory_probe: the machine's memory rates by working-set size, for the per-vertex cost
// of a frame as the sheet grows (issue 13's target 3 compares N = 512 and 1024 with N = 128,
// whose state fits a large L3). For each size, one array allocated as the fast backend's state
// is (fast/aligned.h: huge pages where the kernel gives them) and first touched by the thread
// that reads it; then REPS rounds of a streaming read (BM_Stream's read kernel, GB/s) and of
// random 64-byte lines (BM_Stream's gather, ns a line on each thread and M lines/s in all),
// medians over the rounds. The last column sets each size's line time against the smallest
// size's. Sizes: the MiB given, or by default 16 MiB doubling to 8 GiB, within a quarter of the
// machine's memory.
// Usage: crumple_memory_probe THREADS REPS [MiB ...]
#include <oneapi/tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "fast/aligned.h"
#include "probe_common.h"
#include "stream_kernels.h"

namespace {

using Clock = std::chrono::steady_clock;
using crumple::bench::for_thread_chunks;

/// The largest array whose 64-byte lines a 32-bit line order numbers (random_line_order).
constexpr std::size_t kMaxMiB = (std::size_t{1} << 32) * 64 / (1 << 20) - 1;

struct Rates {
  double read_gbs = 0;     ///< streaming read, GB/s
  double line_ns = 0;      ///< random lines: ns a line on each thread
  double lines_per_s = 0;  ///< random lines, all threads
};

struct Freed {
  std::size_t bytes;
  void operator()(double* p) const { crumple::fast::free_aligned(p, bytes); }
};

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// One pass of `kernel` over the chunks of [0, n); returns its seconds and keeps its sums live.
template <class Kernel>
double timed_pass(int threads, std::size_t n, Kernel kernel) {
  std::vector<double> partial(std::size_t(threads), 0.0);
  const Clock::time_point t0 = Clock::now();
  for_thread_chunks(threads, n, [&](int t, std::size_t b, std::size_t e) { partial[std::size_t(t)] = kernel(b, e); });
  const double seconds = seconds_since(t0);
  volatile double sink = 0;
  for (double p : partial) sink = sink + p;
  return seconds;
}

Rates measure(int threads, int reps, std::size_t mib) {
  const std::size_t bytes = mib << 20, n = bytes / sizeof(double), lines = bytes / 64;
  std::unique_ptr<double[], Freed> a(static_cast<double*>(crumple::fast::allocate_aligned(bytes)), Freed{bytes});
  for_thread_chunks(threads, n, [&](int, std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) a[i] = 1.0;
  });
  const std::vector<std::uint32_t> order = crumple::bench::random_line_order(lines);
  const double* p = a.get();
  auto read = [&](std::size_t b, std::size_t e) { return crumple::bench::read_sum(p, b, e); };
  auto gather = [&](std::size_t b, std::size_t e) { return crumple::bench::gather_lines(p, order.data(), b, e); };
  timed_pass(threads, n, read);  // warm-up passes, untimed
  timed_pass(threads, lines, gather);
  std::vector<double> read_s, gather_s;
  for (int r = 0; r < reps; ++r) {
    read_s.push_back(timed_pass(threads, n, read));
    gather_s.push_back(timed_pass(threads, lines, gather));
  }
  const double rs = crumple::bench::median(read_s), gs = crumple::bench::median(gather_s);
  return Rates{double(bytes) / rs * 1e-9, gs * 1e9 * threads / double(lines), double(lines) / gs};
}

/// 16 MiB doubling to 8 GiB, each within a quarter of the physical memory.
std::vector<std::size_t> default_sizes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const std::size_t memory_mib = pages > 0 && page > 0 ? std::size_t(pages) * std::size_t(page) >> 20 : 0;
  std::vector<std::size_t> sizes;
  for (std::size_t mib = 16; mib <= 8192 && mib <= memory_mib / 4; mib *= 2) sizes.push_back(mib);
  return sizes;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: crumple_memory_probe THREADS REPS [MiB ...]\n");
    return 2;
  }
  auto number = [](const char* text, const char* what) {
    return crumple::bench::parse_number("crumple_memory_probe", text, what, true);
  };
  const double threads_arg = number(argv[1], "THREADS"), reps_arg = number(argv[2], "REPS");
  if (threads_arg < 1 || threads_arg > 1024 || reps_arg < 1 || reps_arg > 1000) {
    std::fprintf(stderr, "crumple_memory_probe: THREADS must be in [1, 1024] and REPS in [1, 1000]\n");
    return 2;
  }
  const int threads = int(threads_arg), reps = int(reps_arg);
  std::vector<std::size_t> sizes;
  for (int k = 3; k < argc; ++k) {
    const double mib = number(argv[k], "MiB");
    if (mib < 1 || mib > kMaxMiB) {  // the line order's 32-bit indices
      std::fprintf(stderr, "crumple_memory_probe: MiB must be in [1, %zu], got '%s'\n", kMaxMiB, argv[k]);
      return 2;
    }
    sizes.push_back(std::size_t(mib));
  }
  if (sizes.empty()) sizes = default_sizes();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  std::printf("%d thread(s), medians of %d rounds\n%8s %10s %14s %12s %14s\n", threads, reps, "MiB", "read GB/s",
              "ns a line", "M lines/s", "line / first");
  double first_ns = 0;
  for (std::size_t mib : sizes) {
    const Rates r = measure(threads, reps, mib);
    if (first_ns == 0) first_ns = r.line_ns;
    std::printf("%8zu %10.1f %14.2f %12.1f %14.2f\n", mib, r.read_gbs, r.line_ns, r.lines_per_s * 1e-6,
                r.line_ns / first_ns);
    std::fflush(stdout);
  }
  return 0;
}
