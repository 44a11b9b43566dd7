// BM_Frame/<backend>/<threads>/<N>: one whole 1/60 s frame (params.substeps steps) of the paper's
// sphere crumple (crumple::Params{}, paper_params()) on make_grid(N), for every registered backend,
// as one Sheet::step call of the embedding API; BM_Steps and BM_Frozen: the same frames as bare
// steps; BM_Default: one frame of the command's default configuration (default_params(), D28);
// BM_Pair: BM_Frame's frames on 1 and on 2 threads in alternating pairs (the 2-thread speed-up).
//
// Preparation (outside timing, once per benchmark and cached for the process): the sheet is
// simulated into the crumple, kPrepFraction of sphere_time, i.e. to a state where edges split
// and restore every frame; then a dry run of the warm-up and timed frames on a clone records
// the mean live vertices/edges and the splits/restores of the timed frames.
//
// Comparable work per iteration, and why manual timing:
//   * Every iteration starts from the same prepared state: sim->clone() of the cached state,
//     made outside the timed region (BM_Frame: into a fresh sheet, SheetAccess::adopt, which
//     also packs the render buffers once), and destroyed outside it. The model is deterministic
//     (counter-based random stream keyed by edge id), so each iteration simulates the very
//     same frames; the `mismatch` counter counts iterations whose
//     splits/restores differ from the dry run (0 expected) and would reveal otherwise.
//   * One untimed warm-up frame runs on the clone before the timed frames: the first frame
//     after a clone costs more than a frame of the continuing simulation (a clone's arrays
//     can be allocated to their exact size, so its first splits reallocate and fault in every
//     growing array, which a running simulation amortizes; cold caches and sleeping TBB
//     workers add to it; docs/PERFORMANCE.md, "The benchmarks' prepared state"). From the
//     second frame on, a clone runs at the continuing simulation's speed, which is what a
//     frame of a crumpling sheet costs.
//   * BM_Frame's timed region holds only Sheet::step calls (crumple/crumple.h, the embedding
//     API), one per frame, which is what an engine's frame loop calls and times: the frame's
//     steps plus what the API does around them each call (hand over the manipulators, pack the
//     render buffers, positions and normals every frame and the triangles when the topology
//     changed, and the totals pass of the instability check). BM_Steps and BM_Frozen (below)
//     time bare Simulator::step calls; docs/PERFORMANCE.md gives BM_Frame against BM_Steps. No
//     clone, no destruction inside. It is measured with steady_clock and reported with
//     SetIterationTime (UseManualTime). PauseTiming/ResumeTiming
//     would need the same untimed clone + warm-up anyway, with more overhead inside the
//     measurement: each pair reads the process CPU clock (a system call, ~1 us) inside the timed
//     interval, a few per cent of the fast backend's sub-100 us frames at N = 32; manual timing
//     costs two vDSO clock reads (~20 ns) per batch.
//   * A batch of frames_per_iteration(N) frames (8) is timed per iteration and divided, so each
//     iteration's time is the mean frame time of a fixed stretch of the crumple, long enough
//     to hold the fast backend's occasional relayout at its usual rate; the batch is fixed so
//     that every backend, thread count and revision times the same frames.
//   * BM_Frame and BM_Default also report `longest_ms`, the longest single frame of an
//     iteration's batch (each frame timed by one clock read after it; the median over the
//     repetition's iterations, which all simulate the same frames): the frame a real-time loop
//     must fit. In the fast backend it is a frame that runs one of a relayout's five phases
//     (layout.h), when the batch holds one (a relayout about once every 8-11 frames at the
//     prepared point, bench_common.cpp).
//   * The reported cpu_time is not meaningful (it includes the untimed clone and warm-up, on
//     the main thread only); use real_time, which is the manual time.
// Threads: tbb::global_control(max_allowed_parallelism, T) for the whole benchmark function,
// preparation included, and T is passed to make_simulator. The prepared state is cached per
// (backend, T, N): the thread count is fixed when a simulator is made and clone() keeps it, and
// the interface cannot change it afterwards, so one prepared object cannot serve both counts.
#include <oneapi/tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "api/sheet_access.h"
#include "bench_common.h"
#include "bytes_moved.h"
#include "core_to_core.h"
#include "crumple/crumple.h"
#include "prepared.h"
#include "probe_common.h"
#include "mesh/input_mesh.h"
#include "sim/backends.h"
#include "sim/run.h"
#include "sim/scene.h"

