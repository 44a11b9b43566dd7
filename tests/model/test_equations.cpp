// Every equation of MODEL.md, each against an answer derived by hand or from geometry,
// run on every backend.
#include <cmath>

#include "sim/scene.h"

#include "support/fixtures.h"

namespace crumple::test {
namespace {

class Equations : public EachBackend {};

// Normals (MODEL.md §1): on a fold, the hinge's normal bisects the faces, a wing's is its face's.
TEST_P(Equations, VertexNormalsOnAFold) {
  const double alpha = M_PI / 3;
  auto sim = make(unit_square(), still_params());
  sim->set_state(folded_square(alpha, 1.0), std::vector<Vec3d>(4, Vec3d{}));
  const auto n = sim->normals();
  const V3 x1 = v3(folded_square(alpha, 1.0)[1]), x3 = v3(folded_square(alpha, 1.0)[3]);
  const V3 f0 = (x1).cross(V3(1, 1, 0)).normalized();        // face (0,1,2), vertex 0 at the origin
  const V3 f1 = V3(1, 1, 0).cross(x3).normalized();          // face (0,2,3)
  EXPECT_NEAR(v3(n[0]).dot(V3(0, 0, 1)), 1.0, tol());
  EXPECT_NEAR(v3(n[2]).dot(V3(0, 0, 1)), 1.0, tol());
  EXPECT_NEAR(v3(n[1]).dot(f0), 1.0, tol());
  EXPECT_NEAR(v3(n[3]).dot(f1), 1.0, tol());
  EXPECT_NEAR(v3(n[1]).dot(v3(n[3])), std::cos(alpha), tol());
}

// Springs (MODEL.md §2) with [Eq 5] kappa_e = kappa (m_i + m_j): pull vertex 1 of the square
// out by 0.1 along x. Edge (0,1) stretches by 0.1 along x; edge (1,2), from (1.1,0) to (1,1),
// has length sqrt(1.01); the others keep their rest length.
TEST_P(Equations, SpringForcesWithStiffnessPerUnitMass) {
  Params p = still_params();
  p.kappa = 100;
  auto sim = make(unit_square(), p);
  sim->set_masses({0.5, 2.0, 1.0, 1.5});
  auto x = folded_square(0, 1.0);
  x[1] = {1.1, 0, 0};
  sim->set_state(x, std::vector<Vec3d>(4, Vec3d{}));
  const auto f = sim->forces();
  const double k01 = 100 * (0.5 + 2.0), k12 = 100 * (2.0 + 1.0);
  const double l12 = std::sqrt(1.01);
  const V3 u12 = V3(0.1, -1, 0) / l12;  // from 2 to 1
  const V3 f1 = -k01 * 0.1 * V3(1, 0, 0) - k12 * (l12 - 1.0) * u12;
  EXPECT_NEAR((v3(f[1]) - f1).norm(), 0, tol() * k12);
  EXPECT_NEAR((v3(f[0]) - k01 * 0.1 * V3(1, 0, 0)).norm(), 0, tol() * k12);
  EXPECT_NEAR((v3(f[2]) - k12 * (l12 - 1.0) * u12).norm(), 0, tol() * k12);
  EXPECT_NEAR(v3(f[3]).norm(), 0, tol() * k12);
}

// Bending [Eq 8-9] on the square folded by 90 degrees: n_rl = cos 90 = 0, so B = |e|/2 with
// |e| = sqrt 2. The wings' normals point away from each other (x_r + n_r and x_l + n_l are
// farther apart than x_r and x_l), so s = +1: wings pushed along their normals, the hinge
// against its normal (+z) - the fold flattens.
TEST_P(Equations, BendingForcesPaperAndBalanced) {
  const double alpha = M_PI / 2;
  const auto x = folded_square(alpha, 1.0);
  for (BendingForm form : {BendingForm::Paper, BendingForm::Balanced}) {
    Params p = still_params();
    p.bend = 10;
    p.bending = form;
    auto sim = make(unit_square(), p);
    sim->set_masses({1, 1, 1, 1});
    sim->set_state(x, std::vector<Vec3d>(4, Vec3d{}));
    const auto n = sim->normals();
    const auto f = sim->forces();
    const double C = 10 * (1 + 1);                  // C_beta,e = bend (m_i + m_j)
    const double B = (1 - 0.0) * std::sqrt(2.0) / 2;  // [Eq 8]
    ASSERT_GT(((v3(x[1]) + v3(n[1])) - (v3(x[3]) + v3(n[3]))).norm(), (v3(x[1]) - v3(x[3])).norm());
    V3 want[4] = {-C * B * V3(0, 0, 1), C * B * v3(n[1]), -C * B * V3(0, 0, 1), C * B * v3(n[3])};
    if (form == BendingForm::Balanced) {
      const V3 mean = (want[0] + want[1] + want[2] + want[3]) / 4;
      for (V3& w : want) w -= mean;
    }
    V3 sum = V3::Zero();
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR((v3(f[k]) - want[k]).norm(), 0, tol() * C) << "vertex " << k << " form " << to_string(form);
      sum += v3(f[k]);
    }
    if (form == BendingForm::Balanced) { EXPECT_NEAR(sum.norm(), 0, tol() * C); }
    else { EXPECT_GT(sum.norm(), 1.0); }  // the paper's form creates net force
  }
}

TEST_P(Equations, GravityActsOnEveryVertex) {
  Params p = still_params();
  p.gravity = 9.81;
  auto sim = make(unit_square(), p);
  const auto f = sim->forces();
  const auto s = sim->snapshot();
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(f[k][2], -9.81 * s.mass[k], tol() * 10);
}

// Mass by vertex area: diagonal ends touch both triangles (area 1/3), the others one (1/6).
TEST_P(Equations, MassSpreadByVertexArea) {
  auto sim = make(unit_square(), still_params());
  const auto m = sim->snapshot().mass;
  EXPECT_NEAR(m[0], 1.0 / 3, tol());
  EXPECT_NEAR(m[1], 1.0 / 6, tol());
  EXPECT_NEAR(m[2], 1.0 / 3, tol());
  EXPECT_NEAR(m[3], 1.0 / 6, tol());
}

// The paper check of MODEL.md §5: splitting the diagonal of a unit square of four unit masses
// (every delta = 1/4) with varphi = 4 gives m_n = 2 - sqrt 2; each m_k' = (2^-1/2 + 1)/2 [Eq 3];
// v_n = sum (m_k - m_k') v_k / m_n [Eq 4].
TEST_P(Equations, SplitMassAndMomentumPaperCheck) {
  Params p = still_params();
  p.varphi = 4;
  auto sim = make(unit_square(), p);
  sim->set_masses({1, 1, 1, 1});
  const std::vector<Vec3d> v = {{1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {-1, -1, -1}};
  sim->set_state(folded_square(0, 1.0), v);
  ASSERT_TRUE(sim->split(kDiagonal));
  const auto s = sim->snapshot();
  ASSERT_EQ(s.mass.size(), 5u);
  EXPECT_NEAR(s.mass[4], 2 - std::sqrt(2.0), tol());
  const double mk = 0.5 * (1 / std::sqrt(2.0) + 1);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(s.mass[k], mk, tol());
  const double give = 1 - mk;  // what each k gave
  const V3 vn = give * (v3(v[0]) + v3(v[1]) + v3(v[2]) + v3(v[3])) / (2 - std::sqrt(2.0));
  EXPECT_NEAR((v3(s.velocity[4]) - vn).norm(), 0, tol());
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.velocity[k], v[k]);  // the old vertices keep v_k
  // Rest position: the midpoint; new rest lengths: l0/2 along the edge, sqrt(2)/2 to the wings.
  EXPECT_NEAR((v3(s.rest[4]) - V3(0.5, 0.5, 0)).norm(), 0, tol());
  int new_edges = 0;
  for (const EdgeView& e : s.edges) {
    if (e.a != 4 && e.b != 4) continue;
    ++new_edges;
    EXPECT_NEAR(e.rest, std::sqrt(2.0) / 2, tol());
    EXPECT_TRUE(e.breakable);
  }
  EXPECT_EQ(new_edges, 4);
  EXPECT_TRUE(s.edges[kDiagonal].auxiliary);
  EXPECT_FALSE(s.edges[kDiagonal].breakable);
  EXPECT_EQ(sim->check_topology(), "");
}

// [Eq 7] on a flat, compressed sheet: theta = (psi/2) sqrt(l0^2 - lt^2), along the normal (+-z,
// the sign drawn at random on a flat edge); the auxiliary edge's rest length becomes lt.
TEST_P(Equations, SplitPositionOffsetAlongTheEdgeNormal) {
  Params p = still_params();
  p.psi = 0.5;
  auto sim = make(unit_square(), p);
  const double scale = 0.8;
  sim->set_state(folded_square(0, scale), std::vector<Vec3d>(4, Vec3d{}));
  ASSERT_TRUE(sim->split(kDiagonal));
  const auto s = sim->snapshot();
  const double l0 = std::sqrt(2.0), lt = scale * l0;
  const double theta = 0.25 * std::sqrt(l0 * l0 - lt * lt);
  const V3 mid = scale * V3(0.5, 0.5, 0);
  const V3 off = v3(s.position[4]) - mid;
  EXPECT_NEAR(off.head<2>().norm(), 0, tol());
  EXPECT_NEAR(std::abs(off.z()), theta, tol());
  EXPECT_NEAR(s.edges[kDiagonal].rest, lt, tol());
}

// [Eq 7] sign on a curved edge follows the curvature: s = sign((n_j - n_i).(x_j - x_i)).
// A hinge (0,2) on a cylinder bulging towards +z... here: bend edge (0,1) of the square so its
// end normals diverge; the new vertex moves with the bulge (along +nu).
TEST_P(Equations, SplitOffsetFollowsCurvature) {
  Params p = still_params();
  p.psi = 1;
  auto sim = make(unit_square(), p);
  // Fold about the diagonal: the diagonal's ends (0,2) have equal normals, so use edge 0 = (0,1):
  // n_0 = +z (bisector), n_1 = face 0's normal; (n_1 - n_0).(x_1 - x_0) decides.
  const auto x = folded_square(M_PI / 2, 0.9);
  sim->set_state(x, std::vector<Vec3d>(4, Vec3d{}));
  const auto n = sim->normals();
  const double curl = (v3(n[1]) - v3(n[0])).dot(v3(x[1]) - v3(x[0]));
  ASSERT_GT(std::abs(curl), 1e-3);
  ASSERT_TRUE(sim->split(0));
  const auto s = sim->snapshot();
  // Edge (0,1) is a boundary edge: nu is face 0's normal = n_1.
  const V3 off = v3(s.position[4]) - 0.5 * (v3(x[0]) + v3(x[1]));
  EXPECT_GT(off.dot(v3(n[1])) * curl, 0);
  const double l0 = 1, lt = 0.9;
  EXPECT_NEAR(off.norm(), 0.5 * std::sqrt(l0 * l0 - lt * lt), tol());
}

// Frequency of a diagonal break within one frame of `substeps` steps over `trials` seeds.
int count_breaks(const std::string& backend, Params p, double alpha, double scale, int substeps, int trials) {
  p.floor = 1.0;  // floor length = mean edge (2 + sqrt 2)/3 > 1: sides never break
  p.substeps = substeps;
  p.restoration = false;
  int breaks = 0;
  for (int seed = 1; seed <= trials; ++seed) {
    p.seed = std::uint64_t(seed);
    auto sim = make_simulator(backend, unit_square(), p, 1);
    sim->set_state(folded_square(alpha, scale), std::vector<Vec3d>(4, Vec3d{}));
    int splits = 0;
    for (int k = 0; k < substeps; ++k) splits += sim->step().splits;
    EXPECT_LE(splits, 1);
    if (splits) { EXPECT_TRUE(sim->snapshot().edges[kDiagonal].auxiliary); }
    breaks += splits;
  }
  return breaks;
}

// [Eq 6] by counting: fold the square by alpha, compress it by `scale`; with the floor above
// the side length only the diagonal can break, with P = 1/4 c (1 - phi n_ij)(1 + phi n_rl),
// c = 1 - scale, n_ij = 1 (both hinge normals bisect), n_rl = cos alpha. Over many seeds the
// frequency of a break in the first frame must match P within 4.5 standard deviations.
TEST_P(Equations, FractureProbabilityByCounting) {
  const double alpha = M_PI / 3, scale = 0.6, phi = 0.5;
  const double P = 0.25 * (1 - scale) * (1 - phi) * (1 + phi * std::cos(alpha));
  Params p = still_params();
  p.phi = phi;
  const int trials = 4000, breaks = count_breaks(GetParam(), p, alpha, scale, 1, trials);
  EXPECT_NEAR(breaks, trials * P, 4.5 * std::sqrt(trials * P * (1 - P))) << "P " << P;
}

// With S steps a frame, P_step = 1 - (1 - P)^(h/h_ref) keeps the per-frame break rate at P.
// P = 0.2375 (phi = 0, c = 0.95) and S = 8 set it apart from the two wrong rates: P h/h_ref per
// step gives 1 - (1 - P/8)^8 = 0.2140 a frame (7.8 standard deviations off over 20,000 seeds), P
// per step 1 - (1 - P)^8 = 0.886. Catches either mutation of break_probability.
TEST_P(Equations, FractureProbabilityPerStepKeepsTheFrameRate) {
  const double scale = 0.05, P = 0.25 * (1 - scale);
  const int substeps = 8, trials = 20000;
  const double sigma = std::sqrt(trials * P * (1 - P));
  const double linear = 1 - std::pow(1 - P / substeps, substeps), per_step = 1 - std::pow(1 - P, substeps);
  ASSERT_GT(trials * (P - linear), 7 * sigma);  // the design separates the rates
  ASSERT_GT(trials * (per_step - P), 7 * sigma);
  Params p = still_params();
  p.phi = 0;
  const int breaks = count_breaks(GetParam(), p, 0.0, scale, substeps, trials);
  EXPECT_NEAR(breaks, trials * P, 4.5 * sigma) << "P " << P << "; P h/h_ref would give about "
                                               << trials * linear << ", P per step " << trials * per_step;
}

// --adapt frame (D27): with S steps a frame the pass runs once, after the frame's last step,
// with P over the frame: 1 - (1 - P)^(frame_dt / h_ref) = P at 60 Hz. Counting as above, the
// rate stays P (catches the step's exponent h/h_ref in a per-frame pass: 1 - (1 - P)^(1/8) =
// 0.034 a frame) and no split happens before the frame's last step (catches a pass after every
// step, or a clock that fires early).
TEST_P(Equations, FractureOncePerFrameCoversTheFrame) {
  const double scale = 0.05, P = 0.25 * (1 - scale);
  const int substeps = 8, trials = 4000;
  Params p = still_params();
  p.phi = 0;
  p.floor = 1.0;  // only the diagonal may break (count_breaks)
  p.substeps = substeps;
  p.restoration = false;
  p.adapt_per_frame = true;
  int breaks = 0, early = 0;
  for (int seed = 1; seed <= trials; ++seed) {
    p.seed = std::uint64_t(seed);
    auto sim = make_simulator(GetParam(), unit_square(), p, 1);
    sim->set_state(folded_square(0.0, scale), std::vector<Vec3d>(4, Vec3d{}));
    for (int k = 0; k < substeps; ++k) (k + 1 < substeps ? early : breaks) += sim->step().splits;
  }
  EXPECT_EQ(early, 0);
  EXPECT_NEAR(breaks, trials * P, 4.5 * std::sqrt(trials * P * (1 - P))) << "P " << P;
}

// With one step a frame, --adapt frame is --adapt step: the same passes with the same
// probabilities, bit for bit, through a crumple. Catches a per-frame clock that skips a pass
// at one step a frame, or an interval other than h there.
TEST_P(Equations, AdaptPerFrameAtOneStepIsThePaperStep) {
  Params p;
  auto run = [&](bool per_frame) {
    p.adapt_per_frame = per_frame;
    auto sim = make_simulator(GetParam(), make_grid(16), p, 1);
    long events = 0;
    for (int f = 0; f < 60; ++f) {
      const StepEvents ev = sim->step();
      events += ev.splits + ev.restores;
    }
    EXPECT_GT(events, 50);
    return sim->snapshot();
  };
  const Snapshot a = run(false), b = run(true);
  EXPECT_TRUE(same_snapshot(a, b));
}

// No break when stretched, when phi = 1 on a flat sheet, or below the refinement floor.
TEST_P(Equations, NoFractureWhereTheModelForbidsIt) {
  struct Case { double scale, phi, floor; const char* what; };
  for (const Case& c : {Case{1.2, 0.0, 0.0, "stretched"}, Case{0.5, 1.0, 0.0, "flat with phi = 1"},
                        Case{0.5, 0.0, 1.3, "below the floor"}}) {
    Params p = still_params();
    p.phi = c.phi;
    p.floor = c.floor;
    int splits = 0;
    for (int seed = 1; seed <= 300; ++seed) {
      p.seed = std::uint64_t(seed);
      auto sim = make(unit_square(), p);
      sim->set_state(folded_square(0, c.scale), std::vector<Vec3d>(4, Vec3d{}));
      splits += sim->step().splits;
    }
    EXPECT_EQ(splits, 0) << c.what;
  }
}

// Restoration (MODEL.md §7), exact form: split then restore gives back the topology, the
// masses, and merges n's momentum inelastically: v_k' = (m_k v_k + (m_k' - m_k) v_n) / m_k'.
TEST_P(Equations, ExactRestoreUndoesASplit) {
  Params p = still_params();
  p.varphi = 3;
  auto sim = make(unit_square(), p);
  const auto before = sim->snapshot();
  ASSERT_TRUE(sim->split(kDiagonal));
  const auto mid = sim->snapshot();
  // Give n a velocity of its own, then restore.
  auto v = mid.velocity;
  v[4] = {0, 0, 2};
  sim->set_state(mid.position, v);
  ASSERT_TRUE(sim->restore(kDiagonal));
  const auto after = sim->snapshot();
  EXPECT_EQ(sim->check_topology(), "");
  ASSERT_FALSE(after.vertex_alive[4]);
  for (int t = 0; t < 2; ++t) EXPECT_EQ(after.triangles[t], before.triangles[t]);
  for (int e = 0; e < 5; ++e) {
    EXPECT_EQ(after.edges[e].a, before.edges[e].a);
    EXPECT_EQ(after.edges[e].b, before.edges[e].b);
    EXPECT_NEAR(after.edges[e].rest, before.edges[e].rest, tol());
    EXPECT_EQ(after.edges[e].auxiliary, false);
  }
  double pz = 0;
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(after.mass[k], before.mass[k], tol());
    const double gave = before.mass[k] - mid.mass[k];
    EXPECT_NEAR(after.velocity[k][2], gave * 2 / before.mass[k], tol());
    pz += after.mass[k] * after.velocity[k][2];
  }
  EXPECT_NEAR(pz, mid.mass[4] * 2, tol());
}

