// The prepared crumple state shared by the benchmarks that time it (BM_Frame, BM_Steps,
// BM_Frozen, BM_Events): bench_frame.cpp prepares it once per (backend, threads, N) and caches it
// for the process.
#pragma once

#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "model/params.h"
#include "sim/simulator.h"

namespace crumple::bench {

/// The configuration a prepared crumple runs: the paper's (Params{}: BM_Frame, BM_Steps,
/// BM_Frozen, BM_Events) or the command's default (default_params(): BM_Default).
enum class Config { Paper, Default };

struct Prepared {
  std::unique_ptr<Simulator> sim;  ///< state at the prepared point
  Params params;                   ///< what it runs
  int substeps = 1;                ///< of the paper's configuration (the default chooses per frame)
  double size = 0;                 ///< the scene's size (sim/scene.h), for the API's instability check
  double vertices = 0, edges = 0;  ///< mean live counts at the end of each dry-run frame
  long splits = 0, restores = 0;   ///< events of the whole dry-run batch
  std::string error;               ///< non-empty: the benchmark is skipped with this message
};

/// The cached prepared state (made on first use, under the caller's TBB thread limit).
Prepared& prepared(const std::string& backend, int threads, int n, Config config = Config::Paper);
/// The same, or nullptr when it could not be prepared (the benchmark is then skipped with the
/// reason).
Prepared* prepared_or_skip(benchmark::State& state, const std::string& backend, int threads, int n,
                           Config config = Config::Paper);

}  // namespace crumple::bench
