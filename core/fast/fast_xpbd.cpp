// XPBD with small steps on the fast backend (MODEL.md §3, docs/DECISIONS.md D19): the reference's
// step (ref_xpbd.cpp) with its Gauss-Seidel pass in colour order (constraint_colors.h) instead
// of ascending id, so that the springs of one colour run in parallel.
#include "fast/fast_sim.h"

namespace crumple::fast {

// The viscosity alone (D17) as its own implicit velocity step, no force (operator splitting,
// D19): the isotropic rows with W_e = h c_e I (step_constants' implicit for XPBD), swept as
// the approximate implicit step sweeps them. With h = 0 in the sweep's constants the force term
// h f drops out of the rows and of the momentum drift, which is all that h multiplies there.
void FastSimulator::viscous_step(const StepConstants& c) {
  const int n = topo_.V.size();
  par_.run(n, kPassGrain, [&](int b, int e) { viscous_guess(topo_, c, step_.g.data(), b, e); });
  StepConstants rows_only = c;
  rows_only.h = 0;
  float corr[3];
  sweep_rows(rows_only, corr);
  const Float4* g = step_.g.data();
  par_.run(n, kPassGrain, [&](int b, int e) { take_velocity(g, corr, topo_.V, b, e); });
}

// One step of h: the viscosity, v += h f_ext / m with the displacement d = h v, one projection of
// every spring (colour by colour), then v = d / h and x += h v with the sphere (advance_state).
// f_ext is what the force passes summed with the springs off (step_constants): bending, gravity
// and the caller's grabs.
void FastSimulator::integrate_xpbd() {
  const StepConstants c = step_constants();
  const int n = topo_.V.size();
  step_.fit(topo_);
  if (params_.viscosity > 0) viscous_step(c);
  Float4* disp = step_.g.data();
  par_.run(n, kPassGrain, [&](int b, int e) { xpbd_predict(topo_.V, step_.forces, c, disp, b, e); });
  for (int k : scene_.pinned) disp[topo_.V.phys[k]].w = 0;  // pinned: infinite mass
  colors_.update(topo_);
  const XpbdConstants xc{float(params_.kappa), c.h2, length_unit()};
  for (int color = 0; color < colors_.colors(); ++color) {
    const std::int32_t* slots = colors_.slots(color);
    par_.run(colors_.count(color), kPassGrain,
             [&](int b, int e) { xpbd_project(topo_.E, topo_.V, xc, slots, disp, b, e); });
  }
  par_.run(n, kPassGrain, [&](int b, int e) { displacement_to_velocity(c.h, disp, b, e); });
  const float none[3] = {0, 0, 0};
  advance_state(c, none);
}

}  // namespace crumple::fast