// Restoration, the paper's form [Eq 11-12]: m_k' = 2 m_k / (delta_k^(1/varphi) + 1) and
// v_k' = v_k + m_n v_n / sum m_k', the sum over the masses *after* [Eq 11] (D24). Masses 1, 2, 3, 4
// and every delta = 1/4, varphi = 2: the split leaves m_k = 0.75 m_k0 (sum 7.5) and m_n = 2.5;
// [Eq 11] gives back m_k0 (sum 10), so [Eq 12] adds 2.5 v_n / 10 to every v_k. Catches [Eq 12]
// read with the masses before [Eq 11] (2.5 v_n / 7.5: 0.25 off in x here) and a restore that
// replaces v_k instead of adding to it.
TEST_P(Equations, PaperRestoreFormulas) {
  Params p = still_params();
  p.varphi = 2;
  p.restore = RestoreForm::Paper;
  auto sim = make(unit_square(), p);
  const std::vector<double> m0 = {1, 2, 3, 4};
  sim->set_masses(m0);
  ASSERT_TRUE(sim->split(kDiagonal));
  auto mid = sim->snapshot();
  ASSERT_NEAR(mid.mass[4], 2.5, tol());
  auto v = mid.velocity;
  v[4] = {3, 0, 0};
  for (int k = 0; k < 4; ++k) v[k] = {0, 0.5 * k, -1};
  sim->set_state(mid.position, v);
  ASSERT_TRUE(sim->restore(kDiagonal));
  const auto after = sim->snapshot();
  const double mk = 0.5 * (std::sqrt(0.25) + 1);  // after the split, delta = 1/4
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(after.mass[k], 2 * mk * m0[k] / (std::sqrt(0.25) + 1), tol());
    EXPECT_NEAR(after.velocity[k][0], 2.5 * 3 / 10.0, tol()) << k;
    EXPECT_NEAR(after.velocity[k][1], 0.5 * k, tol()) << k;
    EXPECT_NEAR(after.velocity[k][2], -1, tol()) << k;
  }
}

