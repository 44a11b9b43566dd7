// BM_CoreToCore/2/64: how long two CPUs take to pass one 64-byte cache line back and forth, per
// round trip (core_to_core.h), between the first two CPUs the process may use. Cores on
// separate last-level caches also each cache only their own half of a state the passes hand
// between the threads: two threads gain little on sheets that fit one core's cache
// (docs/PERFORMANCE.md). Reported: ns_per_round_trip, and the time per iteration (manual time).
#include <string>
#include <vector>

#include "bench_common.h"
#include "core_to_core.h"

namespace crumple::bench {
namespace {

constexpr long kRoundTrips = 100000;  ///< per iteration: some tens of milliseconds at the slowest

void BM_CoreToCore(benchmark::State& state) {
  const std::vector<int> cpus = allowed_cpus();
  if (cpus.size() < 2) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  double seconds = 0;
  for (auto _ : state) {
    const double s = round_trip_seconds(cpus[0], cpus[1], kRoundTrips);
    if (s < 0) {
      const std::string error =
          "could not pin its two threads to CPUs " + std::to_string(cpus[0]) + " and " + std::to_string(cpus[1]);
      state.SkipWithError(error.c_str());
      break;
    }
    state.SetIterationTime(s);
    seconds += s;
  }
  if (seconds > 0)
    state.counters["ns_per_round_trip"] = 1e9 * seconds / (double(kRoundTrips) * double(state.iterations()));
}

void register_core_to_core_benchmarks() {
  benchmark::RegisterBenchmark("BM_CoreToCore/2/64", BM_CoreToCore)->Unit(benchmark::kMillisecond)->UseManualTime();
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_core_to_core_benchmarks);

}  // namespace crumple::bench
