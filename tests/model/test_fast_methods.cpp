// The fast backend's axial Jacobian and XPBD (issue 12) as its parallel machinery must run them:
// bit-identical on any thread count, and XPBD's projection order (constraint_colors.h) a function
// of the logical mesh, so that where the slots lie changes nothing. Their one-step equations are
// checked against hand computations in test_implicit.cpp on both backends.
#include <set>

#include "fast/fast_sim.h"
#include "support/fixtures.h"

namespace crumple::test {
namespace {

struct Method {
  const char* name;
  Params params;
};

// The free scene: the sheet starts squeezed (Params::squeeze), so it breaks from the first steps.
std::vector<Method> methods() {
  Params axial;
  axial.scene = Scene::Free;
  axial.jacobian = Jacobian::Axial;
  axial.viscosity = 1e4 / 60;
  axial.sweeps = 2;
  Params xpbd;
  xpbd.scene = Scene::Free;
  xpbd.integrator = Integrator::Xpbd;
  xpbd.viscosity = 1e4 / 60;
  xpbd.substeps = 4;
  return {{"axial", axial}, {"xpbd", xpbd}};
}

// A 128 x 128 sheet: every per-vertex pass has several chunks of kPassGrain, and XPBD's large
// colours (up to ~8,500 springs of its 14) are parallel loops too. Three frames with fracture on 1, 2 and 4
// threads. Catches a race in a pass (a colour whose springs share a
// vertex; a sweep that reads the buffer it writes) or a sum whose order follows the chunks.
TEST(FastMethods, BitIdenticalOnOneTwoAndFourThreads) {
  for (const Method& m : methods()) {
    std::vector<Snapshot> ends;
    long splits = 0;
    for (int threads : {1, 2, 4}) {
      fast::FastSimulator sim(make_grid(128), m.params, threads);
      for (int f = 0; f < 3 * m.params.substeps; ++f) splits += sim.step().splits;
      EXPECT_EQ(sim.check_topology(), "") << m.name;
      ends.push_back(sim.snapshot());
    }
    EXPECT_GT(splits, 0) << m.name;  // the colouring was renewed after events
    for (size_t k = 1; k < ends.size(); ++k) EXPECT_TRUE(same_snapshot(ends[0], ends[k])) << m.name << " " << k;
  }
}

// Relayout after every step and never: the same logical state, bit for bit, through a crumple
// with splits and restores (without viscosity there is no momentum correction, whose block sums
// follow the slots). Catches an XPBD order taken from slots rather than logical ids.
TEST(FastMethods, XpbdDoesNotDependOnTheSlotOrder) {
  Params p = methods()[1].params;
  p.viscosity = 0;
  auto run = [&](double fraction) {  // one simulator alive at a time (see test_fast_internals)
    fast::FastSimulator sim(make_grid(20), p, 2);
    sim.set_layout_fraction(fraction);
    for (int f = 0; f < 60 * p.substeps; ++f) sim.step();
    return sim.snapshot();
  };
  const Snapshot every = run(0), never = run(-1);
  EXPECT_GT(every.mass.size(), 20u * 20u + 50);  // it split
  EXPECT_TRUE(same_snapshot(every, never));
}

// The colouring itself: springs of one colour share no vertex, every live spring has one colour,
// and each takes the smallest colour free of the springs of smaller id at its endpoints.
TEST(FastMethods, ConstraintColorsAreGreedyInIdOrder) {
  Params p = methods()[1].params;
  fast::FastSimulator sim(make_grid(12), p, 1);
  for (int f = 0; f < 40; ++f) sim.step();  // splits and restores: auxiliary edges, new ids
  const fast::Topology& m = sim.topology();
  fast::ConstraintColors colors;
  colors.update(m);
  const std::vector<std::int32_t>& color = colors.color_of_slot();
  int listed = 0;
  for (int c = 0; c < colors.colors(); ++c) {
    std::set<int> ends;
    for (int k = 0; k < colors.count(c); ++k) {
      const int e = colors.slots(c)[k];
      EXPECT_EQ(color[size_t(e)], c);
      EXPECT_TRUE(ends.insert(m.E[e].a).second && ends.insert(m.E[e].b).second) << "colour " << c;
      ++listed;
    }
  }
  int live = 0;
  for (int id = 0; id < m.E.size(); ++id) {
    const int e = m.E.phys[id];
    if (!(m.E[e].flags & fast::kAlive)) continue;
    ++live;
    std::set<int> taken;
    for (int jd = 0; jd < id; ++jd) {
      const int o = m.E.phys[jd];
      if (!(m.E[o].flags & fast::kAlive)) continue;
      if (m.E[o].a == m.E[e].a || m.E[o].a == m.E[e].b || m.E[o].b == m.E[e].a || m.E[o].b == m.E[e].b)
        taken.insert(color[size_t(o)]);
    }
    int smallest = 0;
    while (taken.count(smallest)) ++smallest;
    EXPECT_EQ(color[size_t(e)], smallest) << "edge id " << id;
  }
  EXPECT_EQ(listed, live);
  EXPECT_GT(live, 11 * 12 * 2 + 11 * 11);  // more than the grid's: it split
}

}  // namespace
}  // namespace crumple::test
