// The fast backend against the scalar reference: same forces, normals and step within float
// tolerance; the same fracture and restoration decisions but where a probability is within float
// round-off of its random number; the same totals over a long crumple.
#include <cmath>

#include "sim/run.h"
#include "support/fixtures.h"

namespace crumple::test {
namespace {

std::unique_ptr<Simulator> sim(const std::string& backend, const InputMesh& m, const Params& p) {
  return make_simulator(backend, m, p, 1);
}

// Largest |a - b| over live vertices, relative to the largest |a|.
double rel_diff(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b, const std::vector<bool>& alive) {
  double diff = 0, scale = 1e-30;
  for (size_t k = 0; k < a.size(); ++k) {
    if (!alive[k]) continue;
    diff = std::max(diff, (v3(a[k]) - v3(b[k])).norm());
    scale = std::max(scale, v3(a[k]).norm());
  }
  return diff / scale;
}

// A mid-crumple state of the reference, copied into a fast simulator of identical topology by
// running both in lockstep with the fast state overwritten by the reference's every step.
struct Lockstep {
  std::unique_ptr<Simulator> ref, fast;
  int borderline = 0;  ///< decisions that differ with |P - u| within float round-off
  int compared = 0;    ///< decisions compared
  bool diverged = false;

  Lockstep(const InputMesh& m, const Params& p) : ref(sim("reference", m, p)), fast(sim("fast", m, p)) {}

