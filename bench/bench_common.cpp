#include "bench_common.h"

#include <vector>

namespace crumple::bench {

int frames_per_iteration(int /*n*/) {
  // Eight frames per batch at every size: one iteration's time averages over the frame-to-frame
  // variation of the crumple (splits come in bursts) and includes the fast backend's relayout
  // (docs/DECISIONS.md D12; five phases in consecutive frames) about as often as a continuing run
  // does (once every 8-11 frames at the prepared point); few enough that the timed frames stay close to the prepared point
  // (8 of the 120 frames of the squeeze). Never adapted to the measured speed, so every backend,
  // thread count and revision times exactly the same frames.
  return 8;
}

void FrameTally::set_counters(benchmark::State& state, double vertices, double edges) const {
  const double f = frames > 0 ? double(frames) : 1.0;
  state.counters["vertices"] = vertices;
  state.counters["edges"] = edges;
  state.counters["splits"] = double(splits) / f;
  state.counters["restores"] = double(restores) / f;
  state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["ms_per_frame"] = frames > 0 ? 1e3 * seconds / f : 0.0;
}

namespace {
std::vector<Registrar>& registrars() {
  static std::vector<Registrar> list;
  return list;
}
}  // namespace

bool add_registrar(Registrar fn) {
  registrars().push_back(fn);
  return true;
}

void run_registrars() {
  for (Registrar fn : registrars()) fn();
}

}  // namespace crumple::bench
