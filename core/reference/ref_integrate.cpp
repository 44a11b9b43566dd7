// Time integration of the reference backend (MODEL.md §3) and the sphere constraint (§8).
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <type_traits>

#include "reference/reference_sim.h"

namespace crumple::ref {

// The implicit velocity step shared by the approximate implicit method and by the viscosity
// (MODEL.md §3, docs/DECISIONS.md D1, D17). Each spring e = (i, j) adds a block W_e to row i:
//     (m_i I + sum_e W_e) v_i' = m_i v_i + h f_i + sum_e W_e v_j',
//     W_e = h^2 kappa_e J_e + h c_e I,   J_e = I (isotropic), u u^T (axial), 0 (explicit),
// i.e. symplectic Euler for f plus implicit Euler for the linear terms in W. Each Jacobi sweep
// evaluates the row with v_j' on the right taken from the previous sweep. The first guess:
//  * Explicit (the paper's): v_j + h f_j / m_j. Unstable once h^2 kappa_e / m exceeds about 1.
//  * Bounded (default): v_j + h g + (m_j I + 2 sum_e W_e)^-1 (h f_j^int + sum_e W_e (v_k - v_j)):
//    the same row solved with its diagonal bounded by Gershgorin (neighbours moving against it),
//    external acceleration g exact. Equal to the explicit guess for soft springs; stable for any
//    h and any K. K -> infinity converges to the linear implicit step.
namespace {
using Mat3 = Eigen::Matrix3d;
V3 times(double w, const V3& v) { return w * v; }
V3 times(const Mat3& w, const V3& v) { return w * v; }
template <class Block>
Block zero() {
  if constexpr (std::is_same_v<Block, double>) return 0.0;
  else return Mat3::Zero();
}
V3 solve_row(double m, double w, const V3& b) { return b / (m + w); }
V3 solve_row(double m, const Mat3& w, const V3& b) { return (m * Mat3::Identity() + w).llt().solve(b); }
}  // namespace

void ReferenceSimulator::integrate(double h, const std::vector<V3>& f) {
  const bool viscous = params_.viscosity > 0;
  switch (params_.integrator) {
    case Integrator::Approx:
      advance(h, params_.jacobian == Jacobian::Axial ? solve_rows<Mat3>(h, f) : solve_rows<double>(h, f));
      break;
    case Integrator::Explicit:
      if (viscous) advance(h, solve_rows<double>(h, f));  // the viscosity's implicit step, no stiffness term
      else integrate_explicit(h, f);
      break;
    case Integrator::Implicit: integrate_implicit(h, f); break;
    case Integrator::Xpbd: integrate_xpbd(h); break;  // its own forces: springs are constraints
  }
}

// W_e of one spring (see above): a scalar times I, or a 3 x 3 block for the axial Jacobian.
template <class Block>
Block ReferenceSimulator::implicit_block(const Edge& E, double h) const {
  const double msum = mesh_.verts[E.a].m + mesh_.verts[E.b].m;
  const double ce = params_.viscosity * msum;  // c_e = c (m_i + m_j), like [Eq 5]
  const double stiff = params_.integrator == Integrator::Approx ? h * h * E.kappa : 0.0;
  if constexpr (std::is_same_v<Block, double>) {
    return stiff + h * ce;
  } else {
    const V3 d = mesh_.verts[E.a].x - mesh_.verts[E.b].x;
    const double lt = d.norm();
    const V3 u = lt > 0 ? V3(d / lt) : V3::Zero();
    return stiff * u * u.transpose() + h * ce * Mat3::Identity();
  }
}

template <class Block>
std::vector<V3> ReferenceSimulator::solve_rows(double h, const std::vector<V3>& f) const {
  const size_t n = mesh_.verts.size();
  const V3 g(0, 0, -params_.gravity);
  std::vector<Block> W(mesh_.edges.size(), zero<Block>()), wsum(n, zero<Block>());
  std::vector<V3> jv(n, V3::Zero());  // sum_e W_e (v_j - v_i)
  for (size_t e = 0; e < mesh_.edges.size(); ++e) {
    const Edge& E = mesh_.edges[e];
    if (!E.alive) continue;
    W[e] = implicit_block<Block>(E, h);
    const V3 dv = mesh_.verts[E.b].v - mesh_.verts[E.a].v;
    wsum[E.a] += W[e];
    wsum[E.b] += W[e];
    jv[E.a] += times(W[e], dv);
    jv[E.b] -= times(W[e], dv);
  }
  std::vector<V3> guess(n, V3::Zero()), next(n, V3::Zero());
  for (size_t k = 0; k < n; ++k) {
    const Vertex& V = mesh_.verts[k];
    if (!V.alive) continue;
    if (params_.predictor == Predictor::Explicit)
      guess[k] = V.v + h * f[k] / V.m;
    else
      guess[k] = V.v + h * g + solve_row(V.m, Block(2 * wsum[k]), V3(h * (f[k] - V.m * g) + jv[k]));
  }
  for (int k : scene_.pinned) guess[k].setZero();  // pinned vertices are fixed neighbours
  for (int sweep = 0; sweep < params_.sweeps; ++sweep) {
    std::vector<V3> num(n, V3::Zero());
    for (size_t k = 0; k < n; ++k)
      if (mesh_.verts[k].alive) num[k] = mesh_.verts[k].m * mesh_.verts[k].v + h * f[k];
    for (size_t e = 0; e < mesh_.edges.size(); ++e) {
      const Edge& E = mesh_.edges[e];
      if (!E.alive) continue;
      num[E.a] += times(W[e], guess[E.b]);
      num[E.b] += times(W[e], guess[E.a]);
    }
    for (size_t k = 0; k < n; ++k)
      if (mesh_.verts[k].alive) next[k] = solve_row(mesh_.verts[k].m, wsum[k], num[k]);
    guess.swap(next);
    for (int k : scene_.pinned) guess[k].setZero();
  }
  correct_momentum(h, f, guess);
  return guess;
}
template std::vector<V3> ReferenceSimulator::solve_rows<double>(double, const std::vector<V3>&) const;

// A finite number of sweeps leaves an error with a net momentum, which the exact implicit step
// would not have (its matrix has zero row sums off the mass): remove it with a uniform velocity
// so that sum m v' = sum m v + h sum f exactly (docs/DECISIONS.md D2).
void ReferenceSimulator::correct_momentum(double h, const std::vector<V3>& f, std::vector<V3>& vnew) const {
  const size_t n = mesh_.verts.size();
  V3 drift = V3::Zero();
  double mass = 0;
  for (size_t k = 0; k < n; ++k) {
    const Vertex& V = mesh_.verts[k];
    if (!V.alive) continue;
    drift += V.m * (vnew[k] - V.v) - h * f[k];
    mass += V.m;
  }
  // (No correction with pinned vertices: the pins exert external forces.)
  const V3 correction = scene_.pinned.empty() ? V3(drift / mass) : V3::Zero();
  for (size_t k = 0; k < n; ++k)
    if (mesh_.verts[k].alive) vnew[k] -= correction;
}

// v = v', x' = x + h v'.
void ReferenceSimulator::advance(double h, const std::vector<V3>& vnew) {
  for (size_t k = 0; k < mesh_.verts.size(); ++k) {
    Vertex& V = mesh_.verts[k];
    if (!V.alive) continue;
    V.v = vnew[k];
    V.x += h * V.v;
  }
}

// Symplectic Euler: v' = v + h f / m, x' = x + h v'.
void ReferenceSimulator::integrate_explicit(double h, const std::vector<V3>& f) {
  for (size_t k = 0; k < mesh_.verts.size(); ++k) {
    Vertex& V = mesh_.verts[k];
    if (!V.alive) continue;
    V.v += h * f[k] / V.m;
    V.x += h * V.v;
  }
}

namespace {
// Pinned vertices (rows row[k] of the system's triplets and right-hand side b): their rows and
// columns become the identity with dv = 0 (a fixed vertex).
void pin_rows(const std::vector<int>& pinned, const std::vector<int>& row, std::vector<Eigen::Triplet<double>>& trip,
              Eigen::VectorXd& b) {
  std::vector<char> fixed(std::size_t(b.size()), 0);
  for (int k : pinned)
    for (int d = 0; d < 3; ++d) fixed[std::size_t(3 * row[k] + d)] = 1;
  std::vector<Eigen::Triplet<double>> kept;
  for (const auto& t : trip)
    if (!fixed[std::size_t(t.row())] && !fixed[std::size_t(t.col())]) kept.push_back(t);
  for (Eigen::Index r = 0; r < b.size(); ++r)
    if (fixed[std::size_t(r)]) {
      kept.emplace_back(int(r), int(r), 1.0);
      b(r) = 0;
    }
  trip.swap(kept);
}
}  // namespace

// Baraff-Witkin implicit Euler, (M - h^2 df/dx - h df/dv) dv = h (f + h df/dx v), with the true
// spring Jacobian -kappa_e [u u^T + (1 - l0/lt)(I - u u^T)] (the second term dropped when
// compressed so the matrix stays definite); bending is explicit; the viscosity (D17) implicit
// like the damping. Solved by Eigen's CG.
void ReferenceSimulator::integrate_implicit(double h, const std::vector<V3>& f) {
  const int nv = int(mesh_.verts.size());
  std::vector<int> row(nv, -1);
  int n = 0;
  for (int k = 0; k < nv; ++k)
    if (mesh_.verts[k].alive) row[k] = n++;

  using Mat3 = Eigen::Matrix3d;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::VectorXd b(3 * n);
  for (int k = 0; k < nv; ++k) {
    if (row[k] < 0) continue;
    for (int d = 0; d < 3; ++d) trip.emplace_back(3 * row[k] + d, 3 * row[k] + d, mesh_.verts[k].m);
    b.segment<3>(3 * row[k]) = h * f[k];
  }
  auto add_block = [&](int i, int j, const Mat3& m) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) trip.emplace_back(3 * row[i] + r, 3 * row[j] + c, m(r, c));
  };
  for (const Edge& E : mesh_.edges) {
    if (!E.alive) continue;
    const Vertex &A = mesh_.verts[E.a], &B = mesh_.verts[E.b];
    const V3 d = A.x - B.x;
    const double lt = d.norm();
    if (!(lt > 0)) continue;
    const V3 u = d / lt;
    const Mat3 uu = u * u.transpose();
    Mat3 K = -E.kappa * uu;  // df_a/dx_a
    if (lt > E.l0) K -= E.kappa * (1.0 - E.l0 / lt) * (Mat3::Identity() - uu);
    // df_a/dv_a: spring-axis damping, and the viscosity c_e (v_b - v_a) (D17), whose force
    // at v is not in f and is added to the right-hand side here.
    const double ce = params_.viscosity * (A.m + B.m);
    const Mat3 D = -params_.damping * (A.m + B.m) * uu - ce * Mat3::Identity();
    const Mat3 Aaa = -h * h * K - h * D;
    add_block(E.a, E.a, Aaa);
    add_block(E.b, E.b, Aaa);
    add_block(E.a, E.b, -Aaa);
    add_block(E.b, E.a, -Aaa);
    const V3 jv = h * K * (A.v - B.v) + ce * (B.v - A.v);  // (h df/dx v + f_visc)_a
    b.segment<3>(3 * row[E.a]) += h * jv;
    b.segment<3>(3 * row[E.b]) -= h * jv;
  }
  if (!scene_.pinned.empty()) pin_rows(scene_.pinned, row, trip, b);
  Eigen::SparseMatrix<double> M(3 * n, 3 * n);
  M.setFromTriplets(trip.begin(), trip.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(params_.cg_tolerance);
  cg.setMaxIterations(params_.cg_max_iterations);
  cg.compute(M);
  const Eigen::VectorXd dv = cg.solve(b);
  for (int k = 0; k < nv; ++k) {
    if (row[k] < 0) continue;
    Vertex& V = mesh_.verts[k];
    V.v += dv.segment<3>(3 * row[k]);
    V.x += h * V.v;
  }
}

}  // namespace crumple::ref
