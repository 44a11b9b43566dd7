// One step of each integrator (MODEL.md §3) checked against its defining equation, with the
// forces and their Jacobian taken from the backend's force hook (the Jacobian by central
// finite differences, so the analytic one in the code is checked independently).
#include <Eigen/Dense>

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

// K = 1: v_i' = (m_i v_i + h f_i + h^2 sum_j kappa_e v*_j) / (m_i + h^2 sum kappa_e), with the
// guess v*_j = v_j + h f_j / m_j (the paper's explicit predictor) or the bounded predictor
// v_j + h g + (h (f_j - m_j g) + h^2 sum_k kappa (v_k - v_j)) / (m_j + 2 h^2 sum kappa).
TEST_P(Integrators, ApproximateImplicitOneSweep) {
  for (Predictor pred : {Predictor::Explicit, Predictor::Bounded}) {
    Params p = params(Integrator::Approx);
    p.predictor = pred;
    auto sim = make(mesh, p);
    sim->set_state(x0, v0);
    const auto f = sim->forces();
    const Snapshot s0 = sim->snapshot();
    sim->step();
    const auto s = sim->snapshot();
    const double h = p.h(), h2 = h * h;
    const size_t n = x0.size();
    const V3 g(0, 0, -p.gravity);
    std::vector<double> ksum(n, 0.0);
    std::vector<V3> jv(n, V3::Zero());
    for (const EdgeView& e : s0.edges) {
      const double kap = p.kappa * (s0.mass[e.a] + s0.mass[e.b]);  // [Eq 5]
      ksum[e.a] += kap;
      ksum[e.b] += kap;
      jv[e.a] += kap * (v3(v0[e.b]) - v3(v0[e.a]));
      jv[e.b] += kap * (v3(v0[e.a]) - v3(v0[e.b]));
    }
    auto guess = [&](int j) {
      const double m = s0.mass[j];
      if (pred == Predictor::Explicit) return V3(v3(v0[j]) + h * v3(f[j]) / m);
      return V3(v3(v0[j]) + h * g + (h * (v3(f[j]) - m * g) + h2 * jv[j]) / (m + 2 * h2 * ksum[j]));
    };
    std::vector<V3> num(n);
    for (size_t k = 0; k < n; ++k) num[k] = s0.mass[k] * v3(v0[k]) + h * v3(f[k]);
    for (const EdgeView& e : s0.edges) {
      const double kap = p.kappa * (s0.mass[e.a] + s0.mass[e.b]);
      num[e.a] += h2 * kap * guess(e.b);
      num[e.b] += h2 * kap * guess(e.a);
    }
    // Then the uniform correction that restores sum m v' = sum m v + h sum f (DECISIONS.md D2).
    std::vector<V3> vnew(n);
    V3 drift = V3::Zero();
    double mass = 0;
    for (size_t k = 0; k < n; ++k) {
      vnew[k] = num[k] / (s0.mass[k] + h2 * ksum[k]);
      drift += s0.mass[k] * (vnew[k] - v3(v0[k])) - h * v3(f[k]);
      mass += s0.mass[k];
    }
    for (size_t k = 0; k < n; ++k) {
      const V3 v = vnew[k] - drift / mass;
      EXPECT_NEAR((v3(s.velocity[k]) - v).norm(), 0, tol() * 100) << k << " " << to_string(pred);
      EXPECT_NEAR((v3(s.position[k]) - (v3(x0[k]) + h * v)).norm(), 0, tol() * 10) << k;
    }
  }
}

// Baraff-Witkin: (M - h^2 J) dv = h (f + h J v) with J = df/dx from finite differences.
TEST_P(Integrators, BaraffWitkinSolvesTheLinearSystem) {
  if (skip_implicit) GTEST_SKIP() << "the fast backend has no Baraff-Witkin integrator";
  const Params p = params(Integrator::Implicit);
  auto sim = make(mesh, p);
  const size_t n = x0.size();
  const double h = p.h(), delta = 1e-6;
  Eigen::MatrixXd J(3 * n, 3 * n);
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
  const auto m = sim->snapshot().mass;
  Eigen::VectorXd F(3 * n), V(3 * n), M(3 * n);
  for (size_t k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) {
      F(3 * k + d) = f[k][d];
      V(3 * k + d) = v0[k][d];
      M(3 * k + d) = m[k];
    }
  sim->step();
  const auto s = sim->snapshot();
  Eigen::VectorXd dv(3 * n);
  for (size_t k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) dv(3 * k + d) = s.velocity[k][d] - v0[k][d];
  const Eigen::MatrixXd A = Eigen::MatrixXd(M.asDiagonal()) - h * h * J;
  const Eigen::VectorXd b = h * (F + h * J * V);
  EXPECT_LT((A * dv - b).norm(), 1e-6 * b.norm());
  EXPECT_GT(dv.norm(), 1e-3);
}

CRUMPLE_FOR_EACH_BACKEND(Integrators);

}  // namespace
}  // namespace crumple::test
