// XPBD with small steps (MODEL.md §3; Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke, Mueller
// 2019) on the reference backend: one constraint iteration per step, the steps as small as the
// frame's substeps make them.
#include "reference/reference_sim.h"

namespace crumple::ref {

// One step of h:
//  1. the viscosity (D17), when on, as its own implicit velocity step: the rows of
//     solve_rows with W_e = h c_e I and no force (operator splitting: XPBD's constraints act
//     along springs only, the viscosity across them too);
//  2. v += h f_ext / m (bending, gravity, grabs), x* = x + h v;
//  3. one Gauss-Seidel pass over the springs in ascending edge id, each the distance constraint
//     C = |x_i - x_j| - l0 with compliance alpha = 1 / kappa_e ([Eq 5]), alpha~ = alpha / h^2,
//     lambda starting at 0 (one iteration): dlambda = -C / (w_i + w_j + alpha~),
//     x_i += w_i dlambda u, x_j -= w_j dlambda u (u = (x_i - x_j)/|x_i - x_j|, w = 1/m, 0 pinned);
//  4. v = (x - x_before) / h.
// Each constraint moves its two ends by opposite impulses, so momentum is conserved exactly.
void ReferenceSimulator::integrate_xpbd(double h) {
  const size_t n = mesh_.verts.size();
  // f_ext at the step's start: bending and gravity do not depend on velocities; the caller's
  // grabs (manipulators.h) do, and act with the velocities the step starts from.
  std::vector<V3> f = external_forces();
  add_grab_forces(f);
  if (params_.viscosity > 0) {
    const std::vector<V3> vdamped = solve_rows<double>(h, std::vector<V3>(n, V3::Zero()));
    for (size_t k = 0; k < n; ++k)
      if (mesh_.verts[k].alive) mesh_.verts[k].v = vdamped[k];
  }
  std::vector<double> w(n, 0.0);
  std::vector<V3> before(n, V3::Zero());
  for (size_t k = 0; k < n; ++k) {
    Vertex& V = mesh_.verts[k];
    if (!V.alive) continue;
    w[k] = 1.0 / V.m;
    V.v += h * f[k] / V.m;
    before[k] = V.x;
    V.x += h * V.v;
  }
  for (int k : scene_.pinned) w[k] = 0;  // pinned vertices: infinite mass
  for (const Edge& E : mesh_.edges) {
    if (!E.alive || E.kappa <= 0 || w[E.a] + w[E.b] == 0) continue;
    V3& xa = mesh_.verts[E.a].x;
    V3& xb = mesh_.verts[E.b].x;
    const V3 d = xa - xb;
    const double lt = d.norm();
    if (!(lt > 0)) continue;
    const V3 u = d / lt;
    const double tilde = 1.0 / (E.kappa * h * h);
    const double dlambda = -(lt - E.l0) / (w[E.a] + w[E.b] + tilde);
    xa += w[E.a] * dlambda * u;
    xb -= w[E.b] * dlambda * u;
  }
  for (size_t k = 0; k < n; ++k)
    if (mesh_.verts[k].alive) mesh_.verts[k].v = (mesh_.verts[k].x - before[k]) / h;
}

}  // namespace crumple::ref
