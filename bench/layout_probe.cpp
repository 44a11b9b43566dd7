// crumple_layout_probe: what the fast backend's layout fraction (FastSimulator::
// set_layout_fraction, layout.h) costs and saves in the paper's crumple. From the benchmarks'
// prepared state (bench_frame.cpp: the paper's configuration at 0.6 x sphere_time), each run
// clones it, sets one fraction, runs one untimed warm-up frame and times FRAMES frames; the runs
// of one round take the fractions in a rotated order, so that every fraction meets the machine's
// load at every position. Per run: the mean frame, each pass's share of it (the passes'
// own timers; the layout pass's includes the steps between relayouts that fault in the next
// one's memory and the arrays' growth room, FastSimulator::warm_ahead), the frames that ran a
// relayout phase (a relayout's five phases run in consecutive steps, layout.h: five frames of
// the paper's one step a frame) and the longest phase of a run, the longest frame of a run (the
// hitch an engine sees), and the page faults (first touches of memory, which cost some
// microseconds each on a VM: docs/PERFORMANCE.md) a frame and in the frames that relayout, and
// `warm`: the layout pass's time in the frames that ran no relayout phase (the first touches
// of the next relayout's memory and of the growth room), ms a frame over all the timed frames.
// The summary gives per fraction the medians over the rounds.
// Usage: crumple_layout_probe N THREADS FRAMES ROUNDS FRACTION [FRACTION ...]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "fast/fast_sim.h"
#include "mesh/input_mesh.h"
#include "model/params.h"
#include "probe_common.h"
#include "sim/run.h"

