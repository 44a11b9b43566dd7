// One step of each integrator (MODEL.md §3) checked against its defining equation, with the
// forces and their Jacobian taken from the backend's force hook (the Jacobian by central
// finite differences, so the analytic one in the code is checked independently).
#include <Eigen/Dense>
#include <algorithm>
#include <set>

#include "support/fixtures.h"

namespace crumple::test {
namespace {

class Integrators : public EachBackend {
 protected:
  // A 4 x 4 grid stretched by 10 % (every spring longer than its rest length, so no term of
  // the Baraff-Witkin Jacobian is dropped) with a deterministic velocity field.
  void SetUp() override {
    if (GetParam() == "fast") skip_implicit = true;
    mesh = make_grid(4);
    for (const auto& x : mesh.positions) {
      x0.push_back({1.1 * x[0], 1.1 * x[1], 0.05 * std::sin(7 * x[0] + 3 * x[1])});
      v0.push_back({0.3 * x[1], -0.2 * x[0], 0.5 * x[0] * x[1]});
    }
  }
  Params params(Integrator integ) const {
    Params p = still_params();
    p.kappa = 300;
    p.gravity = 9.81;
    p.fracture = p.restoration = false;
    p.integrator = integ;
    p.cg_tolerance = 1e-13;
    return p;
  }
  InputMesh mesh;
  /// The fast backend has no Baraff-Witkin.
  bool supports(const Params& p) const { return GetParam() == "reference" || p.integrator != Integrator::Implicit; }
  /// One step from (x0, v0): the forces at the start, the state before and after.
  struct OneStep {
    std::vector<Vec3d> forces;
    Snapshot before, after;
  };
  OneStep one_step(const Params& p) const {
    auto sim = make(mesh, p);
    sim->set_state(x0, v0);
    OneStep r{sim->forces(), sim->snapshot(), {}};
    sim->step();
    r.after = sim->snapshot();
    return r;
  }
  std::vector<Vec3d> x0, v0;
  bool skip_implicit = false;  ///< Baraff-Witkin runs on the reference path only
};

TEST_P(Integrators, SymplecticEuler) {
  const Params p = params(Integrator::Explicit);
  auto sim = make(mesh, p);
  sim->set_state(x0, v0);
  const auto f = sim->forces();
  const auto m = sim->snapshot().mass;
  sim->step();
  const auto s = sim->snapshot();
  const double h = p.h();
  for (size_t k = 0; k < x0.size(); ++k) {
    const V3 v = v3(v0[k]) + h * v3(f[k]) / m[k];
    EXPECT_NEAR((v3(s.velocity[k]) - v).norm(), 0, tol() * 100);
    EXPECT_NEAR((v3(s.position[k]) - (v3(x0[k]) + h * v)).norm(), 0, tol() * 10);
  }
}

// K = 1 sweeps of the implicit velocity step (MODEL.md §3, D17), computed here by hand with a
// 3 x 3 block per spring, W_e = h^2 kappa_e J_e + h c_e I (J_e = I isotropic, u u^T axial, 0 for
// explicit Euler with viscosity):
//   v_i' = (m_i I + sum W_e)^-1 (m_i v_i + h f_i + sum W_e v*_j),
// with the guess v*_j = v_j + h f_j / m_j (the paper's explicit predictor) or the bounded predictor
// v_j + h g + (m_j I + 2 sum W)^-1 (h (f_j - m_j g) + sum W (v_k - v_j)), then the uniform
// correction that restores sum m v' = sum m v + h sum f (DECISIONS.md D2).
struct SweepCase {
  Integrator integrator;
  Jacobian jacobian;
  Predictor predictor;
  double viscosity;
};

std::vector<V3> one_sweep(const Params& p, const Snapshot& s0, const std::vector<Vec3d>& f) {
  using M3 = Eigen::Matrix3d;
  const double h = p.h();
  const size_t n = s0.mass.size();
  const V3 g(0, 0, -p.gravity);
  auto block = [&](const EdgeView& e) {
    const double msum = s0.mass[e.a] + s0.mass[e.b];
    const V3 u = (v3(s0.position[e.a]) - v3(s0.position[e.b])).normalized();
    const M3 J = p.integrator == Integrator::Explicit ? M3::Zero()
                 : p.jacobian == Jacobian::Axial      ? M3(u * u.transpose())
                                                      : M3::Identity();
    return M3(h * h * p.kappa * msum * J + h * p.viscosity * msum * M3::Identity());  // [Eq 5], D17
  };
  std::vector<M3> wsum(n, M3::Zero());
  std::vector<V3> jv(n, V3::Zero()), num(n);
  for (const EdgeView& e : s0.edges) {
    const M3 W = block(e);
    wsum[e.a] += W;
    wsum[e.b] += W;
    jv[e.a] += W * (v3(s0.velocity[e.b]) - v3(s0.velocity[e.a]));
    jv[e.b] += W * (v3(s0.velocity[e.a]) - v3(s0.velocity[e.b]));
  }
  auto guess = [&](int j) {
    const double m = s0.mass[j];
    if (p.predictor == Predictor::Explicit) return V3(v3(s0.velocity[j]) + h * v3(f[j]) / m);
    const M3 D = m * M3::Identity() + 2 * wsum[j];
    return V3(v3(s0.velocity[j]) + h * g + D.inverse() * (h * (v3(f[j]) - m * g) + jv[j]));
  };
  for (size_t k = 0; k < n; ++k) num[k] = s0.mass[k] * v3(s0.velocity[k]) + h * v3(f[k]);
  for (const EdgeView& e : s0.edges) {
    num[e.a] += block(e) * guess(e.b);
    num[e.b] += block(e) * guess(e.a);
  }
  std::vector<V3> vnew(n);
  V3 drift = V3::Zero();
  double mass = 0;
  for (size_t k = 0; k < n; ++k) {
    vnew[k] = (s0.mass[k] * M3::Identity() + wsum[k]).inverse() * num[k];
    drift += s0.mass[k] * (vnew[k] - v3(s0.velocity[k])) - h * v3(f[k]);
    mass += s0.mass[k];
  }
  for (V3& v : vnew) v -= drift / mass;
  return vnew;
}

TEST_P(Integrators, OneSweepOfTheImplicitVelocityStep) {
  const SweepCase cases[] = {
      {Integrator::Approx, Jacobian::Isotropic, Predictor::Explicit, 0},
      {Integrator::Approx, Jacobian::Isotropic, Predictor::Bounded, 0},
      {Integrator::Approx, Jacobian::Isotropic, Predictor::Bounded, 7},
      {Integrator::Approx, Jacobian::Axial, Predictor::Bounded, 0},
      {Integrator::Approx, Jacobian::Axial, Predictor::Bounded, 7},
      {Integrator::Explicit, Jacobian::Isotropic, Predictor::Bounded, 7},
  };
  for (const SweepCase& c : cases) {
    Params p = params(c.integrator);
    p.jacobian = c.jacobian;
    p.predictor = c.predictor;
    p.viscosity = c.viscosity;
    const std::string label = std::string(to_string(c.integrator)) + " " + to_string(c.jacobian) + " " +
                              to_string(c.predictor) + " c=" + std::to_string(c.viscosity);
    if (!supports(p)) continue;
    const auto [f, s0, s] = one_step(p);
    const std::vector<V3> v = one_sweep(p, s0, f);
    for (size_t k = 0; k < x0.size(); ++k) {
      EXPECT_NEAR((v3(s.velocity[k]) - v[k]).norm(), 0, tol() * 100) << k << " " << label;
      EXPECT_NEAR((v3(s.position[k]) - (v3(x0[k]) + p.h() * v[k])).norm(), 0, tol() * 10) << k << " " << label;
    }
  }
}

// Baraff-Witkin: (M - h^2 J - h D) dv = h (f + f_visc + h J v) with J = df/dx from finite
// differences of the force hook, and the viscosity (D17, not in the hook) by hand: f_visc,i =
// sum_e c_e (v_j - v_i), D its (constant) velocity Jacobian.
TEST_P(Integrators, BaraffWitkinSolvesTheLinearSystem) {
  if (skip_implicit) GTEST_SKIP() << "the fast backend has no Baraff-Witkin integrator";
  for (double viscosity : {0.0, 4.0}) {
    Params p = params(Integrator::Implicit);
    p.viscosity = viscosity;
    auto sim = make(mesh, p);
    const size_t n = x0.size();
    const double h = p.h(), delta = 1e-6;
    Eigen::MatrixXd J(3 * n, 3 * n), D = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (size_t k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d) {
        auto xp = x0, xm = x0;
        xp[k][d] += delta;
        xm[k][d] -= delta;
        sim->set_state(xp, v0);
        const auto fp = sim->forces();
        sim->set_state(xm, v0);
        const auto fm = sim->forces();
        for (size_t r = 0; r < n; ++r)
          for (int c = 0; c < 3; ++c) J(3 * r + c, 3 * k + d) = (fp[r][c] - fm[r][c]) / (2 * delta);
      }
    sim->set_state(x0, v0);
    const auto f = sim->forces();
    const Snapshot s0 = sim->snapshot();
    Eigen::VectorXd F(3 * n), V(3 * n), M(3 * n);
    for (size_t k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d) {
        F(3 * k + d) = f[k][d];
        V(3 * k + d) = v0[k][d];
        M(3 * k + d) = s0.mass[k];
      }
    for (const EdgeView& e : s0.edges) {
      const double ce = viscosity * (s0.mass[e.a] + s0.mass[e.b]);
      for (int d = 0; d < 3; ++d) {
        const int a = 3 * e.a + d, b = 3 * e.b + d;
        F(a) += ce * (v0[e.b][d] - v0[e.a][d]);
        F(b) += ce * (v0[e.a][d] - v0[e.b][d]);
        D(a, a) -= ce, D(b, b) -= ce, D(a, b) += ce, D(b, a) += ce;
      }
    }
    sim->step();
    const auto s = sim->snapshot();
    Eigen::VectorXd dv(3 * n);
    for (size_t k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d) dv(3 * k + d) = s.velocity[k][d] - v0[k][d];
    const Eigen::MatrixXd A = Eigen::MatrixXd(M.asDiagonal()) - h * h * J - h * D;
    const Eigen::VectorXd b = h * (F + h * J * V);
    EXPECT_LT((A * dv - b).norm(), 1e-6 * b.norm()) << "viscosity " << viscosity;
    EXPECT_GT(dv.norm(), 1e-3);
  }
}

// Many sweeps solve the step's linear system: explicit Euler with viscosity then satisfies
// m_i (v_i' - v_i) = h f_i + h sum_e c_e (v_j' - v_i') (D17), and the axial Jacobian
// m_i (v_i' - v_i) = h f_i + sum_e (h^2 kappa_e u u^T + h c_e I)(v_j' - v_i').
TEST_P(Integrators, ConvergedSweepsSolveTheImplicitVelocityStep) {
  using M3 = Eigen::Matrix3d;
  for (Jacobian jac : {Jacobian::Isotropic, Jacobian::Axial}) {
    Params p = params(jac == Jacobian::Axial ? Integrator::Approx : Integrator::Explicit);
    p.jacobian = jac;
    p.viscosity = 5;
    p.sweeps = 400;
    if (!supports(p)) continue;
    const auto [f, s0, s] = one_step(p);
    const double h = p.h();
    std::vector<V3> residual(x0.size());
    for (size_t k = 0; k < x0.size(); ++k)
      residual[k] = s0.mass[k] * (v3(s.velocity[k]) - v3(v0[k])) - h * v3(f[k]);
    for (const EdgeView& e : s0.edges) {
      const double msum = s0.mass[e.a] + s0.mass[e.b];
      const V3 u = (v3(s0.position[e.a]) - v3(s0.position[e.b])).normalized();
      const M3 W = (jac == Jacobian::Axial ? M3(h * h * p.kappa * msum * u * u.transpose()) : M3(M3::Zero())) +
                   h * p.viscosity * msum * M3::Identity();
      const V3 dv = v3(s.velocity[e.b]) - v3(s.velocity[e.a]);
      residual[e.a] -= W * dv;
      residual[e.b] += W * dv;
    }
    double scale = 0;
    for (size_t k = 0; k < x0.size(); ++k) scale = std::max(scale, h * v3(f[k]).norm());
    for (size_t k = 0; k < x0.size(); ++k)
      EXPECT_LT(residual[k].norm(), (GetParam() == "reference" ? 1e-10 : 1e-4) * scale) << k << " " << to_string(jac);
  }
}

// The identity behind the viscosity (D17): the paper's step (approx, isotropic, no viscosity)
// is symplectic Euler with an implicit viscosity c = h kappa: the same linear system.
TEST_P(Integrators, PaperStepIsSymplecticEulerWithViscosityHKappa) {
  Params paper = params(Integrator::Approx), viscous = params(Integrator::Explicit);
  viscous.viscosity = viscous.h() * viscous.kappa;
  auto a = make(mesh, paper), b = make(mesh, viscous);
  a->set_state(x0, v0);
  b->set_state(x0, v0);
  for (int step = 0; step < 20; ++step) a->step(), b->step();
  const Snapshot sa = a->snapshot(), sb = b->snapshot();
  double vmax = 0;
  for (size_t k = 0; k < x0.size(); ++k) vmax = std::max(vmax, v3(sa.velocity[k]).norm());
  for (size_t k = 0; k < x0.size(); ++k) {
    EXPECT_LT((v3(sa.velocity[k]) - v3(sb.velocity[k])).norm(), 10 * tol() * vmax) << k;
    EXPECT_LT((v3(sa.position[k]) - v3(sb.position[k])).norm(), 10 * tol()) << k;
  }
  EXPECT_GT(vmax, 1e-2);
}

// The order of XPBD's Gauss-Seidel pass (D19): ascending id on the reference; on the fast backend
// by colour, each spring taking the smallest colour no spring of a smaller id at its endpoints
// has, then by id (the springs of a colour share no vertex, so their order among themselves
// does not matter). Computed here from the edge list alone.
std::vector<int> xpbd_order(const std::string& backend, const std::vector<EdgeView>& edges) {
  std::vector<int> order(edges.size()), color(edges.size(), -1);
  for (size_t e = 0; e < edges.size(); ++e) {
    order[e] = int(e);
    std::set<int> taken;
    for (size_t o = 0; o < e; ++o)
      if (edges[o].a == edges[e].a || edges[o].a == edges[e].b || edges[o].b == edges[e].a || edges[o].b == edges[e].b)
        taken.insert(color[o]);
    while (taken.count(color[e] + 1)) ++color[e];
    ++color[e];
  }
  if (backend == "fast") std::stable_sort(order.begin(), order.end(), [&](int p, int q) { return color[p] < color[q]; });
  return order;
}

// One Gauss-Seidel pass of XPBD over the springs in the backend's order, by hand: alpha~ =
// 1 / (kappa_e h^2) with kappa_e of [Eq 5], lambda from 0; x holds the predicted positions.
void xpbd_pass(const std::string& backend, const Snapshot& s0, double kappa, double h, std::vector<V3>& x) {
  for (const int id : xpbd_order(backend, s0.edges)) {
    const EdgeView& e = s0.edges[size_t(id)];
    const double wa = 1 / s0.mass[e.a], wb = 1 / s0.mass[e.b];
    const double kappa_e = kappa * (s0.mass[e.a] + s0.mass[e.b]);  // [Eq 5]
    const V3 d = x[e.a] - x[e.b];
    const double dlambda = -(d.norm() - e.rest) / (wa + wb + 1 / (kappa_e * h * h));
    x[e.a] += wa * dlambda * d.normalized();
    x[e.b] -= wb * dlambda * d.normalized();
  }
}

// XPBD with small steps (MODEL.md §3, ref_xpbd.cpp), by hand: v += h f_ext / m, x* = x + h v,
// one Gauss-Seidel pass over the springs in the backend's order (xpbd_order) with
// alpha~ = 1 / (kappa_e h^2) and lambda from 0, then v = (x - x_before) / h. Then momentum:
// sum m v' = sum m v + h sum f_ext. On the fast backend the id order instead of the colour order
// misses by ~1e-2 here (far above its float tolerance), so the test tells the two orders apart.
TEST_P(Integrators, XpbdProjectsEachSpringOnceInItsOrder) {
  Params p = params(Integrator::Xpbd);
  p.kappa = 3e4;
  if (!supports(p)) GTEST_SKIP() << "no XPBD on this backend";
  const auto [f, s0, s] = one_step(p);
  const double h = p.h();
  std::vector<V3> x(x0.size()), v(x0.size());
  V3 p0 = V3::Zero(), p1 = V3::Zero();
  for (size_t k = 0; k < x0.size(); ++k) {
    v[k] = v3(v0[k]) + h * V3(0, 0, -p.gravity);  // bending is off in params()
    x[k] = v3(x0[k]) + h * v[k];
    p0 += s0.mass[k] * (v3(v0[k]) + h * V3(0, 0, -p.gravity));
  }
  xpbd_pass(GetParam(), s0, p.kappa, h, x);
  for (size_t k = 0; k < x0.size(); ++k) {
    EXPECT_NEAR((v3(s.position[k]) - x[k]).norm(), 0, tol()) << k;
    EXPECT_NEAR((v3(s.velocity[k]) - (x[k] - v3(x0[k])) / h).norm(), 0, tol() / h) << k;
    p1 += s.mass[k] * v3(s.velocity[k]);
  }
  // Exact on the reference; in float each projection's m w differs from 1 by an ulp or so.
  EXPECT_LT((p1 - p0).norm(), GetParam() == "reference" ? 1e-12 : 1e-6);
}

// The viscosity on XPBD (D19): its own implicit velocity step first, solved here densely,
// m_i v*_i = m_i v_i + h sum_e c_e (v*_j - v*_i) with c_e = c (m_i + m_j) (D17), then the XPBD
// step by hand from v*. Catches a viscosity left out of XPBD, applied explicitly (v* from the
// old velocities), after the projection, or with another c_e.
TEST_P(Integrators, XpbdAppliesTheViscosityAsItsOwnImplicitStep) {
  Params p = params(Integrator::Xpbd);
  p.viscosity = 5;
  p.sweeps = 400;
  if (!supports(p)) GTEST_SKIP() << "no XPBD on this backend";
  const auto [f, s0, s] = one_step(p);
  const double h = p.h();
  const int n = int(x0.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Eigen::VectorXd b(3 * n);
  for (int k = 0; k < n; ++k) {
    A.block<3, 3>(3 * k, 3 * k) += s0.mass[size_t(k)] * Eigen::Matrix3d::Identity();
    b.segment<3>(3 * k) = s0.mass[size_t(k)] * v3(v0[size_t(k)]);
  }
  for (const EdgeView& e : s0.edges) {
    const double w = h * p.viscosity * (s0.mass[e.a] + s0.mass[e.b]);
    for (const auto& [i, j] : {std::pair{e.a, e.b}, std::pair{e.b, e.a}}) {
      A.block<3, 3>(3 * i, 3 * i) += w * Eigen::Matrix3d::Identity();
      A.block<3, 3>(3 * i, 3 * j) -= w * Eigen::Matrix3d::Identity();
    }
  }
  const Eigen::VectorXd vstar = A.lu().solve(b);
  std::vector<V3> x(x0.size());
  for (int k = 0; k < n; ++k) x[size_t(k)] = v3(x0[size_t(k)]) + h * (vstar.segment<3>(3 * k) + h * V3(0, 0, -p.gravity));
  xpbd_pass(GetParam(), s0, p.kappa, h, x);
  double moved = 0;
  for (int k = 0; k < n; ++k) moved = std::max(moved, (vstar.segment<3>(3 * k) - v3(v0[size_t(k)])).norm());
  EXPECT_GT(moved, 1e-2);  // the viscosity changed the velocities by more than the tolerance
  for (size_t k = 0; k < x0.size(); ++k) {
    EXPECT_NEAR((v3(s.position[k]) - x[k]).norm(), 0, tol()) << k;
    EXPECT_NEAR((v3(s.velocity[k]) - (x[k] - v3(x0[k])) / h).norm(), 0, tol() / h) << k;
  }
}

// XPBD's compliance is 1 / kappa_e: as h -> 0 it converges to the same motion as symplectic
// Euler (the springs of [Eq 5]); the gap between the two shrinks about linearly with h. A wrong
// compliance (say 1 / kappa) converges to another stiffness and the gap stays.
TEST_P(Integrators, XpbdConvergesToTheSpringModel) {
  Params p = params(Integrator::Xpbd);
  if (!supports(p)) GTEST_SKIP() << "no XPBD on this backend";
  auto gap = [&](int substeps) {
    Params a = params(Integrator::Explicit), b = params(Integrator::Xpbd);
    a.frame_dt = b.frame_dt = 0.05;
    a.substeps = b.substeps = substeps;
    auto sa = make(mesh, a), sb = make(mesh, b);
    sa->set_state(x0, v0);
    sb->set_state(x0, v0);
    for (int k = 0; k < substeps; ++k) sa->step(), sb->step();
    double worst = 0;
    for (size_t k = 0; k < x0.size(); ++k)
      worst = std::max(worst, (v3(sa->snapshot().position[k]) - v3(sb->snapshot().position[k])).norm());
    return worst;
  };
  const double coarse = gap(100), fine = gap(400);
  EXPECT_GT(coarse, 1e-6);
  EXPECT_LT(fine, coarse / 2.5) << coarse << " -> " << fine;
}

CRUMPLE_FOR_EACH_BACKEND(Integrators);

}  // namespace
}  // namespace crumple::test
