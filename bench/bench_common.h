// What every crumple benchmark file shares: sizes, the timing policy, counters, registration.
//
// Timing policy (bench_frame.cpp explains why): every benchmark uses manual timing. One
// benchmark iteration restores a prepared state outside the timed region (clone + one warm-up
// frame), then times frames_per_iteration(N) frames back to back with steady_clock and reports
// their mean with State::SetIterationTime, so the reported time (".../manual_time") is
// milliseconds per frame.
//
// Registration: a file defines `void register_xyz()` that calls benchmark::RegisterBenchmark,
// and adds `CRUMPLE_BENCH_REGISTRAR(register_xyz);` at namespace scope; main.cpp runs every
// registrar before benchmark::Initialize. Names follow BM_<Kind>/<backend>/<threads>/<N>
// (scripts/bench_report.py and scripts/gate.py parse them that way; per-pass benchmarks are
// expected as BM_Pass/<pass>/<backend>/<threads>/<N>).
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "sim/backends.h"

namespace crumple::bench {

/// The backend's name in benchmark names: the fast backend built with CRUMPLE_DISABLE_SIMD is
/// `fast-nosimd`, so one report holds scalar, SIMD and threaded runs of the same kernels.
inline std::string bench_label(const std::string& backend) {
#ifdef CRUMPLE_DISABLE_SIMD
  if (backend == "fast") return "fast-nosimd";
#endif
  return backend;
}

/// Sheet sizes: N x N vertex grids on the unit square.
inline constexpr std::array<int, 6> kSizes{32, 64, 128, 256, 512, 1024};

/// Sheet sizes of the benchmarks that price the physics and the events (BM_Steps, BM_Frozen,
/// BM_Events).
inline constexpr std::array<int, 3> kPricedSizes{128, 256, 512};

/// Sheet sizes of BM_Pair (two threads against one, frame by frame): issue 13's target 4 is
/// about N >= 256.
inline constexpr std::array<int, 3> kPairedSizes{256, 512, 1024};

/// BM_<kind>/<backend label>/<threads>/<n>.
inline std::string bench_name(const std::string& kind, const std::string& backend, int threads, int n) {
  return "BM_" + kind + "/" + bench_label(backend) + "/" + std::to_string(threads) + "/" + std::to_string(n);
}

/// Calls f(backend, threads) for every backend on 1 and 2 threads, the serial reference on 1.
template <class F>
void for_each_config(F f) {
  for (const std::string& backend : backend_names())
    for (int threads : {1, 2})
      if (backend != "reference" || threads == 1) f(backend, threads);
}

/// Frames timed back to back in one iteration, fixed per N (never adapted to the measured
/// speed) so that every backend, thread count and revision times exactly the same frames.
int frames_per_iteration(int n);

/// The middle value of a non-empty v (the upper one of two for an even count): what one
/// repetition reports of per-iteration or per-pair samples.
inline double middle_value(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

using Clock = std::chrono::steady_clock;
inline double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

/// Accumulates what the timed frames did and sets the standard counters at the end.
struct FrameTally {
  double seconds = 0;         ///< wall time of every timed frame
  long frames = 0;            ///< timed frames
  long splits = 0, restores = 0;

  /// Reports the batch's mean frame time as this iteration's time.
  void add_batch(benchmark::State& state, double batch_seconds, int batch_frames) {
    state.SetIterationTime(batch_seconds / batch_frames);
    seconds += batch_seconds;
    frames += batch_frames;
  }
  /// vertices/edges: mean live counts at the end of the timed frames (from a dry run);
  /// splits/restores: per frame over the timed frames; fps: frames per second of frame time
  /// (each iteration's manual time is one mean frame, so iterations / time is the frame rate);
  /// ms_per_frame: mean frame time.
  void set_counters(benchmark::State& state, double vertices, double edges) const;
};

using Registrar = void (*)();
bool add_registrar(Registrar fn);
void run_registrars();

}  // namespace crumple::bench

#define CRUMPLE_BENCH_REGISTRAR(fn) \
  [[maybe_unused]] static const bool crumple_bench_registrar_##fn = ::crumple::bench::add_registrar(fn)