namespace {

using crumple::fast::FastSimulator;
using crumple::fast::Pass;

struct RunResult {
  double frame_ms = 0;                          ///< mean over the timed frames
  double pass_ms[int(Pass::kCount)] = {};       ///< each pass's mean per frame
  int layout_frames = 0;         ///< frames that ran a relayout phase
  double longest_layout_ms = 0;  ///< the longest relayout phase
  double longest_frame_ms = 0;
  double faults = 0;           ///< minor page faults a frame (mean)
  double relayout_faults = 0;  ///< minor page faults a frame that relayouts (mean; 0 if none)
  double warm_ms = 0;          ///< the layout pass in frames without a relayout phase (warm's), ms a frame
};

/// The process's minor page faults so far.
double minor_faults() { return double(crumple::bench::self_usage().ru_minflt); }

RunResult run(const FastSimulator& prepared, const crumple::Params& params, int first_frame, int frames, double fraction) {
  std::unique_ptr<crumple::Simulator> clone = prepared.clone();
  auto& sim = static_cast<FastSimulator&>(*clone);
  sim.set_layout_fraction(fraction);
  crumple::run_frame(sim, params, first_frame);  // warm-up, untimed
  RunResult r;
  const auto before = sim.pass_seconds();
  double seconds = 0;
  for (int f = 1; f <= frames; ++f) {
    const double layout_before = sim.pass_seconds()[int(Pass::Layout)];
    const std::uint64_t phases_before = sim.relayout_phases();
    const double faults_before = minor_faults();
    const auto t0 = std::chrono::steady_clock::now();
    crumple::run_frame(sim, params, first_frame + f);
    const double frame = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    seconds += frame;
    r.longest_frame_ms = std::max(r.longest_frame_ms, 1e3 * frame);
    const double faults = minor_faults() - faults_before;
    r.faults += faults;
    const double layout = sim.pass_seconds()[int(Pass::Layout)] - layout_before;
    if (sim.relayout_phases() > phases_before) {  // other frames' layout time is warm_ahead's
      ++r.layout_frames, r.relayout_faults += faults;
      r.longest_layout_ms = std::max(r.longest_layout_ms, 1e3 * layout);
    } else {
      r.warm_ms += 1e3 * layout;
    }
  }
  r.frame_ms = 1e3 * seconds / frames;
  r.faults /= frames;
  r.warm_ms /= frames;
  if (r.layout_frames > 0) r.relayout_faults /= r.layout_frames;
  for (int k = 0; k < int(Pass::kCount); ++k) r.pass_ms[k] = 1e3 * (sim.pass_seconds()[k] - before[k]) / frames;
  return r;
}

/// Per fraction, the medians over the rounds of each run's figures.
void print_medians(const std::map<double, std::vector<RunResult>>& results, int rounds) {
  std::printf("\nmedians over %d rounds (ms a frame; longest: a run's longest frame; layout_frames: frames that ran "
              "a relayout phase; phase: a run's longest one; faults: page faults a frame)\n",
              rounds);
  std::printf("%-9s %8s %8s %13s %8s", "fraction", "frame", "longest", "layout_frames", "phase");
  for (int p = 0; p < int(Pass::kCount); ++p) std::printf(" %14s", to_string(Pass(p)));
  std::printf(" %8s %15s %8s\n", "faults", "relayout_faults", "warm");
  for (const auto& [fraction, runs] : results) {
    auto med = [&](auto get) {
      std::vector<double> v;
      for (const RunResult& r : runs) v.push_back(get(r));
      return crumple::bench::median(v);
    };
    std::printf("%-9g %8.2f %8.2f %13.1f %8.1f", fraction, med([](const RunResult& r) { return r.frame_ms; }),
                med([](const RunResult& r) { return r.longest_frame_ms; }),
                med([](const RunResult& r) { return double(r.layout_frames); }),
                med([](const RunResult& r) { return r.longest_layout_ms; }));
    for (int p = 0; p < int(Pass::kCount); ++p) std::printf(" %14.2f", med([&](const RunResult& r) { return r.pass_ms[p]; }));
    std::printf(" %8.0f %15.0f %8.2f\n", med([](const RunResult& r) { return r.faults; }),
                med([](const RunResult& r) { return r.relayout_faults; }), med([](const RunResult& r) { return r.warm_ms; }));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: crumple_layout_probe N THREADS FRAMES ROUNDS FRACTION [FRACTION ...]\n");
    return 2;
  }
  auto number = [](const char* text, const char* what, bool integer) {
    return crumple::bench::parse_number("crumple_layout_probe", text, what, integer);
  };
  const int n = int(number(argv[1], "N", true)), threads = int(number(argv[2], "THREADS", true));
  const int frames = int(number(argv[3], "FRAMES", true)), rounds = int(number(argv[4], "ROUNDS", true));
  if (n < 4 || threads < 1 || frames < 1 || rounds < 1) {
    std::fprintf(stderr, "crumple_layout_probe: N must be >= 4 and THREADS, FRAMES, ROUNDS >= 1\n");
    return 2;
  }
  std::vector<double> fractions;
  for (int a = 5; a < argc; ++a) fractions.push_back(number(argv[a], "FRACTION", false));

  const crumple::Params params = crumple::paper_params();
  FastSimulator prepared(crumple::make_grid(n), params, threads);
  const int prep_frames = crumple::bench::prepared_frames(params);
  for (int f = 1; f <= prep_frames; ++f) crumple::run_frame(prepared, params, f);
  std::printf("N = %d, %d thread(s), %d vertices at frame %d; %d timed frames a run\n", n, threads,
              prepared.totals().vertices, prep_frames, frames);

  std::map<double, std::vector<RunResult>> results;
  const int nf = int(fractions.size());
  for (int round = 0; round < rounds; ++round) {
    for (int k = 0; k < nf; ++k) {
      const double fraction = fractions[(k + round) % nf];
      const RunResult r = run(prepared, params, prep_frames + 1, frames, fraction);
      results[fraction].push_back(r);
      std::printf("round %d, fraction %g: frame %.2f ms (longest %.2f), %d layout frames (longest phase %.1f ms) |",
                  round + 1, fraction, r.frame_ms, r.longest_frame_ms, r.layout_frames, r.longest_layout_ms);
      for (int p = 0; p < int(Pass::kCount); ++p) std::printf(" %s %.2f", to_string(Pass(p)), r.pass_ms[p]);
      std::printf(" | page faults %.0f a frame, %.0f a relayout frame\n", r.faults, r.relayout_faults);
      std::fflush(stdout);
    }
  }
  print_medians(results, rounds);
  return 0;
}