namespace crumple::bench {
namespace {

// The timed frames start at the prepared point (probe_common.h). An unstable prepared state
// skips the benchmark with the reason instead of timing it.

/// Largest N at which the reference backend is benchmarked: a frame must cost under ~2 s, and a
/// reference frame at N = 1024 costs about that, after minutes of preparation, so N = 1024 is
/// left to the fast backend (docs/PERFORMANCE.md, "The benchmarks' prepared state").
constexpr int kReferenceMaxN = 512;

/// Largest N of BM_Default: its frames take tens of steps (docs/DECISIONS.md D28), so a frame at
/// N = 256 costs about what the paper's costs at N = 1024, and its preparation minutes.
constexpr int kDefaultMaxN = 256;
constexpr int kDefaultReferenceMaxN = 64;

Prepared make_prepared(const std::string& backend, int threads, int n, Config config) {
  Prepared p;
  const Params params = config == Config::Paper ? paper_params() : default_params();  // sphere scene
  const InputMesh mesh = make_grid(n);
  const double size = make_scene(mesh, params).size;
  p.params = params;
  p.substeps = params.substeps;
  p.size = size;
  p.sim = make_simulator(backend, mesh, params, threads);
  const int prep_frames = prepared_frames(params);
  for (int f = 1; f <= prep_frames; ++f) {
    const FrameStats s = run_frame(*p.sim, params, f);  // the default: substeps chosen per frame
    if (std::string why = instability(s.totals, size); !why.empty()) {
      p.error = "unstable while preparing, frame " + std::to_string(f) + ": " + why;
      return p;
    }
  }
  const int k = frames_per_iteration(n);
  std::unique_ptr<Simulator> dry = p.sim->clone();
  for (int f = 0; f <= k; ++f) {  // f = 0: the untimed warm-up frame
    const FrameStats s = run_frame(*dry, params, prep_frames + 1 + f);
    if (std::string why = instability(s.totals, size); !why.empty()) {
      p.error = "unstable in the timed frames, frame " + std::to_string(prep_frames + 1 + f) + ": " + why;
      return p;
    }
    if (f == 0) continue;
    p.vertices += double(s.totals.vertices) / k;
    p.edges += double(s.totals.edges) / k;
    p.splits += s.splits;
    p.restores += s.restores;
  }
  if (p.splits == 0 && p.restores == 0)
    p.error = "no split or restore in the timed frames: not the crumple this benchmark is about";
  return p;
}

}  // namespace

Prepared& prepared(const std::string& backend, int threads, int n, Config config) {
  static std::map<std::tuple<std::string, int, int, Config>, Prepared> cache;
  const auto key = std::make_tuple(backend, threads, n, config);
  auto it = cache.find(key);
  if (it == cache.end()) {
    // Progress on stderr: with random interleaving Google Benchmark prints a benchmark's rows
    // only after its last repetition, and preparing the large sheets takes minutes.
    const Clock::time_point t0 = Clock::now();
    it = cache.emplace(key, make_prepared(backend, threads, n, config)).first;
    std::fprintf(stderr, "crumple_bench: prepared %s%s, %d thread(s), N = %d in %.1f s%s%s\n", backend.c_str(),
                 config == Config::Default ? " (default configuration)" : "", threads, n,
                 seconds_between(t0, Clock::now()), it->second.error.empty() ? "" : ": ",
                 it->second.error.c_str());
  }
  return it->second;
}

Prepared* prepared_or_skip(benchmark::State& state, const std::string& backend, int threads, int n, Config config) {
  Prepared& p = prepared(backend, threads, n, config);
  if (p.error.empty()) return &p;
  state.SkipWithError(p.error.c_str());
  return nullptr;
}

namespace {

// BM_Frame/<backend>/<threads>/<N> times frames as an engine runs them, one Sheet::step each.
// BM_Steps/<backend>/<threads>/<N> times the same frames as the backend's bare steps, and
// BM_Frozen/<backend>/<threads>/<N> those bare steps with fracture and restoration switched off
// (Simulator::set_adaptivity) before the warm-up frame: the physics of those frames alone, with
// the topology frozen. BM_Frame minus BM_Steps is what the API's call adds to the steps (render
// buffers, totals); BM_Steps minus BM_Frozen is what the events cost (fracture and restoration
// tests, splits, restores, relayouts), which scripts/bench_report.py divides by the events per
// frame. The two instruments stay on bare steps so that neither the event prices nor the frozen
// step's bandwidth floor (issue 13) carry the API's per-call passes. (A frozen step computes the
// normals at its start, where an adaptive step has them from its fracture test: that pass is in
// both. The frozen frames keep the prepared mesh, which the adaptive ones grow by ~1 % a frame,
// so the difference also holds the physics of the elements the events add; BM_Frozen's vertices
// and edges counters are the adaptive dry run's.) BM_FrozenFresh/fast/<threads>/<N> times the
// same frozen frames after one relayout of the prepared state (untimed): the prepared state lies
// late in a relayout interval, a fifth of its vertices created since the last one and stored at
// the arrays' ends, so the two bracket what the physics costs as the layout ages between
// relayouts (docs/PERFORMANCE.md, "The frozen step on a fresh layout").
/// A frozen frame's bytes floor (fast backend): substeps frozen steps on the prepared mesh,
/// which the frozen frames keep (bytes_moved.h); and those bytes over the frame time.
void set_floor_counters(benchmark::State& state, const Simulator& sim, int substeps) {
  const std::optional<LayoutSizes> sizes = layout_sizes(sim);
  if (!sizes) return;
  const double bytes = substeps * frozen_step_bytes(*sizes, Params{}.sweeps);
  state.counters["bytes"] = bytes;
  state.counters["bytes_per_second"] = benchmark::Counter(bytes * double(state.iterations()), benchmark::Counter::kIsRate);
}

/// What one iteration timed: k frames after an untimed warm-up frame, on a fresh clone.
struct Batch {
  double seconds = 0;
  double longest = 0;  ///< the longest single frame (api_batch only)
  long splits = 0, restores = 0;
};

/// BM_Frame: one Sheet::step per frame. Throws Error if the sheet became unstable.
Batch api_batch(const Prepared& p, int k) {
  const Params& params = p.params;
  Sheet sheet = SheetAccess::adopt(p.sim->clone(), params, p.size);  // untimed: restore
  sheet.step(params.frame_dt);                                        // untimed warm-up frame
  Batch b;
  // One clock read a frame: each frame's time is the gap between two reads, and the batch's
  // the gap between the first and the last, as with two reads around the loop.
  const Clock::time_point t0 = Clock::now();
  Clock::time_point before = t0;
  for (int f = 0; f < k; ++f) {
    const FrameEvents ev = sheet.step(params.frame_dt);
    const Clock::time_point after = Clock::now();
    b.longest = std::max(b.longest, seconds_between(before, after));
    before = after;
    b.splits += ev.splits;
    b.restores += ev.restores;
  }
  b.seconds = seconds_between(t0, before);
  return b;  // the sheet is destroyed after the clock stopped
}

/// BM_Steps and BM_Frozen: params.substeps bare Simulator::step calls per frame; `fresh`
/// (BM_FrozenFresh) relays the clone out first, untimed.
Batch step_batch(const Prepared& p, int k, bool frozen, bool fresh) {
  std::unique_ptr<Simulator> sim = p.sim->clone();  // untimed: restore the prepared state
  if (frozen) sim->set_adaptivity(false, false);
  if (fresh) sim->run_pass("layout");
  for (int s = 0; s < p.substeps; ++s) sim->step();  // untimed warm-up frame
  Batch b;
  const Clock::time_point t0 = Clock::now();
  for (int f = 0; f < k; ++f)
    for (int s = 0; s < p.substeps; ++s) {
      const StepEvents ev = sim->step();
      b.splits += ev.splits;
      b.restores += ev.restores;
    }
  b.seconds = seconds_between(t0, Clock::now());
  return b;
}

enum class Timed { Api, Steps, Frozen, FrozenFresh };

void BM_Frame(benchmark::State& state, const std::string& backend, int threads, int n, Timed timed,
              Config config) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  Prepared* prep = prepared_or_skip(state, backend, threads, n, config);
  if (!prep) return;
  Prepared& p = *prep;
  const int k = frames_per_iteration(n);
  const bool fresh = timed == Timed::FrozenFresh, frozen = fresh || timed == Timed::Frozen;
  const long want_splits = frozen ? 0 : p.splits, want_restores = frozen ? 0 : p.restores;
  FrameTally tally;
  long mismatch = 0;
  std::vector<double> longest;  // each iteration's longest frame (BM_Frame, BM_Default)
  for (auto _ : state) {
    Batch b;
    try {
      b = timed == Timed::Api ? api_batch(p, k) : step_batch(p, k, frozen, fresh);
    } catch (const Error& e) {  // the dry run was stable, so only a broken determinism gets here
      state.SkipWithError(e.what());
      break;
    }
    tally.add_batch(state, b.seconds, k);
    if (timed == Timed::Api) longest.push_back(b.longest);
    tally.splits += b.splits;
    tally.restores += b.restores;
    mismatch += (b.splits != want_splits || b.restores != want_restores);
  }
  tally.set_counters(state, p.vertices, p.edges);
  state.counters["mismatch"] = double(mismatch);
  if (frozen) set_floor_counters(state, *p.sim, p.substeps);
  // The median iteration's: every iteration simulates the same frames.
  if (!longest.empty()) state.counters["longest_ms"] = 1e3 * middle_value(longest);
}

// BM_Pair/<backend>/2/<N>: the same frames as BM_Frame on 1 thread and on 2, back to back in
// every iteration (which runs first alternates), so that both halves of a pair see the same
// neighbours on this shared VM: issue 13's target 4 asks for the median of such pairs. The
// iteration's time is the 2-thread frame; the counters give each side's mean frame and
// `speedup`, the 1-thread time over the 2-thread time summed over the repetition's pairs.
// A VM's host may move its two vCPUs between chips within minutes (docs/PERFORMANCE.md), and a
// repetition lasts about a second: before each pair the first two CPUs' round trip is sampled
// (core_to_core.h), and `round_trip_ns` (the repetition's median) with `near_placement` (1 when
// it is below kNearRoundTripNs) let the report group repetitions by placement. The sample runs
// outside the timed frames; without two pinnable CPUs the two counters are left out.
void BM_Pair(benchmark::State& state, const std::string& backend, int n) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
  Prepared* one = prepared_or_skip(state, backend, 1, n, Config::Paper);
  Prepared* two = one ? prepared_or_skip(state, backend, 2, n, Config::Paper) : nullptr;
  if (!two) return;
  const int k = frames_per_iteration(n);
  double seconds[2] = {0, 0};  // 1 thread, 2 threads
  long mismatch = 0, pairs = 0;
  std::vector<double> trips_ns;
  for (auto _ : state) {
    if (const double ns = first_two_cpus_round_trip_ns(kPlacementSampleTrips); ns > 0) trips_ns.push_back(ns);
    Batch b[2];
    try {
      const bool two_first = pairs % 2 == 1;
      for (int side : {two_first ? 1 : 0, two_first ? 0 : 1}) b[side] = api_batch(side == 0 ? *one : *two, k);
    } catch (const Error& e) {  // the dry runs were stable, so only a broken determinism gets here
      state.SkipWithError(e.what());
      break;
    }
    state.SetIterationTime(b[1].seconds / k);
    for (int side : {0, 1}) {
      const Prepared& p = side == 0 ? *one : *two;
      seconds[side] += b[side].seconds;
      mismatch += b[side].splits != p.splits || b[side].restores != p.restores;
    }
    ++pairs;
  }
  const double frames = double(std::max(1L, pairs * k));
  state.counters["ms_1t"] = 1e3 * seconds[0] / frames;
  state.counters["ms_2t"] = 1e3 * seconds[1] / frames;
  state.counters["speedup"] = seconds[1] > 0 ? seconds[0] / seconds[1] : 0.0;
  state.counters["vertices"] = two->vertices;
  state.counters["mismatch"] = double(mismatch);
  if (!trips_ns.empty() && trips_ns.size() == std::size_t(pairs)) {
    const double median_ns = middle_value(trips_ns);
    state.counters["round_trip_ns"] = median_ns;
    state.counters["near_placement"] = median_ns < kNearRoundTripNs ? 1.0 : 0.0;
  }
}

