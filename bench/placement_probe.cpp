// crumple_placement_probe: what two threads gain over one as the machine places its first two
// CPUs near each other or far apart. On a VM the host may move the vCPUs between chips from one
// minute to the next (docs/PERFORMANCE.md), and every two-thread timing then mixes two
// machines. From the benchmarks' prepared state (bench_frame.cpp: the paper's configuration at
// 0.6 x sphere_time) on 1 and on 2 threads, each round measures the CPUs' round trip
// (core_to_core.h), then times FRAMES frames of a fresh clone on 1 and on 2 threads (the order
// alternating from round to round), then sleeps GAP seconds, so that ROUNDS rounds span the
// placements of some minutes. Prints a line a round, then per placement (round trip below or
// above NEAR_NS) the medians and the speed-up's quartiles.
// Usage: crumple_placement_probe N FRAMES ROUNDS GAP [NEAR_NS=250]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "core_to_core.h"
#include "fast/fast_sim.h"
#include "mesh/input_mesh.h"
#include "model/params.h"
#include "probe_common.h"
#include "sim/run.h"

namespace {

constexpr long kRoundTrips = 20000;  ///< per round: some milliseconds

struct Round {
  double trip_ns = 0;
  double ms[2] = {};  ///< a frame on 1 and on 2 threads
};

/// Milliseconds a frame over `frames` frames of a clone of `prepared`, after one untimed frame.
double frame_ms(const crumple::fast::FastSimulator& prepared, const crumple::Params& params, int first, int frames) {
  std::unique_ptr<crumple::Simulator> sim = prepared.clone();
  crumple::run_frame(*sim, params, first);
  const auto t0 = std::chrono::steady_clock::now();
  for (int f = 1; f <= frames; ++f) crumple::run_frame(*sim, params, first + f);
  return 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / frames;
}

/// The q-quantile of v (0 <= q <= 1), interpolated between order statistics.
double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * double(v.size() - 1);
  const std::size_t lo = std::size_t(at);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - double(lo)) * (v[hi] - v[lo]);
}

void print_placement(const char* name, const std::vector<Round>& rounds) {
  if (rounds.empty()) {
    std::printf("%-5s rounds 0\n", name);
    return;
  }
  std::vector<double> trip, one, two, gain;
  for (const Round& r : rounds) {
    trip.push_back(r.trip_ns), one.push_back(r.ms[0]), two.push_back(r.ms[1]);
    gain.push_back(r.ms[0] / r.ms[1]);
  }
  std::printf("%-5s rounds %zu: round trip %.0f ns (%.0f-%.0f), 1 thread %.3f ms, 2 threads %.3f ms, "
              "2t/1t %.2f (quartiles %.2f-%.2f)\n",
              name, rounds.size(), quantile(trip, 0.5), quantile(trip, 0), quantile(trip, 1), quantile(one, 0.5),
              quantile(two, 0.5), quantile(gain, 0.5), quantile(gain, 0.25), quantile(gain, 0.75));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || argc > 6) {
    std::fprintf(stderr, "usage: crumple_placement_probe N FRAMES ROUNDS GAP [NEAR_NS]\n");
    return 2;
  }
  auto number = [](const char* text, const char* what, bool integer) {
    return crumple::bench::parse_number("crumple_placement_probe", text, what, integer);
  };
  const int n = int(number(argv[1], "N", true)), frames = int(number(argv[2], "FRAMES", true));
  const int count = int(number(argv[3], "ROUNDS", true));
  const double gap = number(argv[4], "GAP", false), near_ns = argc > 5 ? number(argv[5], "NEAR_NS", false)
                                                                        : crumple::bench::kNearRoundTripNs;
  if (n < 4 || frames < 1 || count < 1 || gap < 0 || near_ns <= 0) {
    std::fprintf(stderr, "crumple_placement_probe: N must be >= 4, FRAMES and ROUNDS >= 1, GAP >= 0, NEAR_NS > 0\n");
    return 2;
  }
  const std::vector<int> cpus = crumple::bench::allowed_cpus();
  if (cpus.size() < 2) {
    std::fprintf(stderr, "crumple_placement_probe: needs two CPUs, the process may use %zu\n", cpus.size());
    return 2;
  }

  const crumple::Params params = crumple::paper_params();
  crumple::fast::FastSimulator one(crumple::make_grid(n), params, 1), two(crumple::make_grid(n), params, 2);
  const int prep = crumple::bench::prepared_frames(params);
  for (int f = 1; f <= prep; ++f) crumple::run_frame(one, params, f), crumple::run_frame(two, params, f);
  std::printf("N = %d, %d vertices at frame %d; CPUs %d and %d; %d timed frames a run\n", n, one.totals().vertices,
              prep, cpus[0], cpus[1], frames);

  std::vector<Round> near, far;
  for (int r = 0; r < count; ++r) {
    const double seconds = crumple::bench::round_trip_seconds(cpus[0], cpus[1], kRoundTrips);
    if (seconds < 0) {
      std::fprintf(stderr, "crumple_placement_probe: could not pin two threads to CPUs %d and %d\n", cpus[0], cpus[1]);
      return 1;
    }
    Round round;
    round.trip_ns = 1e9 * seconds / double(kRoundTrips);
    for (int k = 0; k < 2; ++k) {
      const int threads = (k + r) % 2;  // 0: one thread, 1: two
      round.ms[threads] = frame_ms(threads ? two : one, params, prep + 1, frames);
    }
    std::printf("round %d: round trip %.0f ns, 1 thread %.3f ms, 2 threads %.3f ms\n", r + 1, round.trip_ns,
                round.ms[0], round.ms[1]);
    std::fflush(stdout);
    (round.trip_ns < near_ns ? near : far).push_back(round);
    if (gap > 0 && r + 1 < count) usleep(useconds_t(gap * 1e6));
  }
  std::printf("\nby placement (near: round trip below %.0f ns)\n", near_ns);
  print_placement("near", near);
  print_placement("far", far);
}
