// crumple_bench: runs every benchmark registered by the files of bench/ (bench_common.h).
// All Google Benchmark flags apply, e.g.
//   crumple_bench --benchmark_filter='BM_Frame/reference/' --benchmark_repetitions=5
//                 --benchmark_min_time=0.5 --benchmark_out=out.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <string>

#include "bench_build_info.h"
#include "bench_common.h"
#include "sim/backends.h"

int main(int argc, char** argv) {
  std::string backends;
  for (const std::string& b : crumple::backend_names()) backends += (backends.empty() ? "" : ",") + b;
  benchmark::AddCustomContext("crumple_backends", backends);
#ifdef __clang__
  benchmark::AddCustomContext("crumple_compiler", "clang " __VERSION__);
#else
  benchmark::AddCustomContext("crumple_compiler", "g++ " __VERSION__);
#endif
  benchmark::AddCustomContext("crumple_build_type", CRUMPLE_BENCH_BUILD_TYPE);
  benchmark::AddCustomContext("crumple_cxx_flags", CRUMPLE_BENCH_CXX_FLAGS);
  std::string batches;
  for (int n : crumple::bench::kSizes)
    batches += (batches.empty() ? "" : ", ") + std::to_string(n) + ": " + std::to_string(crumple::bench::frames_per_iteration(n));
  benchmark::AddCustomContext("crumple_frames_per_iteration", batches);
  crumple::bench::run_registrars();

  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