void register_frame_benchmarks() {
  // BM_Frame (the paper's configuration) and BM_Default (the command's, D28): the same prepared-
  // state method, one Sheet::step per frame; BM_Steps and BM_Frozen: the paper's as bare steps.
  for_each_config([](const std::string& backend, int threads) {
    const bool reference = backend == "reference";
    auto add = [&](const char* kind, int n, Timed timed, Config config) {
      benchmark::RegisterBenchmark(bench_name(kind, backend, threads, n).c_str(), BM_Frame, backend, threads, n,
                                   timed, config)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime();
    };
    for (int n : kSizes) {
      if (n <= (reference ? kReferenceMaxN : n)) add("Frame", n, Timed::Api, Config::Paper);
      if (n <= (reference ? kDefaultReferenceMaxN : kDefaultMaxN)) add("Default", n, Timed::Api, Config::Default);
    }
    for (int n : kPricedSizes) {
      add("Steps", n, Timed::Steps, Config::Paper);
      add("Frozen", n, Timed::Frozen, Config::Paper);
      if (!reference) add("FrozenFresh", n, Timed::FrozenFresh, Config::Paper);
    }
    if (reference || threads != 2) return;
    for (int n : kPairedSizes)
      benchmark::RegisterBenchmark(bench_name("Pair", backend, threads, n).c_str(), BM_Pair, backend, n)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime();
  });
  benchmark::AddCustomContext("crumple_prep_fraction_of_sphere_time", std::to_string(kPrepFraction));
  benchmark::AddCustomContext("crumple_near_round_trip_ns", std::to_string(int(kNearRoundTripNs)));
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_frame_benchmarks);

}  // namespace crumple::bench
