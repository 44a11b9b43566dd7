// crumple_resident_probe: what `--resident` (Simulator::make_resident, SheetDesc::resident)
// costs and saves in a continuous run of the paper's crumple, as an engine runs it: one fast
// simulator from the flat sheet, no clone (the benchmarks' clones recycle memory another clone
// just freed, which a growing sheet in a running game does not). Each round runs two
// simulations, plain and resident (which goes first alternates), each in a child process of
// its own (fork), so that neither inherits the memory the other freed; each runs frames 1 to
// FROM - 1 untimed and times frames FROM to TO one by one. Per run: the load (construction, and
// make_resident), the timed frames (mean, median, 90th percentile, longest), the page faults a
// frame, the child's peak resident set, and each pass's time a frame (the passes' own timers;
// the layout pass holds the relayout phases and FastSimulator::warm_ahead's first touches). The
// summary gives each figure's medians over the rounds and the median of the rounds' ratios
// resident / plain. The two runs of a round must end in the same state (make_resident touches
// memory, never the model): the probe exits 1 if they do not.
// Usage: crumple_resident_probe N THREADS FROM TO ROUNDS
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "fast/fast_sim.h"
#include "mesh/input_mesh.h"
#include "model/params.h"
#include "probe_common.h"
#include "sim/run.h"

namespace {

using crumple::fast::FastSimulator;
using crumple::fast::Pass;
using Clock = std::chrono::steady_clock;

struct RunResult {
  double load_ms = 0;
  double mean_ms = 0, median_ms = 0, p90_ms = 0, longest_ms = 0;  ///< over the timed frames
  double faults = 0;                       ///< minor page faults a timed frame (mean)
  double peak_mib = 0;                     ///< the run's peak resident set
  double pass_ms[int(Pass::kCount)] = {};  ///< each pass a timed frame (mean)
  crumple::Totals end;                     ///< the state after the last frame (both modes must agree)
};
static_assert(std::is_trivially_copyable_v<RunResult>, "sent through a pipe");

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

/// The `share` percentile of v by nearest rank: the ceil(share n)-th smallest value.
double percentile(std::vector<double> v, double share) {
  std::sort(v.begin(), v.end());
  const std::size_t rank = std::max<std::size_t>(1, std::size_t(std::ceil(share * double(v.size()))));
  return v[std::min(v.size(), rank) - 1];
}

RunResult run(int n, int threads, int from, int to, bool resident) {
  const crumple::Params params = crumple::paper_params();
  RunResult r;
  const Clock::time_point t0 = Clock::now();
  FastSimulator sim(crumple::make_grid(n), params, threads);
  if (resident) sim.make_resident();
  r.load_ms = ms_since(t0);
  for (int f = 1; f < from; ++f) crumple::run_frame(sim, params, f);
  std::vector<double> frames;
  const double faults_before = double(crumple::bench::self_usage().ru_minflt);
  const auto passes_before = sim.pass_seconds();
  for (int f = from; f <= to; ++f) {
    const Clock::time_point start = Clock::now();
    crumple::run_frame(sim, params, f);
    frames.push_back(ms_since(start));
  }
  const double count = double(frames.size());
  for (double ms : frames) r.mean_ms += ms / count;
  r.median_ms = crumple::bench::median(frames);
  r.p90_ms = percentile(frames, 0.9);
  r.longest_ms = *std::max_element(frames.begin(), frames.end());
  const rusage u = crumple::bench::self_usage();
  r.faults = (double(u.ru_minflt) - faults_before) / count;
  r.peak_mib = double(u.ru_maxrss) / 1024.0;  // KiB on Linux
  for (int k = 0; k < int(Pass::kCount); ++k) r.pass_ms[k] = 1e3 * (sim.pass_seconds()[k] - passes_before[k]) / count;
  r.end = sim.totals();
  return r;
}

/// run() in a child process, its result sent back through a pipe; exits the probe if the child
/// fails. The parent starts no thread, so the child forks from a single-threaded process.
RunResult run_in_child(int n, int threads, int from, int to, bool resident) {
  std::fflush(stdout);  // a child must not inherit lines still buffered
  int fd[2];
  if (pipe(fd) != 0) std::perror("crumple_resident_probe: pipe"), std::exit(1);
  const pid_t pid = fork();
  if (pid < 0) std::perror("crumple_resident_probe: fork"), std::exit(1);
  if (pid == 0) {
    close(fd[0]);
    const RunResult r = run(n, threads, from, to, resident);
    const bool sent = write(fd[1], &r, sizeof r) == ssize_t(sizeof r);
    _exit(sent ? 0 : 1);
  }
  close(fd[1]);
  RunResult r;
  std::size_t got = 0;
  for (ssize_t k; got < sizeof r && (k = read(fd[0], reinterpret_cast<char*>(&r) + got, sizeof r - got)) > 0;)
    got += std::size_t(k);
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (got != sizeof r || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "crumple_resident_probe: the %s run failed\n", resident ? "resident" : "plain");
    std::exit(1);
  }
  return r;
}

