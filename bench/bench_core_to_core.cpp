// BM_CoreToCore/2/64: how long two CPUs take to pass one 64-byte cache line back and forth, per
// round trip. Two threads, pinned to the first two CPUs the process may use, take turns writing
// a counter the other waits for. Cores that share a last-level cache answer in some tens of
// nanoseconds; cores on separate ones (two chiplets, two sockets, or a VM's vCPUs placed so)
// take hundreds, and then each core also caches only its own half of a state the passes hand
// between the threads: two threads gain little on sheets that fit one core's cache
// (docs/PERFORMANCE.md). Reported: ns_per_round_trip, and the time per iteration (manual time).
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.h"

namespace crumple::bench {
namespace {

constexpr int kRoundTrips = 100000;  ///< per iteration: some tens of milliseconds at the slowest

/// The CPUs this process may run on, in order (sched_getaffinity).
std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  return cpus;
}

bool pin_to(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

/// The counter the two threads hand back and forth, alone on its line.
struct alignas(64) Line {
  std::atomic<long> turn{0};
};

/// kRoundTrips round trips, timed on this thread: it writes odd values from base + 1 on, and
/// the partner thread answers each with the next even one.
double bounce(Line& line, long base) {
  const Clock::time_point t0 = Clock::now();
  for (long i = 0; i < kRoundTrips; ++i) {
    const long ask = base + 2 * i + 1;
    line.turn.store(ask, std::memory_order_release);
    while (line.turn.load(std::memory_order_acquire) != ask + 1) {
    }
  }
  return seconds_between(t0, Clock::now());
}

void BM_CoreToCore(benchmark::State& state) {
  const std::vector<int> cpus = allowed_cpus();
  if (cpus.size() < 2) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  const pthread_t self = pthread_self();
  cpu_set_t before;
  CPU_ZERO(&before);
  pthread_getaffinity_np(self, sizeof before, &before);
  Line line;
  std::atomic<bool> stop{false};
  std::atomic<int> partner_pinned{-1};  // -1 until the partner has tried, then 0 or 1
  std::thread partner([&] {
    partner_pinned = pin_to(cpus[1]) ? 1 : 0;
    long seen = 0;
    while (!stop.load(std::memory_order_relaxed)) {
      const long v = line.turn.load(std::memory_order_acquire);
      if (v != seen && (v & 1)) line.turn.store(v + 1, std::memory_order_release), seen = v + 1;
    }
  });
  const bool pinned = pin_to(cpus[0]);
  while (partner_pinned.load() < 0) std::this_thread::yield();
  auto finish = [&] {
    stop = true;
    partner.join();
    pthread_setaffinity_np(self, sizeof before, &before);  // the benchmarks after this one run unpinned
  };
  // Unpinned, the two threads may share one CPU, and a round trip would time the scheduler.
  if (!pinned || partner_pinned.load() != 1) {
    finish();
    const std::string error =
        "could not pin its two threads to CPUs " + std::to_string(cpus[0]) + " and " + std::to_string(cpus[1]);
    state.SkipWithError(error.c_str());
    return;
  }
  double seconds = 0;
  long base = 0;
  for (auto _ : state) {
    const double s = bounce(line, base);
    base += 2 * kRoundTrips;
    state.SetIterationTime(s);
    seconds += s;
  }
  finish();
  state.counters["ns_per_round_trip"] = 1e9 * seconds / (double(kRoundTrips) * double(state.iterations()));
}

void register_core_to_core_benchmarks() {
  benchmark::RegisterBenchmark("BM_CoreToCore/2/64", BM_CoreToCore)->Unit(benchmark::kMillisecond)->UseManualTime();
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_core_to_core_benchmarks);

}  // namespace crumple::bench
