// What the benchmarks and the probes (crumple_layout_probe, crumple_placement_probe,
// crumple_relayout_probe) share without Google Benchmark: the prepared point where their timed
// frames start, the probes' argument parsing and their medians.
#pragma once

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "model/params.h"

namespace crumple::bench {

/// Where the timed frames start: this fraction of params.sphere_time (1.2 s with the paper's
/// parameters, frame 72), well into the crumple, where every N from 32 to 1024 splits and
/// restores edges every frame and stays stable past the timed frames (docs/PERFORMANCE.md,
/// "The benchmarks' prepared state").
inline constexpr double kPrepFraction = 0.6;

/// The frames run to reach the prepared point.
inline int prepared_frames(const Params& params) {
  return int(std::lround(kPrepFraction * params.sphere_time / params.frame_dt));
}

/// Parses a whole decimal integer or number, or exits (status 2) with a one-line error naming
/// the program and the argument.
inline double parse_number(const char* program, const char* text, const char* what, bool integer) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || (integer && v != std::floor(v))) {
    std::fprintf(stderr, "%s: %s must be %s, got '%s'\n", program, what, integer ? "an integer" : "a number", text);
    std::exit(2);
  }
  return v;
}

/// This process's resource usage so far (page faults, peak resident set).
inline rusage self_usage() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u;
}

/// The median of v (the mean of the middle two when their count is even).
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace crumple::bench
