// The fast backend's internal machinery, which must not change what is simulated: the slot
// layout (core/fast/layout.h) changes only where things are stored; the parallel rounds of
// splits (fast_adapt.cpp) give what one split after the other gives.
#include <cmath>

#include "fast/fast_sim.h"
#include "fast/layout.h"
#include "support/fixtures.h"

namespace crumple::test {
namespace {

bool same_snapshot(const Snapshot& a, const Snapshot& b) {
  if (!(a.position == b.position && a.velocity == b.velocity && a.mass == b.mass && a.rest == b.rest &&
        a.vertex_alive == b.vertex_alive && a.triangles == b.triangles && a.edges.size() == b.edges.size()))
    return false;
  for (std::size_t e = 0; e < a.edges.size(); ++e) {
    const EdgeView &p = a.edges[e], &q = b.edges[e];
    if (p.a != q.a || p.b != q.b || p.wing_l != q.wing_l || p.wing_r != q.wing_r || p.rest != q.rest ||
        p.auxiliary != q.auxiliary || p.breakable != q.breakable)
      return false;
  }
  return true;
}

/// Mean |slot(a) - slot(b)| over live edges: how far apart neighbours are stored.
double mean_slot_distance(const fast::Topology& m) {
  double sum = 0;
  int n = 0;
  for (int e = 0; e < m.E.size(); ++e) {
    if (!(m.E.flags[e] & fast::kAlive)) continue;
    sum += std::abs(m.E.a[e] - m.E.b[e]);
    ++n;
  }
  return sum / n;
}

// The sphere crumple with symplectic Euler (no momentum correction, whose block sums follow
// the slot order): relayout after every step and never give bit-identical logical states,
// through hundreds of splits and restores, on one and two threads.
TEST(Layout, RelayoutEveryStepChangesNoBit) {
  Params p;
  p.integrator = Integrator::Explicit;
  p.kappa = 50;  // inside symplectic Euler's limit at h = 1/60
  for (int threads : {1, 2}) {
    fast::FastSimulator every(make_grid(20), p, threads), never(make_grid(20), p, threads);
    every.set_layout_fraction(0);
    never.set_layout_fraction(-1);
    long splits = 0, restores = 0;
    for (int f = 0; f < 90; ++f) {
      const StepEvents a = every.step(), b = never.step();
      ASSERT_EQ(a.splits, b.splits) << "frame " << f;
      ASSERT_EQ(a.restores, b.restores) << "frame " << f;
      splits += a.splits;
      restores += a.restores;
      ASSERT_EQ(every.check_topology(), "") << "frame " << f;
    }
    EXPECT_GT(splits, 300);
    EXPECT_GT(restores, 30);
    EXPECT_TRUE(same_snapshot(every.snapshot(), never.snapshot())) << threads << " threads";
    // The layout did move slots: logical ids are no longer the identity.
    int moved = 0;
    for (int v = 0; v < every.topology().V.size(); ++v) moved += every.topology().V.lid[v] != v;
    EXPECT_GT(moved, every.topology().V.size() / 2);
  }
}

// One relayout of a crumpled state (default approximate implicit method): the interface sees
// the same state, forces, normals and decisions, bit for bit; the next step agrees to float
// round-off (only the momentum correction's summation order changed); neighbours are stored
// much closer together than before.
TEST(Layout, OneRelayoutKeepsTheStateAndBringsNeighboursTogether) {
  Params p;
  fast::FastSimulator sim(make_grid(24), p, 1);
  sim.set_layout_fraction(-1);
  for (int f = 0; f < 60; ++f) sim.step();
  fast::FastSimulator moved(sim);
  const double before = mean_slot_distance(moved.topology());
  moved.run_pass(fast::Pass::Layout);
  ASSERT_EQ(moved.check_topology(), "");
  const double after = mean_slot_distance(moved.topology());
  RecordProperty("slot_distance_before", std::to_string(before));
  RecordProperty("slot_distance_after", std::to_string(after));
  EXPECT_LT(after, 0.5 * before);
  EXPECT_TRUE(same_snapshot(sim.snapshot(), moved.snapshot()));
  EXPECT_EQ(sim.forces(), moved.forces());
  EXPECT_EQ(sim.normals(), moved.normals());
  const auto da = sim.decide(), db = moved.decide();
  ASSERT_EQ(da.size(), db.size());
  int differ = 0;
  for (std::size_t e = 0; e < da.size(); ++e) differ += da[e].kind != db[e].kind;
  EXPECT_EQ(differ, 0);
  // Splits and restores through the interface use logical ids on both.
  int split_id = -1;
  for (std::size_t e = 0; e < da.size() && split_id < 0; ++e)
    if (sim.snapshot().edges[e].breakable && !sim.snapshot().edges[e].auxiliary) split_id = int(e);
  ASSERT_GE(split_id, 0);
  fast::FastSimulator s1(sim), s2(moved);
  ASSERT_EQ(s1.split(split_id), s2.split(split_id));
  EXPECT_TRUE(same_snapshot(s1.snapshot(), s2.snapshot()));
  ASSERT_TRUE(s2.restore(split_id));
  ASSERT_TRUE(s1.restore(split_id));
  EXPECT_TRUE(same_snapshot(s1.snapshot(), s2.snapshot()));
  // The next step.
  sim.step();
  moved.step();
  const Snapshot a = sim.snapshot(), b = moved.snapshot();
  ASSERT_EQ(a.position.size(), b.position.size());
  double worst = 0;
  for (std::size_t v = 0; v < a.position.size(); ++v)
    for (int d = 0; d < 3; ++d) worst = std::max(worst, std::abs(a.position[v][d] - b.position[v][d]));
  EXPECT_LT(worst, 1e-6);
}

// Splits applied in parallel rounds of vertex-disjoint events against the same splits applied
// one after the other in event order: bit-identical states through a crumple with thousands of
// splits, on one thread (rounds run as plain loops) and on two (rounds in parallel).
TEST(FastTopology, ParallelSplitRoundsEqualSerialSplits) {
  Params p;
  for (int threads : {1, 2}) {
    fast::FastSimulator rounds(make_grid(24), p, threads), serial(make_grid(24), p, threads);
    serial.set_serial_splits(true);
    long splits = 0;
    for (int f = 0; f < 90; ++f) {
      const StepEvents a = rounds.step(), b = serial.step();
      ASSERT_EQ(a.splits, b.splits) << "frame " << f;
      ASSERT_EQ(a.restores, b.restores) << "frame " << f;
      splits += a.splits;
    }
    ASSERT_EQ(rounds.check_topology(), "");
    EXPECT_GT(splits, 800);
    EXPECT_TRUE(same_snapshot(rounds.snapshot(), serial.snapshot())) << threads << " threads";
  }
}

}  // namespace
}  // namespace crumple::test