bool same_state(const crumple::Totals& a, const crumple::Totals& b) {
  return a.vertices == b.vertices && a.triangles == b.triangles && a.edges == b.edges && a.kinetic == b.kinetic &&
         a.momentum[0] == b.momentum[0] && a.momentum[1] == b.momentum[1] && a.momentum[2] == b.momentum[2];
}

void print_run(int round, const char* mode, const RunResult& r) {
  std::printf("round %d, %-8s load %8.1f ms | frame mean %7.2f median %7.2f p90 %7.2f longest %7.2f ms | "
              "faults %7.1f a frame | peak %7.1f MiB |",
              round, mode, r.load_ms, r.mean_ms, r.median_ms, r.p90_ms, r.longest_ms, r.faults, r.peak_mib);
  for (int p = 0; p < int(Pass::kCount); ++p) std::printf(" %s %.2f", to_string(Pass(p)), r.pass_ms[p]);
  std::printf("\n");
  std::fflush(stdout);
}

/// One row of the summary: a figure's median over the rounds in each mode and the median of
/// the rounds' ratios resident / plain (over the rounds whose plain figure is not 0; "-" if none).
template <class Get>
void print_row(const char* what, const std::vector<RunResult>& plain, const std::vector<RunResult>& resident, Get get) {
  std::vector<double> a, b, ratio;
  for (std::size_t k = 0; k < plain.size(); ++k) {
    a.push_back(get(plain[k]));
    b.push_back(get(resident[k]));
    if (a.back() > 0) ratio.push_back(b.back() / a.back());
  }
  using crumple::bench::median;
  std::printf("%-18s %10.2f %10.2f", what, median(a), median(b));
  if (ratio.empty())
    std::printf(" %8s\n", "-");
  else
    std::printf(" %8.3f\n", median(ratio));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: crumple_resident_probe N THREADS FROM TO ROUNDS\n");
    return 2;
  }
  auto number = [](const char* text, const char* what) {
    return int(crumple::bench::parse_number("crumple_resident_probe", text, what, true));
  };
  const int n = number(argv[1], "N"), threads = number(argv[2], "THREADS");
  const int from = number(argv[3], "FROM"), to = number(argv[4], "TO"), rounds = number(argv[5], "ROUNDS");
  if (n < 4 || threads < 1 || from < 1 || to < from || rounds < 1) {
    std::fprintf(stderr, "crumple_resident_probe: N must be >= 4, THREADS and ROUNDS >= 1, 1 <= FROM <= TO\n");
    return 2;
  }
  std::printf("N = %d, %d thread(s), frames %d to %d of the paper's crumple timed, %d round(s)\n", n, threads, from,
              to, rounds);
  std::vector<RunResult> plain, resident;
  for (int round = 1; round <= rounds; ++round) {
    for (bool make_resident : {round % 2 == 0, round % 2 == 1}) {
      const RunResult r = run_in_child(n, threads, from, to, make_resident);
      (make_resident ? resident : plain).push_back(r);
      print_run(round, make_resident ? "resident" : "plain", r);
    }
    if (!same_state(plain.back().end, resident.back().end)) {
      std::fprintf(stderr, "crumple_resident_probe: round %d: the resident run ended in another state\n", round);
      return 1;
    }
  }
  std::printf("\nmedians over %d round(s) (ms; faults a frame; peak MiB; passes ms a frame)\n", rounds);
  std::printf("%-18s %10s %10s %8s\n", "", "plain", "resident", "ratio");
  print_row("load", plain, resident, [](const RunResult& r) { return r.load_ms; });
  print_row("frame mean", plain, resident, [](const RunResult& r) { return r.mean_ms; });
  print_row("frame median", plain, resident, [](const RunResult& r) { return r.median_ms; });
  print_row("frame p90", plain, resident, [](const RunResult& r) { return r.p90_ms; });
  print_row("frame longest", plain, resident, [](const RunResult& r) { return r.longest_ms; });
  print_row("faults", plain, resident, [](const RunResult& r) { return r.faults; });
  print_row("peak", plain, resident, [](const RunResult& r) { return r.peak_mib; });
  for (int p = 0; p < int(Pass::kCount); ++p)
    print_row(to_string(Pass(p)), plain, resident, [p](const RunResult& r) { return r.pass_ms[p]; });
  return 0;
}
