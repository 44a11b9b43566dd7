#include "model/params.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace crumple {

namespace {
// Returns a message when v is not finite or outside [lo, hi].
std::string check(const char* name, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream s;
    s << "--" << name << " must be a finite number in [" << lo << ", " << hi << "], got " << v;
    return s.str();
  }
  return {};
}
}  // namespace

std::string Params::validate() const {
  struct Range { const char* name; double value, lo, hi; };
  const Range ranges[] = {
      {"squeeze", squeeze, 0.05, 1.0},       {"sphere-start", sphere_start, 0.01, 100.0},
      {"sphere-end", sphere_end, 0.01, 100.0}, {"sphere-time", sphere_time, 0.0, 1e6},
      {"gravity", gravity, -1e4, 1e4},       {"perturb", perturb, 0.0, 1.0},       {"mass", total_mass, 1e-9, 1e9},
      {"frame-dt", frame_dt, 1e-6, 1.0},     {"substeps", double(substeps), 1, 10000},
      {"max-step", max_step, 0.0, 1.0},      {"adapt-every", adapt_every, 0.0, 1.0},
      {"sweeps", double(sweeps), 1, 1000},   {"cg-tolerance", cg_tolerance, 1e-15, 0.5},
      {"cg-max-iterations", double(cg_max_iterations), 1, 1e6},
      {"kappa", kappa, 0.0, 1e12},           {"bend", bend, 0.0, 1e12},
      {"damping", damping, 0.0, 1e9},        {"viscosity", viscosity, 0.0, 1e9},
      {"phi", phi, 0.0, 1.0},
      {"psi", psi, 0.0, 1.0},                {"epsilon", epsilon, 0.0, 1.0},
      {"varphi", varphi, 1.0, 100.0},        {"floor", floor, 0.0, 1.0},
      {"max-vertices", double(max_vertices), 0, 2e9},
  };
  for (const Range& r : ranges) {
    std::string m = check(r.name, r.value, r.lo, r.hi);
    if (!m.empty()) return m;
  }
  return {};
}

double Params::budget_factor(int live_vertices) const {
  if (max_vertices <= 0) return 1.0;
  const double start = kBudgetSoftStart * max_vertices;
  if (live_vertices <= start) return 1.0;  // exactly 1: far from the budget nothing changes
  return std::max(0.0, (max_vertices - live_vertices) / (max_vertices - start));
}

Params paper_params() { return Params{}; }

Params default_params() {
  Params p;
  p.integrator = Integrator::Explicit;
  p.viscosity = kDefaultViscosity;
  p.auto_substeps = true;
  p.max_step = kDefaultMaxStep;
  p.adapt_per_frame = true;
  p.adapt_every = kDefaultAdaptEvery;
  return p;
}

const char* to_string(Scene s) { return s == Scene::Sphere ? "sphere" : s == Scene::Free ? "free" : "hang"; }
const char* to_string(Integrator i) {
  return i == Integrator::Approx     ? "approx"
         : i == Integrator::Explicit ? "explicit"
         : i == Integrator::Implicit ? "implicit"
                                     : "xpbd";
}
const char* to_string(RestoreForm r) { return r == RestoreForm::Exact ? "exact" : "paper"; }
const char* to_string(Predictor p) { return p == Predictor::Bounded ? "bounded" : "explicit"; }
const char* to_string(Jacobian j) { return j == Jacobian::Isotropic ? "isotropic" : "axial"; }
const char* to_string(BendingForm b) { return b == BendingForm::Balanced ? "balanced" : "paper"; }

}  // namespace crumple
