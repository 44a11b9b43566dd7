// Running a simulation frame by frame: statistics per frame, the substep choice and the
// instability check, the same for every backend (used by the embedding API, the tests and the
// benchmarks' preparation).
#pragma once

#include <string>

#include "sim/scene.h"
#include "sim/simulator.h"

namespace crumple {

/// What one frame did and left (the command writes the same values to stats.csv).
struct FrameStats {
  int frame = 0;          ///< 1-based frame number
  double time = 0;        ///< simulated seconds at the end of the frame
  Totals totals;          ///< state at the end of the frame
  int splits = 0;         ///< splits during the frame
  int restores = 0;       ///< restores during the frame
  double step_ms = 0;     ///< wall time of the frame
  int substeps = 1;       ///< steps taken in the frame
};

/// Advances one frame (substeps steps) and returns its statistics.
FrameStats run_frame(Simulator& sim, int substeps, int frame);
/// Advances one frame of p.substeps steps, or with p.auto_substeps of choose_substeps(p,
/// sim.stiffness_bound()) steps (the backend is told the count first).
FrameStats run_frame(Simulator& sim, const Params& p, int frame);

/// The largest step at which a method stays stable on a mesh whose stiffest mode is bounded by
/// mu (Simulator::stiffness_bound), times kStableStepSafety. Symplectic Euler with the implicit
/// viscosity c (D17) is stable on a mode of stiffness kappa mu and damping c mu while
/// h^2 kappa mu <= 4 + 2 h c mu. The approximate implicit method and Baraff-Witkin are stable
/// at any step (infinity).
double max_stable_step(const Params& p, double mu);
/// Room below the bound for what it leaves out (bending, springs compressed below half length).
constexpr double kStableStepSafety = 0.95;
/// Steps per frame: ceil(frame_dt / h), h the smaller of max_stable_step and p.max_step (when
/// set), in [1, 10000]. With max_step = frame_dt / k for every frame rate in use, every frame
/// rate takes the same step h and the same crumple.
int choose_substeps(const Params& p, double mu);

/// Empty if the state is sane; otherwise why it is not: a non-finite value, or a vertex that has
/// gone past 100 sheet sizes from the centre or faster than 1e4 sheet sizes per second, or mesh
/// edges stretched to twice their rest length on average (energy growing without bound; inside
/// the sphere positions stay bounded, so strain is what shows it there). A few short springs
/// can be stretched far more in a legitimate crumple (frozen creases pull against each other),
/// so the test is on the RMS strain, not the maximum.
std::string instability(const Totals& t, double sheet_size);

}  // namespace crumple
