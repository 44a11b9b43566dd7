// crumple_relayout_probe: what each phase of a relayout (layout.h: vertices, lists, triangles,
// the edges' order, edges)
// costs on a state that has grown since its last one. From the benchmarks' prepared state
// (bench_frame.cpp: the paper's configuration at 0.6 x sphere_time) it runs GROWTH more frames
// with relayouts off, so that the vertices created since the last relayout are many (the
// prepared state holds about a fifth); then each round relays out a copy of that topology,
// timing the five phases one after the other, with the relayout's scratch faulted in first
// (LayoutScratch::warm, as the steps between relayouts do): the phases' own work, without the
// first touches that the simulator moves out of them. The summary gives each phase's median
// over the rounds.
// Usage: crumple_relayout_probe N THREADS ROUNDS GROWTH
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "fast/fast_sim.h"
#include "fast/layout.h"
#include "mesh/input_mesh.h"
#include "model/params.h"
#include "probe_common.h"
#include "sim/run.h"

namespace {

using crumple::fast::kLayoutPhases;

/// Each phase's time of one relayout of a copy of m, ms.
std::vector<double> time_phases(const crumple::fast::Topology& m, const crumple::fast::Parallel& par) {
  crumple::fast::Topology copy = m;
  crumple::fast::LayoutScratch scratch;
  scratch.warm(copy, par, SIZE_MAX);
  std::vector<double> ms;
  for (int phase = 0; phase < kLayoutPhases; ++phase) {
    const auto start = std::chrono::steady_clock::now();
    crumple::fast::relayout_phase(phase, copy, par, scratch);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: crumple_relayout_probe N THREADS ROUNDS GROWTH\n");
    return 2;
  }
  auto number = [](const char* text, const char* what) {
    return int(crumple::bench::parse_number("crumple_relayout_probe", text, what, true));
  };
  const int n = number(argv[1], "N"), threads = number(argv[2], "THREADS");
  const int rounds = number(argv[3], "ROUNDS"), growth = number(argv[4], "GROWTH");
  if (n < 4 || threads < 1 || rounds < 1 || growth < 0) {
    std::fprintf(stderr, "crumple_relayout_probe: N must be >= 4, THREADS and ROUNDS >= 1, GROWTH >= 0\n");
    return 2;
  }
  const crumple::Params params = crumple::paper_params();
  crumple::fast::FastSimulator sim(crumple::make_grid(n), params, threads);
  const int prep_frames = crumple::bench::prepared_frames(params);
  for (int f = 1; f <= prep_frames; ++f) crumple::run_frame(sim, params, f);
  sim.set_layout_fraction(-1);
  for (int f = 1; f <= growth; ++f) crumple::run_frame(sim, params, prep_frames + f);
  const crumple::fast::Topology& m = sim.topology();
  std::printf("N = %d, %d thread(s), frame %d: %d vertex, %d edge, %d triangle slots, %lld vertices created since the last relayout\n",
              n, threads, prep_frames + growth, m.V.size(), m.E.size(), m.T.size(), static_cast<long long>(m.V.created));
  std::printf("round   vertices      lists  triangles edge_order      edges   (ms)\n");
  const crumple::fast::Parallel par(threads);
  std::vector<std::vector<double>> by_phase(kLayoutPhases);
  for (int r = 0; r < rounds; ++r) {
    const std::vector<double> ms = time_phases(m, par);
    std::printf("%5d", r);
    for (int phase = 0; phase < kLayoutPhases; ++phase) std::printf(" %10.2f", ms[phase]), by_phase[phase].push_back(ms[phase]);
    std::printf("\n");
  }
  std::printf("median");
  for (const std::vector<double>& v : by_phase) std::printf(" %10.2f", crumple::bench::median(v));
  std::printf("\n");
}