// The hang scene's pins are external forces, so the momentum correction of D2 is off with them
// (D23). With no springs (kappa = 0, no bending, no viscosity) the rows of the implicit step
// decouple: after one step from rest every free vertex falls at exactly v_z = -h g and the
// pinned corners stay at their start with v = 0, so the sheet's momentum changes by
// -h g (M - pinned mass), not by -h g M. On the 2 x 2 grid the pinned corners (ids 2, 3) hold
// half the mass. Catches the correction left on with pins: it removes the pins' support,
// h g m_pinned / M = h g / 2, from every vertex (the free ones then fall at h g / 2).
TEST_P(Equations, PinsSwitchOffTheMomentumCorrection) {
  Params p = still_params();
  p.scene = Scene::Hang;
  p.gravity = 9.81;
  const InputMesh sheet = make_grid(2);
  const SceneSetup scene = make_scene(sheet, p);
  ASSERT_EQ(scene.pinned, (std::vector<int>{2, 3}));
  auto sim = make(sheet, p);
  const Snapshot s0 = sim->snapshot();
  sim->step();
  const Snapshot s = sim->snapshot();
  const double h = p.h();
  double pinned_mass = 0, mass = 0, pz = 0;
  for (int k = 0; k < 4; ++k) {
    const bool pin = k >= 2;
    mass += s.mass[k];
    pinned_mass += pin ? s.mass[k] : 0.0;
    pz += s.mass[k] * s.velocity[k][2];
    EXPECT_NEAR(s.velocity[k][2], pin ? 0.0 : -h * 9.81, tol()) << "vertex " << k;
    if (pin) { EXPECT_EQ(s.position[k], s0.position[k]) << "vertex " << k; }
  }
  ASSERT_NEAR(pinned_mass, 0.5 * mass, tol());
  EXPECT_NEAR(pz, -h * 9.81 * (mass - pinned_mass), tol());
}

