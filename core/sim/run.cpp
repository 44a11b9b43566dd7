#include "sim/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace crumple {

FrameStats run_frame(Simulator& sim, int substeps, int frame) {
  FrameStats s;
  s.frame = frame;
  s.substeps = substeps;
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

double max_stable_step(const Params& p, double mu) {
  if (p.integrator != Integrator::Explicit || !(mu > 0) || !(p.kappa > 0)) return INFINITY;
  const double km = p.kappa * mu, cm = p.viscosity * mu;
  return kStableStepSafety * (cm + std::sqrt(cm * cm + 4 * km)) / km;  // root of h^2 km = 4 + 2 h cm
}

int choose_substeps(const Params& p, double mu) {
  double h = max_stable_step(p, mu);
  if (p.max_step > 0) h = std::min(h, p.max_step);
  // The relative tolerance keeps frame_dt / max_step = 4 (say 1/60 and 1/240) at 4 steps
  // despite the rounding of the two decimal inputs.
  return int(std::clamp(std::ceil(p.frame_dt / h * (1 - 1e-12)), 1.0, 10000.0));
}

FrameStats run_frame(Simulator& sim, const Params& p, int frame) {
  int substeps = p.substeps;
  if (p.auto_substeps) {
    substeps = choose_substeps(p, sim.stiffness_bound());
    sim.set_substeps(substeps);
  }
  return run_frame(sim, substeps, frame);
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