  void sync() {
    const Snapshot s = ref->snapshot();
    fast->set_masses(s.mass);
    fast->set_state(s.position, s.velocity);
  }
  // Compares the decisions on the synced state, then steps both. Returns false on divergence.
  bool step() {
    sync();
    const auto a = ref->decide(), b = fast->decide();
    EXPECT_EQ(a.size(), b.size());
    for (size_t e = 0; e < a.size() && e < b.size(); ++e) {
      ++compared;
      // Decision::margin is filled by both backends (P_step - u or the restoration angle's
      // distance from epsilon) and agrees to float round-off.
      EXPECT_NEAR(a[e].margin, b[e].margin, 1e-4) << "edge " << e;
      if (a[e].kind == b[e].kind) continue;
      // Float round-off of P (relative ~1e-6) decides only when P_step is that close to u.
      EXPECT_LT(std::abs(a[e].margin), 1e-4) << "edge " << e << " ref " << int(a[e].kind) << " fast " << int(b[e].kind);
      ++borderline;
    }
    ref->step();
    fast->step();
    if (ref->snapshot().triangles != fast->snapshot().triangles) diverged = true;
    return !diverged;
  }
};

TEST(Agreement, ForcesNormalsAndOneStepOnGridsAndMeshes) {
  std::vector<std::pair<std::string, InputMesh>> meshes = {{"grid 16", make_grid(16)},
                                                           {"grid 9 fixed", make_grid(9, false)}};
  for (const char* name : {"woody.obj", "spot.obj"}) meshes.push_back({name, load_obj(data_file(name))});
  for (const auto& [name, m] : meshes) {
    for (const auto& [integ, jacobian] : {std::pair{Integrator::Approx, Jacobian::Isotropic},
                                          std::pair{Integrator::Approx, Jacobian::Axial},
                                          std::pair{Integrator::Explicit, Jacobian::Isotropic}}) {
      Params p;
      p.integrator = integ;
      p.jacobian = jacobian;
      p.viscosity = jacobian == Jacobian::Axial ? 20 : 0;  // the axial rows with both parts of W_e
      p.kappa = integ == Integrator::Explicit ? 50 : p.kappa;
      p.gravity = 9.81;
      p.fracture = p.restoration = false;
      Lockstep ls(m, p);
      for (int k = 0; k < 5; ++k) {  // a state with motion and curvature, same clock on both
        ls.sync();
        ls.ref->step();
        ls.fast->step();
      }
      ls.sync();
      const auto alive = ls.ref->snapshot().vertex_alive;
      // Float normals of thin triangles lose digits: ~1e-7 / sin(smallest angle).
      EXPECT_LT(rel_diff(ls.ref->normals(), ls.fast->normals(), alive), 1e-4) << name;
      EXPECT_LT(rel_diff(ls.ref->forces(), ls.fast->forces(), alive), 1e-4) << name;
      ls.ref->step();
      ls.fast->step();
      const Snapshot a = ls.ref->snapshot(), b = ls.fast->snapshot();
      EXPECT_LT(rel_diff(a.velocity, b.velocity, alive), 1e-4) << name << " " << to_string(integ) << " "
                                                                << to_string(jacobian);
      EXPECT_LT(rel_diff(a.position, b.position, alive), 1e-5) << name << " " << to_string(integ) << " "
                                                               << to_string(jacobian);
    }
  }
}

// Spring damping along the axis (§2), which the default configurations leave at 0 and the fast
// edge pass then skips (it reads no velocity): with damping on, both backends' forces agree on a
// state with relative motion along every spring, and they differ from the undamped forces of the
// same state by far more than the tolerance, so a fast pass that dropped the term, or took its
// undamped form with damping on, fails.
TEST(Agreement, SpringDampingOnBothBackends) {
  Params p;
  p.integrator = Integrator::Explicit;
  p.kappa = 50;
  p.damping = 5;
  p.fracture = p.restoration = false;
  const InputMesh m = make_grid(16);
  const std::unique_ptr<Simulator> ref = sim("reference", m, p), fast = sim("fast", m, p);
  Params undamped_params = p;
  undamped_params.damping = 0;
  const std::unique_ptr<Simulator> undamped = sim("reference", m, undamped_params);
  Snapshot s = ref->snapshot();
  for (std::size_t k = 0; k < s.velocity.size(); ++k) {  // a velocity field that is no rigid motion
    const double x = double(k);
    s.velocity[k] = Vec3d{0.1 * std::sin(x), 0.1 * std::cos(2.0 * x), 0.1 * std::sin(3.0 * x)};
  }
  for (Simulator* target : {ref.get(), fast.get(), undamped.get()}) {
    target->set_masses(s.mass);
    target->set_state(s.position, s.velocity);
  }
  const auto damped = ref->forces();
  EXPECT_LT(rel_diff(damped, fast->forces(), s.vertex_alive), 1e-4);
  EXPECT_GT(rel_diff(damped, undamped->forces(), s.vertex_alive), 0.1);
}

// Fracture and restoration decisions on identical states: equal but for round-off cases.
TEST(Agreement, SameDecisionsButForRoundOff) {
  Params p;
  Lockstep ls(make_grid(24), p);
  int steps = 0;
  while (steps < 150 && ls.step()) ++steps;
  RecordProperty("steps_in_lockstep", steps);
  RecordProperty("decisions_compared", ls.compared);
  RecordProperty("borderline_decisions", ls.borderline);
  std::printf("lockstep: %d steps, %d decisions compared, %d differ within round-off\n", steps, ls.compared,
              ls.borderline);
  EXPECT_GE(steps, 30);  // long enough for hundreds of splits and restores
  EXPECT_LE(ls.borderline, ls.compared / 10000 + 3);
}

// The same in the budget's ramp (D22): both backends scale P_step and epsilon by one factor of
// the pass's live vertices. Catches a backend that does not shape, or shapes differently: its
// margins then differ by (1 - f) P_step or (1 - f) epsilon, up to half of epsilon here.
TEST(Agreement, SameDecisionsNearTheBudget) {
  Params p = churn_params();
  p.max_vertices = 700;
  Lockstep ls(make_grid(24), p);
  int steps = 0, in_ramp = 0;
  while (steps < 150 && ls.step()) {
    ++steps;
    in_ramp += ls.ref->totals().vertices > 0.9 * p.max_vertices;
  }
  std::printf("lockstep with a budget: %d steps, %d in the ramp, %d decisions, %d differ within round-off\n", steps,
              in_ramp, ls.compared, ls.borderline);
  EXPECT_GE(in_ramp, 20);
  EXPECT_LE(ls.borderline, ls.compared / 10000 + 3);
}

// A 600-frame sphere crumple run independently on both: totals agree within a few per cent
// (the trajectories differ after the first round-off decision, the statistics must not).
TEST(Agreement, TotalsOverALongCrumple) {
  Params p;
  const InputMesh m = make_grid(32);
  long splits[2] = {0, 0}, restores[2] = {0, 0};
  Totals t[2];
  int i = 0;
  for (const char* b : {"reference", "fast"}) {
    auto s = sim(b, m, p);
    for (int f = 0; f < 600; ++f) {
      const StepEvents ev = s->step();
      splits[i] += ev.splits;
      restores[i] += ev.restores;
    }
    t[i++] = s->totals();
  }
  std::printf("600 frames: reference %d vertices %ld splits %ld restores; fast %d vertices %ld splits %ld restores\n",
              t[0].vertices, splits[0], restores[0], t[1].vertices, splits[1], restores[1]);
  EXPECT_NEAR(t[1].vertices, t[0].vertices, 0.05 * t[0].vertices);
  EXPECT_NEAR(splits[1], splits[0], 0.05 * splits[0]);
  EXPECT_NEAR(restores[1], restores[0], 0.05 * restores[0]);
  EXPECT_NEAR(t[1].mass, t[0].mass, 1e-5);
}

}  // namespace
}  // namespace crumple::test
