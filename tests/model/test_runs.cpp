// Whole runs on every backend: exact invariants through many topology changes, mesh validity
// after every step, determinism, stability, and every shared mesh.
#include <array>
#include <cmath>
#include <filesystem>

#include "sim/run.h"
#include "sim/scene.h"
#include "support/fixtures.h"

namespace crumple::test {
namespace {

class Runs : public EachBackend {};

// Free relax (no external force), balanced bending, exact restore: total mass and linear
// momentum stay what they were, to round-off, through over a thousand splits and restores,
// and the mesh is valid after every step.
TEST_P(Runs, MassAndMomentumConservedThroughSplitsAndRestores) {
  const Params p = churn_params();
  auto sim = make(make_grid(24), p);
  const Totals t0 = sim->totals();
  long splits = 0, restores = 0;
  double worst_mass = 0, worst_p = 0;
  for (int step = 0; step < 600 && (splits < 1000 || restores < 1000); ++step) {
    const StepEvents ev = sim->step();
    splits += ev.splits;
    restores += ev.restores;
    const std::string bad = sim->check_topology();
    ASSERT_EQ(bad, "") << "after step " << step;
    const Totals t = sim->totals();
    worst_mass = std::max(worst_mass, std::abs(t.mass - t0.mass));
    for (int d = 0; d < 3; ++d) worst_p = std::max(worst_p, std::abs(t.momentum[d] - t0.momentum[d]));
  }
  RecordProperty("splits", int(splits));
  RecordProperty("restores", int(restores));
  EXPECT_GE(splits, 1000);
  EXPECT_GE(restores, 1000);
  // Round-off: the sums themselves carry ~1e-16 relative error per term.
  const double eps = GetParam() == "reference" ? 1e-12 : 1e-5;
  EXPECT_LT(worst_mass, eps);
  EXPECT_LT(worst_p, eps);
}

// The same with the viscosity (D17) on every integrator: its implicit step exerts equal and
// opposite forces, and a finite sweep count is corrected (D2), so totals stay exact.
TEST_P(Runs, MassAndMomentumConservedWithViscosity) {
  for (Integrator integ : {Integrator::Approx, Integrator::Explicit, Integrator::Xpbd, Integrator::Implicit}) {
    if (integ == Integrator::Implicit && GetParam() == "fast") continue;  // Baraff-Witkin: reference only
    Params p = churn_params();
    p.integrator = integ;
    p.viscosity = 20;
    p.kappa = integ == Integrator::Explicit ? 300 : p.kappa;
    // Baraff-Witkin's momentum is exact only to its CG residual: solved tightly, what is left
    // is the viscosity's own (none, its forces being equal and opposite).
    p.cg_tolerance = integ == Integrator::Implicit ? 1e-14 : p.cg_tolerance;
    auto sim = make(make_grid(16), p);
    const Totals t0 = sim->totals();
    long splits = 0, restores = 0;
    for (int step = 0; step < 600 && (step < 150 || restores < 20); ++step) {
      const StepEvents ev = sim->step();
      splits += ev.splits;
      restores += ev.restores;
    }
    const Totals t = sim->totals();
    EXPECT_EQ(sim->check_topology(), "");
    EXPECT_GE(splits, 100) << to_string(integ);
    EXPECT_GE(restores, 20) << to_string(integ);
    const double eps = GetParam() == "reference" ? 1e-12 : 1e-5;
    EXPECT_LT(std::abs(t.mass - t0.mass), eps);
    for (int d = 0; d < 3; ++d) EXPECT_LT(std::abs(t.momentum[d] - t0.momentum[d]), eps) << to_string(integ);
    EXPECT_LT(t.kinetic, 1e3);  // bounded
  }
}

// Splitting then restoring every interior edge of a grid, one at a time, gives back exactly
// the original topology (same ids) and masses.
TEST_P(Runs, SplitThenRestoreGivesBackTheTopology) {
  auto sim = make(make_grid(5), still_params());
  const Snapshot s0 = sim->snapshot();
  for (int e = 0; e < int(s0.edges.size()); ++e) {
    ASSERT_TRUE(sim->split(e)) << e;
    ASSERT_EQ(sim->check_topology(), "");
    ASSERT_TRUE(sim->restore(e)) << e;
    ASSERT_EQ(sim->check_topology(), "");
  }
  const Snapshot s1 = sim->snapshot();
  int live = 0;
  for (size_t t = 0; t < s1.triangles.size(); ++t) live += s1.triangles[t][0] >= 0;
  EXPECT_EQ(live, int(s0.triangles.size()));
  for (size_t t = 0; t < s0.triangles.size(); ++t) EXPECT_EQ(s1.triangles[t], s0.triangles[t]);
  for (size_t e = 0; e < s0.edges.size(); ++e) {
    EXPECT_EQ(s1.edges[e].a, s0.edges[e].a);
    EXPECT_EQ(s1.edges[e].b, s0.edges[e].b);
    EXPECT_EQ(s1.edges[e].wing_l, s0.edges[e].wing_l);
    EXPECT_EQ(s1.edges[e].wing_r, s0.edges[e].wing_r);
    EXPECT_FALSE(s1.edges[e].auxiliary);
  }
  for (size_t k = 0; k < s0.mass.size(); ++k) EXPECT_NEAR(s1.mass[k], s0.mass[k], tol());
}

Snapshot crumple(const EachBackend& /*unused*/, const std::string& backend, std::uint64_t seed, int threads) {
  Params p;
  p.seed = seed;
  auto sim = make_simulator(backend, make_grid(16), p, threads);
  for (int f = 0; f < 60; ++f) sim->step();
  return sim->snapshot();
}

bool same(const Snapshot& a, const Snapshot& b) {
  return a.position == b.position && a.velocity == b.velocity && a.mass == b.mass &&
         a.triangles == b.triangles;
}

// With --substeps auto and a step bound that divides every frame time in use, the frame rate no
// longer changes the crumple: 1/30, 1/60, 1/120 and 1/240 s frames over the same 1.5 s take the
// same steps of 1/480 s and end in the same state, bit for bit. (Without the bound, auto takes
// the largest stable step, which differs between frame rates, and so does the crumple.)
TEST_P(Runs, FrameRateIndependentWithAStepBound) {
  Params p;
  p.integrator = Integrator::Explicit;
  p.viscosity = 1e4 / 60;
  p.auto_substeps = true;
  p.max_step = 1.0 / 480;
  std::vector<Snapshot> ends;
  for (int rate : {30, 60, 120, 240}) {
    p.frame_dt = 1.0 / rate;
    auto sim = make(make_grid(12), p);
    for (int f = 1; f <= rate * 3 / 2; ++f) EXPECT_EQ(run_frame(*sim, p, f).substeps, 480 / rate);
    ends.push_back(sim->snapshot());
  }
  for (size_t k = 1; k < ends.size(); ++k) EXPECT_TRUE(same(ends[0], ends[k])) << k;
  p.max_step = 0;  // stability alone: the frame rates take different steps
  std::vector<int> taken;
  for (int rate : {30, 240}) {
    p.frame_dt = 1.0 / rate;
    auto sim = make(make_grid(12), p);
    taken.push_back(run_frame(*sim, p, 1).substeps);
  }
  EXPECT_NE(taken[0], 8 * taken[1]);
}

// The default configuration (D28) is frame-rate independent bit for bit: its step bound (1/3840
// s) and its pass interval (1/240 s) divide every frame time from 1/30 to 1/240 s, so each rate
// takes the same steps and runs fracture and restoration after the same ones. Catches the pass
// tied to the frame again (adapt_every ignored: the 1/30 s frames then pass half as often as
// the 1/60 s ones, and the crumples differ) and a default without the step bound.
TEST_P(Runs, DefaultIsFrameRateIndependent) {
  Params p = default_params();
  std::vector<Snapshot> ends;
  for (int rate : {30, 60, 240}) {
    p.frame_dt = 1.0 / rate;
    auto sim = make(make_grid(12), p);
    for (int f = 1; f <= rate / 2; ++f) ASSERT_EQ(run_frame(*sim, p, f).substeps, 3840 / rate);
    ends.push_back(sim->snapshot());
  }
  EXPECT_GT(ends[0].position.size(), 144u);  // it split: the passes ran
  for (size_t k = 1; k < ends.size(); ++k) EXPECT_TRUE(same(ends[0], ends[k])) << k;
}

// The passes of pass_names() run in order (adapt_test and layout included) leave the state that
// one step() leaves, bit for bit, in a step with events: BM_Pass and BM_Events time the step's
// own work on the step's own batch of events. Catches a pass sequence that drops part of the
// step (the reference's once left out gravity and the clock, so BM_Events applied another batch).
TEST_P(Runs, PassesInOrderAreOneStep) {
  Params p;  // the paper's sphere crumple, with gravity (off by default) so that it is in the step
  p.gravity = 9.81;
  auto sim = make(make_grid(16), p);
  for (int s = 0; s < 45; ++s) sim->step();
  std::unique_ptr<Simulator> passes = sim->clone();
  const StepEvents ev = sim->step();
  for (const std::string& name : passes->pass_names()) passes->run_pass(name);
  EXPECT_GT(ev.splits, 0);
  EXPECT_TRUE(same_snapshot(sim->snapshot(), passes->snapshot()));
}

TEST_P(Runs, SameSeedSameResultOtherSeedOther) {
  const Snapshot a = crumple(*this, GetParam(), 7, 1), b = crumple(*this, GetParam(), 7, 1);
  const Snapshot c = crumple(*this, GetParam(), 8, 1);
  EXPECT_TRUE(same(a, b));
  EXPECT_FALSE(same(a, c));
}

TEST_P(Runs, DeterministicAcrossThreadCounts) {
  const Snapshot one = crumple(*this, GetParam(), 3, 1);
  for (int threads : {2, 4}) EXPECT_TRUE(same(one, crumple(*this, GetParam(), 3, threads))) << threads;
}

// The sphere crumple with the defaults (16 x 16 grid, 150 frames, seed 1) stays valid and inside
// the sphere, and its splits, restores and final vertex count lie in the band mean +- 4 sd of 32
// runs (seeds 1-16 on both backends): results/sphere_band/band.json, made by
// scripts/sphere_band.py (rerun it and update these numbers when the model changes on purpose).
// Catches a change of the crumple's statistics: e.g. phi read as 0.6 instead of 0.75 in [Eq 6]
// gives 1,176 splits (band 774-1,121), epsilon 0.4 instead of 0.5 in [Eq 10] 380 restores
// (band 161-371), restoration off none.
TEST_P(Runs, SphereCrumpleDefaults) {
  Params p;
  auto sim = make(make_grid(16), p);
  const SceneSetup scene = make_scene(make_grid(16), p);
  long splits = 0, restores = 0;
  for (int f = 1; f <= 150; ++f) {
    const StepEvents ev = sim->step();
    splits += ev.splits;
    restores += ev.restores;
    ASSERT_EQ(instability(sim->totals(), scene.size), "") << "frame " << f;
  }
  EXPECT_EQ(sim->check_topology(), "");
  RecordProperty("splits", int(splits));
  RecordProperty("restores", int(restores));
  EXPECT_GE(splits, 774);
  EXPECT_LE(splits, 1121);
  EXPECT_GE(restores, 161);
  EXPECT_LE(restores, 371);
  EXPECT_GE(sim->totals().vertices, 776);
  EXPECT_LE(sim->totals().vertices, 1100);
  // Inside the sphere, but for new vertices placed by [Eq 7] after this step's constraint.
  EXPECT_LE(sim->totals().max_distance, scene.sphere_radius(sim->time()) * 1.1);
}

// The model has no unit ([Eq 5] and bending per unit mass, c a ratio in [Eq 6], the floor and
// the scene relative to the sheet; D3, D4): the churning 16 x 16 sheet scaled by 2e-8 (edges of
// 1.3e-9, about the smallest D20 accepts) and by 1e-12 (below D20, through the library) gives the
// splits, restores and vertices of the unscaled sheet within 5 % (the tolerance of
// Agreement.TotalsOverALongCrumple). [Eq 9]'s sign adds unit normals to positions, the one place
// where a unit enters, and moves these counts by about 1 % (2,293 against 2,311 splits).
// Catches an absolute length in the fast backend (issue 14 defect 2): without the length unit
// (FastSimulator::length_unit) the areas of the 1e-12 sheet square to float subnormals and zero,
// its normals vanish and it made 1,006 splits, 876 restores, 386 vertices; at 1e-25 its squared
// edge lengths were 0 and every compressed edge broke (22,000 vertices in 24 frames).
TEST_P(Runs, TinySheetCrumplesLikeTheUnscaledOne) {
  auto counts = [&](double scale) {
    InputMesh m = make_grid(16);
    for (Vec3d& x : m.positions) x = {scale * x[0], scale * x[1], scale * x[2]};
    auto sim = make(m, churn_params());
    std::array<double, 3> c{0, 0, 0};
    for (int step = 0; step < 150; ++step) {
      const StepEvents ev = sim->step();
      c[0] += ev.splits;
      c[1] += ev.restores;
    }
    c[2] = sim->totals().vertices;
    return c;
  };
  const std::array<double, 3> unscaled = counts(1.0);
  ASSERT_GT(unscaled[1], 500);
  for (double scale : {2e-8, 1e-12}) {
    const std::array<double, 3> c = counts(scale);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(c[k], unscaled[k], 0.05 * unscaled[k]) << "scale " << scale << (k == 0 ? " splits" : k == 1 ? " restores" : " vertices");
  }
}

// set_adaptivity: with fracture and restoration off the topology stays exactly as it was while
// the sheet keeps moving; each switch alone stops only its own events; on again, both resume.
TEST_P(Runs, AdaptivitySwitchesFreezeAndResumeTheTopology) {
  const Params p = churn_params();
  auto sim = make(make_grid(24), p);
  long splits = 0, restores = 0;
  for (int step = 0; step < 300 && (splits < 50 || restores < 50); ++step) {
    const StepEvents ev = sim->step();
    splits += ev.splits, restores += ev.restores;
  }
  ASSERT_GE(splits, 50);
  ASSERT_GE(restores, 50);
  auto run = [&](bool fracture, bool restoration, int steps) {
    sim->set_adaptivity(fracture, restoration);
    StepEvents sum;
    for (int k = 0; k < steps; ++k) {
      const StepEvents ev = sim->step();
      sum.splits += ev.splits, sum.restores += ev.restores;
    }
    return sum;
  };
  const Snapshot before = sim->snapshot();
  const StepEvents frozen = run(false, false, 20);
  const Snapshot after = sim->snapshot();
  EXPECT_EQ(frozen.splits, 0);
  EXPECT_EQ(frozen.restores, 0);
  EXPECT_EQ(after.triangles, before.triangles);
  EXPECT_EQ(after.vertex_alive, before.vertex_alive);
  EXPECT_NE(after.position, before.position);  // the physics ran
  const StepEvents restores_only = run(false, true, 60);
  EXPECT_EQ(restores_only.splits, 0);
  EXPECT_GT(restores_only.restores, 0);
  const StepEvents splits_only = run(true, false, 60);
  EXPECT_EQ(splits_only.restores, 0);
  EXPECT_GT(splits_only.splits, 0);
  const StepEvents again = run(true, true, 200);
  EXPECT_GT(again.splits + again.restores, 0);
  EXPECT_EQ(sim->check_topology(), "");
}

// Symplectic Euler with kappa_e = kappa (m_i + m_j) needs h < 2/omega_max, omega_max^2 about
// 4 n_max kappa (MODEL.md §8): at kappa = 1e5 (omega_max ~ 1500/s on a grid of valence <= 8)
// a 1/60 s step is ~12x over the limit and must blow up; at kappa = 50 (omega_max ~ 35/s,
// limit ~ 1/17 s) it must not; the approximate implicit method must not blow up at either.
TEST_P(Runs, ExplicitDivergesAboveItsLimitApproxDoesNot) {
  auto run = [&](Integrator integ, double kappa, Predictor pred = Predictor::Bounded) {
    Params p;
    p.scene = Scene::Free;
    p.squeeze = 0.9;
    p.fracture = false;
    p.restoration = false;
    p.integrator = integ;
    p.predictor = pred;
    p.kappa = kappa;
    p.bend = 0;
    const InputMesh m = make_grid(12);
    auto sim = make(m, p);
    const double size = make_scene(m, p).size;
    for (int f = 0; f < 300; ++f) {
      sim->step();
      if (!instability(sim->totals(), size).empty()) return false;
    }
    return true;
  };
  EXPECT_FALSE(run(Integrator::Explicit, 1e5));
  // The paper's explicit predictor fails like explicit Euler (docs/DECISIONS.md D1).
  EXPECT_FALSE(run(Integrator::Approx, 1e5, Predictor::Explicit));
  EXPECT_TRUE(run(Integrator::Explicit, 50));
  EXPECT_TRUE(run(Integrator::Approx, 1e5));
  EXPECT_TRUE(run(Integrator::Approx, 50));
}

// The approximate implicit method with many sweeps converges to a fixed point of the
// isotropic-Jacobian implicit system: with K large, K and 2K give the same step.
TEST_P(Runs, ApproxSweepsConverge) {
  auto velocities = [&](int sweeps) {
    Params p;
    p.scene = Scene::Free;
    p.squeeze = 0.8;
    p.fracture = p.restoration = false;
    p.kappa = 200;  // h^2 sum kappa / m ~ 0.3: a contraction
    p.sweeps = sweeps;
    auto sim = make(make_grid(6), p);
    sim->step();
    return sim->snapshot().velocity;
  };
  const auto a = velocities(60), b = velocities(120), one = velocities(1);
  double diff = 0, moved = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    diff = std::max(diff, (v3(a[k]) - v3(b[k])).norm());
    moved = std::max(moved, (v3(a[k]) - v3(one[k])).norm());
  }
  EXPECT_LT(diff, 1e-6 * moved + 10 * tol());
  EXPECT_GT(moved, 1e-6);  // more sweeps do change the answer
}

// Every shared mesh runs a few frames of the sphere crumple or is rejected by the loader with
// an InputError; none crashes.
TEST_P(Runs, EverySharedMeshRunsOrIsRejected) {
  int ran = 0;
  for (const char* name : {"woody.obj", "alligator.obj", "spot.obj", "beetle.obj", "suzanne.obj",
                           "stanford-bunny.obj"}) {
    InputMesh m;
    try {
      m = load_obj(data_file(name));
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      continue;
    }
    Params p;
    auto sim = make(m, p);
    const double size = make_scene(m, p).size;
    const int frames = m.positions.size() > 10000 ? 3 : 20;
    for (int f = 0; f < frames; ++f) sim->step();
    EXPECT_EQ(instability(sim->totals(), size), "") << name;
    EXPECT_EQ(sim->check_topology(), "") << name;
    ++ran;
  }
  EXPECT_GE(ran, 3);
}

CRUMPLE_FOR_EACH_BACKEND(Runs);

}  // namespace
}  // namespace crumple::test
