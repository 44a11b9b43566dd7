#include "sim/run.h"

#include <chrono>
#include <cmath>
#include <cstdio>

namespace crumple {

const char* stats_header() {
  return "frame,time,vertices,edges,triangles,splits,restores,mass,px,py,pz,kinetic,max_strain,step_ms";
}

std::string stats_row(const FrameStats& s) {
  char buf[512];
  const Totals& t = s.totals;
  std::snprintf(buf, sizeof buf, "%d,%.6f,%d,%d,%d,%d,%d,%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.4f",
                s.frame, s.time, t.vertices, t.edges, t.triangles, s.splits, s.restores, t.mass,
                t.momentum[0], t.momentum[1], t.momentum[2], t.kinetic, t.max_strain, s.step_ms);
  return buf;
}

FrameStats run_frame(Simulator& sim, int substeps, int frame) {
  FrameStats s;
  s.frame = frame;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < substeps; ++k) {
    const StepEvents ev = sim.step();
    s.splits += ev.splits;
    s.restores += ev.restores;
  }
  s.step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  s.time = sim.time();
  s.totals = sim.totals();
  return s;
}

std::string instability(const Totals& t, double size) {
  const double values[] = {t.mass, t.momentum[0], t.momentum[1], t.momentum[2], t.kinetic,
                           t.max_strain, t.rms_strain, t.max_distance, t.max_speed};
  for (double v : values)
    if (!std::isfinite(v)) return "a position or velocity is not finite";
  if (t.max_distance > 100 * size) return "a vertex left the scene (over 100 sheet sizes away)";
  if (t.max_speed > 1e4 * size) return "a vertex moves faster than 1e4 sheet sizes per second";
  if (t.rms_strain > 1) return "the mesh edges are stretched to twice their rest length on average";
  return {};
}

}  // namespace crumple
