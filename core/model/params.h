// The model's parameters (MODEL.md §9) and the run's set-up, shared by every backend.
// Defaults give a plausible crumple of a 32 x 32 sheet in the sphere scene; README.md lists them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>

namespace crumple {

enum class Scene { Sphere, Free, Hang };            ///< MODEL.md §8; Hang: two corners pinned
enum class Integrator { Approx, Explicit, Implicit, Xpbd };  ///< MODEL.md §3
enum class RestoreForm { Exact, Paper };            ///< MODEL.md §7
enum class BendingForm { Balanced, Paper };         ///< MODEL.md §6
/// Where the approximate implicit method's Jacobi sweeps start (docs/DECISIONS.md, D1).
enum class Predictor { Bounded, Explicit };
/// The spring Jacobian of the approximate implicit method (MODEL.md §3): kappa_e I (the paper's)
/// or kappa_e u u^T (stiff along the spring only, so it damps stretching, not folding).
enum class Jacobian { Isotropic, Axial };

/// Fraction of Params::max_vertices where the budget's shaping starts (docs/DECISIONS.md D22).
inline constexpr double kBudgetSoftStart = 0.9;

struct Params {
  // --- scene (MODEL.md §8) ---
  Scene scene = Scene::Sphere;  ///< sphere crumple or free relax
  double squeeze = 0.7;         ///< free scene: initial positions scaled by this about the centroid
  double sphere_start = 1.0;    ///< R0 as a fraction of the farthest vertex's distance from the centroid
  double sphere_end = 0.3;      ///< R1, same unit as sphere_start
  double sphere_time = 2.0;     ///< seconds for the sphere to shrink from R0 to R1 (then it holds)
  double perturb = 0.03;        ///< initial dome along the rest normals, height as a fraction
                                ///< of the sheet's reach (a real sheet is never exactly flat)
  double gravity = 0.0;         ///< m/s^2 along -z
  double total_mass = 1.0;      ///< sheet mass, spread by vertex area

  // --- time integration (MODEL.md §3) ---
  double frame_dt = 1.0 / 60.0;          ///< one frame of simulated time
  int substeps = 1;                      ///< steps per frame: h = frame_dt / substeps
  bool auto_substeps = false;            ///< substeps chosen each frame from the stiffest mode
                                         ///< of the current mesh (sim/run.h choose_substeps)
  double max_step = 0;                   ///< auto_substeps: the step is at most this (seconds;
                                         ///< 0: no bound but stability), the accuracy knob
  bool adapt_per_frame = false;          ///< fracture and restoration once per frame, after its
                                         ///< last step, with P over the frame (MODEL.md §4;
                                         ///< docs/DECISIONS.md D27); else after every step
  double adapt_every = 0;                ///< adapt_per_frame: the pass once per this many seconds
                                         ///< of simulated time instead of once per frame (0),
                                         ///< so that it does not follow the frame rate (D28)
  Integrator integrator = Integrator::Approx;
  int sweeps = 1;                        ///< K, Jacobi sweeps of the approximate implicit method
  Predictor predictor = Predictor::Bounded;  ///< bounded (stable for any h) or the paper's explicit
  Jacobian jacobian = Jacobian::Isotropic;   ///< approx: the spring Jacobian of its implicit term
  double cg_tolerance = 1e-6;            ///< Baraff-Witkin: relative CG residual
  int cg_max_iterations = 1000;          ///< Baraff-Witkin: CG iteration cap

  // --- forces (MODEL.md §2, §6) ---
  double kappa = 1.0e4;     ///< stiffness per unit mass: kappa_e = kappa (m_i + m_j)   [Eq 5]
  double bend = 30.0;       ///< C_beta per unit mass: C_beta,e = bend (m_i + m_j)      [Eq 9]
  double damping = 0.0;     ///< k_d per unit mass, spring-axis damping (optional)
  double viscosity = 0.0;   ///< c per unit mass: c_e = c (m_i + m_j), force c_e (v_j - v_i) on i
                            ///< from each spring, applied implicitly (docs/DECISIONS.md D17)
  BendingForm bending = BendingForm::Balanced;

  // --- adaptive mesh (MODEL.md §4, §5, §7) ---
  bool fracture = true;         ///< stochastic fracture on/off
  bool restoration = true;      ///< restoration on/off
  double phi = 0.75;            ///< curvature sensitivity of fracture            [Eq 6]
  double psi = 0.5;             ///< new-vertex offset scale                       [Eq 7]
  double epsilon = 0.5;         ///< restoration threshold                         [Eq 10]
  double varphi = 2.0;          ///< mass-split exponent (>= 1)                    [Eq 3]
  double floor = 0.5;           ///< refinement floor: edges with rest length below floor x the
                                ///< initial mean edge length never break
  RestoreForm restore = RestoreForm::Exact;
  std::uint64_t seed = 1;       ///< seed of the counter-based random stream
  int max_vertices = 0;         ///< vertex budget: fracture fades and restoration eases from
                                ///< kBudgetSoftStart of it on; a step's splits, in event order,
                                ///< stop where they would pass it (0: unlimited; D22)

  /// Time step h.
  double h() const { return frame_dt / substeps; }
  /// The interval one fracture/restoration pass covers: P over it is 1 - (1 - P)^(t / h_ref).
  /// Never shorter than a step: the pass runs after steps.
  double adapt_interval() const {
    if (!adapt_per_frame) return h();
    return adapt_every > 0 ? std::max(adapt_every, h()) : frame_dt;
  }

  /// The vertex budget's shaping factor for a pass that starts with `live_vertices` (D22): 1
  /// without a budget or up to kBudgetSoftStart of it, then linear down to 0 at the budget.
  /// Every backend multiplies P_step of [Eq 6] and epsilon of [Eq 10] by it.
  double budget_factor(int live_vertices) const;

  /// Empty if every value is usable; otherwise one line naming the first bad parameter.
  std::string validate() const;
};

/// The paper's viscosity at its own frame rate, made a constant (docs/DECISIONS.md D17):
/// c = h_ref kappa with h_ref = 1/60 s and the default kappa.
inline constexpr double kDefaultViscosity = 1.0e4 / 60.0;
/// The default configuration's largest step in seconds (docs/DECISIONS.md D28).
inline constexpr double kDefaultMaxStep = 1.0 / (60.0 * 64);
/// The default configuration's interval between fracture/restoration passes in seconds (D28):
/// it divides the frame times from 1/30 to 1/240 s, and kDefaultMaxStep divides it.
inline constexpr double kDefaultAdaptEvery = 1.0 / 240;

/// The paper's configuration (MODEL.md §3): the approximate implicit step (its isotropic
/// Jacobian, one sweep), one step per 1/60 s frame, fracture and restoration after every step,
/// no viscosity. Params{} is this; `crumple run --paper` starts from it.
Params paper_params();
/// The command's default (docs/DECISIONS.md D28): the same model with the viscosity of D17 in
/// physical units, integrated by symplectic Euler at substeps chosen each frame (stable for the
/// current mesh, and no step above kDefaultMaxStep), fracture and restoration once per frame. It
/// converges with the step where the paper's configuration changes with the frame rate.
Params default_params();

const char* to_string(Scene);
const char* to_string(Integrator);
const char* to_string(RestoreForm);
const char* to_string(BendingForm);
const char* to_string(Predictor);
const char* to_string(Jacobian);

}  // namespace crumple
