// BM_Pass/<pass>/<backend>/<threads>/<N>: one pass of one step, alone, at the prepared crumple
// state of BM_Frame (kPrepFraction of sphere_time into the default sphere scene), so each step
// of the speed-up is visible per pass: the reference, the fast kernels without SIMD (a build
// with -DCRUMPLE_DISABLE_SIMD=ON, labelled fast-nosimd), with SIMD on one thread, on two.
//
// Each iteration restores the prepared state (clone and one warm-up step, untimed), runs the
// step's earlier passes untimed so the timed pass sees the inputs it has inside a step, and times that pass alone
// with steady_clock (manual time). Passes and their order come from Simulator::pass_names():
// the reference computes springs and bending in separate loops; the fast backend fuses them in
// one edge pass (edge_forces) followed by a per-vertex gather. `topology_apply` is the whole
// adapt pass (its test, the splits in parallel rounds and the serial restores); `adapt_test` the
// test alone. The fast backend's `layout` pass (docs/DECISIONS.md D12) is not timed alone.
// Fast backend only: `bytes`, what the pass must move counted from the layout of the state it
// runs on (bytes_moved.h; for topology_apply with the splits and restores of that step, from a
// dry run of it on a clone), and `bytes_per_second`, those bytes over the pass's time: the
// achieved bandwidth the report sets against BM_Stream's.
#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <tuple>

#include "bench_common.h"
#include "bytes_moved.h"
#include "mesh/input_mesh.h"
#include "probe_common.h"
#include "sim/backends.h"

namespace crumple::bench {
namespace {

constexpr std::array<int, 2> kPassSizes{128, 256};

std::unique_ptr<Simulator>& prepared(const std::string& backend, int threads, int n) {
  static std::map<std::tuple<std::string, int, int>, std::unique_ptr<Simulator>> cache;
  auto& sim = cache[std::make_tuple(backend, threads, n)];
  if (!sim) {
    const Params params;
    sim = make_simulator(backend, make_grid(n), params, threads);
    const int steps = int(std::lround(kPrepFraction * params.sphere_time / params.h()));  // BM_Frame's point
    for (int s = 0; s < steps; ++s) sim->step();
  }
  return sim;
}

/// What `pass` moves in the step that starts from sim's state (0: not a fast backend).
double bytes_of(const Simulator& sim, const std::string& pass) {
  const std::optional<LayoutSizes> sizes = layout_sizes(sim);
  if (!sizes) return 0;
  double events = 0;
  if (pass == "topology_apply") {  // the events this step applies, from a dry run of it
    const StepEvents ev = sim.clone()->step();
    events = ev.splits + ev.restores;
  }
  return pass_bytes(pass, *sizes, Params{}.sweeps, events);
}

void BM_Pass(benchmark::State& state, const std::string& backend, int threads, int n, const std::string& pass) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  const std::unique_ptr<Simulator>& base = prepared(backend, threads, n);
  const std::vector<std::string> order = base->pass_names();
  double seconds = 0, bytes = -1;
  for (auto _ : state) {
    std::unique_ptr<Simulator> sim = base->clone();
    sim->step();  // untimed warm-up step: a fresh clone's first splits reallocate (bench_frame.cpp)
    if (bytes < 0) bytes = bytes_of(*sim, pass);  // untimed, once: every iteration runs the same step
    for (const std::string& earlier : order) {  // untimed: the inputs this pass sees in a step
      if (earlier == pass) break;
      if (earlier != "topology_apply") sim->run_pass(earlier);
    }
    const Clock::time_point t0 = Clock::now();
    sim->run_pass(pass);
    const double dt = seconds_between(t0, Clock::now());
    state.SetIterationTime(dt);
    seconds += dt;
  }
  state.counters["ms_per_pass"] = state.iterations() ? 1e3 * seconds / double(state.iterations()) : 0.0;
  state.counters["vertices"] = base->totals().vertices;
  if (bytes > 0) {
    state.counters["bytes"] = bytes;
    state.counters["bytes_per_second"] = benchmark::Counter(bytes * double(state.iterations()), benchmark::Counter::kIsRate);
  }
}

void register_pass_benchmarks() {
  for (const std::string& backend : backend_names()) {
    const bool reference = backend == "reference";
    const std::unique_ptr<Simulator> probe = make_simulator(backend, make_grid(4), Params{}, 1);
    for (const std::string& pass : probe->pass_names()) {
      // A relayout runs once every several frames (when a quarter of the slots are new); timed
      // alone it would count as a per-frame pass in the breakdown. Its amortized cost is in
      // BM_Frame.
      if (pass == "layout") continue;
      for (int threads : {1, 2}) {
        if (reference && threads != 1) continue;
        for (int n : kPassSizes) {
          const std::string name = "BM_Pass/" + pass + "/" + bench_label(backend) + "/" + std::to_string(threads) +
                                   "/" + std::to_string(n);
          // A fixed iteration count: each iteration's untimed set-up (clone, warm-up step,
          // earlier passes) costs up to 50x the timed pass, so --benchmark_min_time (which
          // counts only the manual time) would spend minutes per benchmark.
          benchmark::RegisterBenchmark(name.c_str(), BM_Pass, backend, threads, n, pass)
              ->Unit(benchmark::kMillisecond)
              ->UseManualTime()
              ->Iterations(8);
        }
      }
    }
  }
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_pass_benchmarks);

}  // namespace crumple::bench
