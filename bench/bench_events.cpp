// BM_Events/<backend>/<threads>/<N>: what applying one fixed batch of events costs, per event.
//
// The batch: the splits and restores of the first step after the warm-up frame of BM_Frame's
// prepared state (prepared.h), as the adapt pass of that step decides them. Every iteration
// restores the same state (clone + warm-up frame + the step's physics passes, all untimed,
// Simulator::run_pass in pass_names() order up to adapt_test), so every iteration applies the
// very same batch (the model is deterministic).
//
// What is timed: the adapt pass (run_pass("topology_apply"): normals, the fracture and
// restoration test of every edge, then the events applied, with their normal renewal) minus its
// test alone (run_pass("adapt_test") on a twin clone of the same state, timed just after), so
// what remains is the batch's application; divided by the batch's events, that is the
// iteration's time (manual time: seconds per event, clamped at 0 when noise makes the
// difference negative). A relayout, which a step may trigger after its events, is not in it
// (BM_Steps - BM_Frozen holds it). The batch's size comes from a dry run of the same step on
// another clone (Simulator::step's StepEvents): counters splits and restores per batch;
// us_per_event is the ratio of the summed times, which noise biases less than the per-iteration
// clamp; mismatch counts iterations whose pass left other live counts than the dry run (0
// expected: the run_pass sequence and step() decide the same batch).
#include <oneapi/tbb/global_control.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench_common.h"
#include "bytes_moved.h"
#include "prepared.h"

namespace crumple::bench {
namespace {

/// A clone of the prepared state after its warm-up frame and the physics passes of the next
/// step: the state whose adapt pass applies the batch.
std::unique_ptr<Simulator> before_events(const Prepared& p) {
  std::unique_ptr<Simulator> sim = p.sim->clone();
  for (int s = 0; s < p.substeps; ++s) sim->step();  // the warm-up frame (bench_frame.cpp)
  for (const std::string& pass : sim->pass_names()) {
    if (pass == "adapt_test") break;
    sim->run_pass(pass);
  }
  return sim;
}

struct Batch {
  StepEvents events;  ///< splits and restores of the recorded step
  Totals after;       ///< the live counts they leave
};

Batch recorded_batch(const Prepared& p) {
  std::unique_ptr<Simulator> sim = p.sim->clone();
  for (int s = 0; s < p.substeps; ++s) sim->step();
  Batch b;
  b.events = sim->step();
  b.after = sim->totals();
  return b;
}

/// The timed pass left other live counts than the recorded step: it applied another batch.
bool differs(const Totals& a, const Totals& b) {
  return a.vertices != b.vertices || a.edges != b.edges || a.auxiliary != b.auxiliary || a.triangles != b.triangles;
}

double time_pass(Simulator& sim, const char* pass) {
  const Clock::time_point t0 = Clock::now();
  sim.run_pass(pass);
  return seconds_between(t0, Clock::now());
}

void BM_Events(benchmark::State& state, const std::string& backend, int threads, int n) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  Prepared* prep = prepared_or_skip(state, backend, threads, n);
  if (!prep) return;
  const Prepared& p = *prep;
  const Batch recorded = recorded_batch(p);
  const StepEvents batch = recorded.events;
  const double events = batch.splits + batch.restores;
  if (events == 0) {
    state.SkipWithError("the recorded step has no events");
    return;
  }
  double applied = 0;
  long mismatch = 0;
  for (auto _ : state) {
    std::unique_ptr<Simulator> with = before_events(p);  // untimed
    std::unique_ptr<Simulator> test_only = with->clone();
    const double seconds = time_pass(*with, "topology_apply") - time_pass(*test_only, "adapt_test");
    state.SetIterationTime(std::max(0.0, seconds) / events);
    applied += seconds;
    mismatch += differs(with->totals(), recorded.after);  // untimed
  }
  state.counters["mismatch"] = double(mismatch);
  state.counters["splits"] = batch.splits;
  state.counters["restores"] = batch.restores;
  state.counters["us_per_event"] = state.iterations() ? 1e6 * applied / (events * double(state.iterations())) : 0.0;
  // The modelled bytes of one event's lines (bench/bytes_moved.cpp), where the backend's layout
  // is modelled: the report sets them against the machine's random-line rate (BM_Stream/gather).
  if (const std::optional<LayoutSizes> sizes = layout_sizes(*p.sim))
    state.counters["event_bytes"] = pass_bytes("topology_apply", *sizes, 1, 1) - pass_bytes("topology_apply", *sizes, 1, 0);
}

void register_event_benchmarks() {
  for_each_config([](const std::string& backend, int threads) {
    for (int n : kPricedSizes)
      // A fixed iteration count: each iteration's untimed set-up (clone, warm-up frame,
      // physics passes) costs many times the timed events (cf. bench_pass.cpp).
      benchmark::RegisterBenchmark(bench_name("Events", backend, threads, n).c_str(), BM_Events, backend, threads, n)
          ->Unit(benchmark::kMicrosecond)
          ->UseManualTime()
          ->Iterations(8);
  });
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_event_benchmarks);

}  // namespace crumple::bench
