// The kernels that measure the machine's memory (BM_Stream, crumple_memory_probe): a streaming
// read in wide independent sums, and the random-line gather. Each runs over [begin, end) and
// returns a value that depends on every element it read.
#pragma once

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

namespace crumple::bench {

/// Runs f(t, begin, end) over [0, n) in `threads` equal chunks t, one per thread (static
/// partitioner: the same chunks every call, so each thread streams the memory it first touched).
template <class F>
void for_thread_chunks(int threads, std::size_t n, F f) {
  const std::size_t chunk = (n + std::size_t(threads) - 1) / std::size_t(threads);
  tbb::parallel_for(
      0, threads,
      [&](int t) {
        const std::size_t begin = std::size_t(t) * chunk;
        f(t, begin, std::min(n, begin + chunk));
      },
      tbb::static_partitioner());
}

/// The read kernel's sums: kAccumulators vectors of kLaneCount doubles (one AVX-512 register).
typedef double Lanes __attribute__((vector_size(64)));
inline constexpr std::size_t kLaneCount = sizeof(Lanes) / sizeof(double), kAccumulators = 4;
inline constexpr std::size_t kLineDoubles = 64 / sizeof(double);

/// s += a[i] over [begin, end). Wide independent sums: a scalar sum is a chain of dependent
/// adds, bound by the add's latency, not by memory; GCC does not vectorize the reduction
/// without -ffast-math, so the lanes are spelled out.
inline double read_sum(const double* __restrict a, std::size_t begin, std::size_t end) {
  constexpr std::size_t kStep = kLaneCount * kAccumulators;
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
  return s;
}

/// The gather's line order over `lines` lines (at most 2^32): a random permutation, the same
/// every run.
inline std::vector<std::uint32_t> random_line_order(std::size_t lines) {
  std::vector<std::uint32_t> order(lines);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(1));
  return order;
}

/// s += a[8 p[i]] over [begin, end) of the line order p, in independent sums (the loads overlap
/// as far as the core's outstanding misses allow: that limit is what the kernel measures).
inline double gather_lines(const double* __restrict a, const std::uint32_t* __restrict lines, std::size_t begin,
                           std::size_t end) {
  double s[4] = {0, 0, 0, 0};
  std::size_t i = begin;
  for (; i + 4 <= end; i += 4)
    for (std::size_t l = 0; l < 4; ++l) s[l] += a[std::size_t(lines[i + l]) * kLineDoubles];
  for (; i < end; ++i) s[0] += a[std::size_t(lines[i]) * kLineDoubles];
  return (s[0] + s[1]) + (s[2] + s[3]);
}

}  // namespace crumple::bench
