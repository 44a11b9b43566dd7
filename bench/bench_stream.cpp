// BM_Stream/<kernel>/<threads>/<MiB>: the machine's streaming bandwidth, STREAM-like, measured
// in the same run as the frames so that scripts/bench_report.py can set each pass's achieved
// bandwidth against it (the roofline). Kernels over arrays of doubles, each kArrayMiB:
//   read   s += a[i]            8 bytes per element
//   copy   c[i] = a[i]          16 bytes (STREAM's count: the write-allocate read is not counted)
//   triad  a[i] = b[i] + q c[i] 24 bytes (idem)
// Each array is 128 MiB, four times the largest L3 this runs on (32 MiB per Zen CCD), so every
// pass comes from memory. Threads as in the other benchmarks: tbb::global_control caps the
// parallelism at T; the range is cut into T equal static chunks (static_partitioner), the same
// chunks that first touched the pages, so each thread streams the memory it faulted in.
// Reported: bytes_per_second (a kIsRate counter of the bytes above: GB/s in the report), and
// the time per pass (manual time, steady_clock).
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench_common.h"

namespace crumple::bench {
namespace {

constexpr std::size_t kArrayMiB = 128;
constexpr std::size_t kElements = kArrayMiB * 1024 * 1024 / sizeof(double);

/// The read kernel's sums: kAccumulators vectors of kLaneCount doubles (one AVX-512 register).
typedef double Lanes __attribute__((vector_size(64)));
constexpr std::size_t kLaneCount = sizeof(Lanes) / sizeof(double), kAccumulators = 4;
constexpr std::size_t kStep = kLaneCount * kAccumulators;

enum class Kernel { Read, Copy, Triad };
constexpr double bytes_per_element(Kernel k) { return k == Kernel::Read ? 8 : k == Kernel::Copy ? 16 : 24; }

struct Arrays {
  std::unique_ptr<double[]> a, b, c;
};

/// Runs f(t, begin, end) over [0, kElements) in `threads` equal chunks t, one per thread.
template <class F>
void for_chunks(int threads, F f) {
  const std::size_t chunk = (kElements + std::size_t(threads) - 1) / std::size_t(threads);
  tbb::parallel_for(
      0, threads,
      [&](int t) {
        const std::size_t begin = std::size_t(t) * chunk;
        f(t, begin, std::min(kElements, begin + chunk));
      },
      tbb::static_partitioner());
}

Arrays make_arrays(int threads) {
  Arrays m{std::unique_ptr<double[]>(new double[kElements]), std::unique_ptr<double[]>(new double[kElements]),
           std::unique_ptr<double[]>(new double[kElements])};
  for_chunks(threads, [&](int, std::size_t b, std::size_t e) {  // first touch by the thread that streams it
    for (std::size_t i = b; i < e; ++i) m.a[i] = 1.0, m.b[i] = 2.0, m.c[i] = 0.5;
  });
  return m;
}

/// One pass of the kernel; returns a value that depends on every element read (read kernel).
double run(Kernel k, Arrays& m, int threads) {
  double* __restrict a = m.a.get();
  double* __restrict b = m.b.get();
  double* __restrict c = m.c.get();
  std::vector<double> partial(std::size_t(threads), 0.0);
  for_chunks(threads, [&](int t, std::size_t begin, std::size_t end) {
    if (k == Kernel::Read) {
      // Wide independent sums: a scalar sum is a chain of dependent adds, bound by the add's
      // latency (~8 GB/s here), not by memory; GCC does not vectorize the reduction without
      // -ffast-math, so the lanes are spelled out.
      Lanes acc[kAccumulators] = {};
      std::size_t i = begin;
      for (; i + kStep <= end; i += kStep)
        for (std::size_t l = 0; l < kAccumulators; ++l) {
          Lanes x;
          std::memcpy(&x, a + i + l * kLaneCount, sizeof x);
          acc[l] += x;
        }
      double s = 0;
      for (; i < end; ++i) s += a[i];
      for (const Lanes& x : acc)
        for (std::size_t l = 0; l < kLaneCount; ++l) s += x[l];
      partial[std::size_t(t)] = s;
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
  Arrays m = make_arrays(threads);
  run(kernel, m, threads);  // untimed warm-up pass
  for (auto _ : state) {
    const Clock::time_point t0 = Clock::now();
    benchmark::DoNotOptimize(run(kernel, m, threads));
    benchmark::ClobberMemory();
    state.SetIterationTime(seconds_between(t0, Clock::now()));
  }
  state.counters["bytes_per_second"] = benchmark::Counter(
      bytes_per_element(kernel) * double(kElements) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["bytes"] = bytes_per_element(kernel) * double(kElements);
}

void register_stream_benchmarks() {
  const std::pair<const char*, Kernel> kernels[] = {{"read", Kernel::Read}, {"copy", Kernel::Copy}, {"triad", Kernel::Triad}};
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
