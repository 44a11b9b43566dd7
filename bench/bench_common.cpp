#include "bench_common.h"

#include <vector>

namespace crumple::bench {

int frames_per_iteration(int n) {
  // Several frames per batch where frames are short, so one iteration's time averages over the
  // frame-to-frame variation of the crumple (splits come in bursts) and over timer and
  // scheduling granularity; few enough that the timed frames stay close to the prepared point.
  if (n <= 64) return 8;
  if (n <= 128) return 4;
  if (n <= 256) return 2;
  return 1;
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