// [Eq 10] angle test in a step: after a split, a fold across the crease line with
// (1 - n_rl)/2 >= epsilon restores the edge; a smaller fold does not.
TEST_P(Equations, RestorationThreshold) {
  for (double alpha : {M_PI / 6, 2 * M_PI / 3}) {
    Params p = still_params();
    p.fracture = false;
    p.epsilon = 0.5;  // restores when n_rl <= 0: a fold of more than 90 degrees
    auto sim = make(unit_square(), p);
    ASSERT_TRUE(sim->split(kDiagonal));
    auto s = sim->snapshot();
    auto x = folded_square(alpha, 1.0);
    x.push_back({0.5, 0.5, 0});  // n on the hinge
    sim->set_state(x, s.velocity);
    const int restores = sim->step().restores;
    EXPECT_EQ(restores, alpha > M_PI / 2 ? 1 : 0) << "fold " << alpha;
    EXPECT_EQ(sim->check_topology(), "");
  }
}

// The extra condition of MODEL.md §7: once a neighbouring split changed n's fan, no restore.
TEST_P(Equations, NoRestoreAfterANeighbouringSplit) {
  auto sim = make(unit_square(), still_params());
  ASSERT_TRUE(sim->split(kDiagonal));
  const auto s = sim->snapshot();
  int e_in = -1;
  for (int e = 0; e < int(s.edges.size()); ++e)
    if ((s.edges[e].a == 0 && s.edges[e].b == 4) || (s.edges[e].a == 4 && s.edges[e].b == 0)) e_in = e;
  ASSERT_GE(e_in, 0);
  ASSERT_TRUE(sim->split(e_in));
  EXPECT_FALSE(sim->restore(kDiagonal));
  EXPECT_TRUE(sim->restore(e_in));
  EXPECT_TRUE(sim->restore(kDiagonal));
  EXPECT_EQ(sim->check_topology(), "");
  EXPECT_EQ(sim->totals().vertices, 4);
}

CRUMPLE_FOR_EACH_BACKEND(Equations);

}  // namespace
}  // namespace crumple::test
