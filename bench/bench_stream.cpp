// BM_Stream/<kernel>/<threads>/<MiB>: the machine's streaming bandwidth, STREAM-like, measured
// in the same run as the frames so that scripts/bench_report.py can set each pass's achieved
// bandwidth against it (the roofline). Kernels over arrays of doubles, each kArrayMiB:
//   read   s += a[i]            8 bytes per element
//   copy   c[i] = a[i]          16 bytes (STREAM's count: the write-allocate read is not counted)
//   triad  a[i] = b[i] + q c[i] 24 bytes (idem)
//   gather s += a[8 p[i]]       64 bytes: one double from each 64-byte line of a, the lines in a
//                               fixed random order p (independent loads, as a pass's or an event's
//                               scattered reads of rows; the index stream is not counted)
// The gather is no streaming kernel: it is the rate at which the machine serves lines at random,
// the roof of a pass whose reads miss at scattered places, and is left out of the STREAM roof.
// Each array is four times the L3 that the machine reports, rounded up to a multiple of 128 MiB
// (128 MiB on a 32 MiB Zen L3 or where none is reported, 1,152 MiB on a 260 MiB Xeon L3; the
// L3 is what glibc reads from cpuid, which a VM may set apart from lscpu's: 320 MiB on a Zen 4
// VM whose lscpu shows 32, hence 1,280 MiB there; the three arrays within a quarter of the
// memory: array_mib), so every pass comes from memory,
// not from a cache that holds a whole array; allocated as the fast backend's state is (on huge
// pages where the kernel gives them: with 4 KiB pages the gather's lines also miss the TLB).
// Threads as in the other benchmarks: tbb::global_control caps the parallelism at T; the range
// is cut into T equal static chunks (static_partitioner), the same chunks that first touched
// the pages, so each thread streams the memory it faulted in.
// Reported: bytes_per_second (a kIsRate counter of the bytes above: GB/s in the report), and
// the time per pass (manual time, steady_clock).
#include <oneapi/tbb/global_control.h>

#include <unistd.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "bench_common.h"
#include "fast/aligned.h"
#include "stream_kernels.h"

namespace crumple::bench {
namespace {

constexpr std::size_t kMinArrayMiB = 128, kCacheMultiple = 4;
/// The three arrays together take at most this share of the machine's memory.
constexpr std::size_t kMemoryShare = 4;

/// Each array's size in MiB: kCacheMultiple times the L3 that sysconf reports (glibc reads it
/// from cpuid; 0 where the VM reports none), rounded up to a multiple of kMinArrayMiB, at least
/// kMinArrayMiB, and the three arrays within 1 / kMemoryShare of the physical memory (rounded
/// down, but never below kMinArrayMiB). A name carries it (BM_Stream/read/2/128), so runs on one
/// machine compare.
std::size_t array_mib() {
  const long l3 = sysconf(_SC_LEVEL3_CACHE_SIZE);
  const std::size_t want = l3 > 0 ? kCacheMultiple * std::size_t(l3) / (1024 * 1024) : 0;
  const std::size_t blocks = std::max<std::size_t>(1, (want + kMinArrayMiB - 1) / kMinArrayMiB);
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const std::size_t memory_mib = pages > 0 && page > 0 ? std::size_t(pages) * std::size_t(page) / (1024 * 1024) : 0;
  const std::size_t most = std::max<std::size_t>(1, memory_mib / (3 * kMemoryShare) / kMinArrayMiB);
  return std::min(blocks, most) * kMinArrayMiB;
}
const std::size_t kArrayMiB = array_mib();
const std::size_t kElements = kArrayMiB * 1024 * 1024 / sizeof(double);

enum class Kernel { Read, Copy, Triad, Gather };
const std::size_t kLines = kElements / kLineDoubles;
/// Bytes a pass moves, as STREAM counts them (the gather: every line it reads, whole).
double pass_bytes(Kernel k) {
  return k == Kernel::Gather ? 64.0 * double(kLines)
                             : double(kElements) * (k == Kernel::Read ? 8 : k == Kernel::Copy ? 16 : 24);
}

/// An array allocated as the fast backend allocates its state (fast/aligned.h: huge pages where
/// the kernel gives them), so the roof is measured on the memory the passes read.
struct FastArray {
  void operator()(double* p) const { fast::free_aligned(p, kElements * sizeof(double)); }
};
using Doubles = std::unique_ptr<double[], FastArray>;
Doubles make_doubles() { return Doubles(static_cast<double*>(fast::allocate_aligned(kElements * sizeof(double)))); }

struct Arrays {
  Doubles a, b, c;
  std::vector<std::uint32_t> lines;  ///< the gather's line order: a random permutation
};

Arrays make_arrays(int threads, Kernel kernel) {
  Arrays m{make_doubles(), make_doubles(), make_doubles(), {}};
  for_thread_chunks(threads, kElements, [&](int, std::size_t b, std::size_t e) {  // first touch by the thread that streams it
    for (std::size_t i = b; i < e; ++i) m.a[i] = 1.0, m.b[i] = 2.0, m.c[i] = 0.5;
  });
  if (kernel == Kernel::Gather) m.lines = random_line_order(kLines);
  return m;
}

/// One pass of the kernel; returns a value that depends on every element read (read kernel).
double run(Kernel k, Arrays& m, int threads) {
  double* __restrict a = m.a.get();
  double* __restrict b = m.b.get();
  double* __restrict c = m.c.get();
  std::vector<double> partial(std::size_t(threads), 0.0);
  if (k == Kernel::Gather) {
    for_thread_chunks(threads, kLines, [&](int t, std::size_t b, std::size_t e) {
      partial[std::size_t(t)] = gather_lines(a, m.lines.data(), b, e);
    });
    return std::accumulate(partial.begin(), partial.end(), 0.0);
  }
  for_thread_chunks(threads, kElements, [&](int t, std::size_t begin, std::size_t end) {
    if (k == Kernel::Read) {
      partial[std::size_t(t)] = read_sum(a, begin, end);
    } else if (k == Kernel::Copy) {
      for (std::size_t i = begin; i < end; ++i) c[i] = a[i];
    } else {
      for (std::size_t i = begin; i < end; ++i) a[i] = b[i] + 0.5 * c[i];
    }
  });
  double sum = 0;
  for (double p : partial) sum += p;
  return sum;
}

void BM_Stream(benchmark::State& state, Kernel kernel, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  Arrays m = make_arrays(threads, kernel);
  run(kernel, m, threads);  // untimed warm-up pass
  for (auto _ : state) {
    const Clock::time_point t0 = Clock::now();
    benchmark::DoNotOptimize(run(kernel, m, threads));
    benchmark::ClobberMemory();
    state.SetIterationTime(seconds_between(t0, Clock::now()));
  }
  state.counters["bytes_per_second"] =
      benchmark::Counter(pass_bytes(kernel) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["bytes"] = pass_bytes(kernel);
}

void register_stream_benchmarks() {
  const std::pair<const char*, Kernel> kernels[] = {
      {"read", Kernel::Read}, {"copy", Kernel::Copy}, {"triad", Kernel::Triad}, {"gather", Kernel::Gather}};
  for (const auto& [label, kernel] : kernels)
    for (int threads : {1, 2}) {
      const std::string name = std::string("BM_Stream/") + label + "/" + std::to_string(threads) + "/" +
                               std::to_string(kArrayMiB);
      benchmark::RegisterBenchmark(name.c_str(), BM_Stream, kernel, threads)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime();
    }
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_stream_benchmarks);

}  // namespace crumple::bench
