// Manipulators (sim/manipulators.h) on every backend: what holds exactly at the end of a step
// (pins at their targets, vertices on a plane's side and outside a sphere), the grab force as
// defined, and bit-identical runs on 1, 2 and 4 threads and in the caller's oneTBB arena.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <set>
#include <vector>

#include "crumple/crumple.h"
#include "../support/fixed_step.h"
#include "sim/backends.h"

namespace crumple {
namespace {

class Manip : public ::testing::TestWithParam<std::string> {
 protected:
  // A 20 x 20 sheet with fracture on, falling under a gravity its springs can hang from.
  Sheet sheet(int threads = 1, double gravity = 2.0) const {
    SheetDesc d;
    d.grid = 20;
    d.backend = GetParam();
    d.threads = threads;
    d.params.gravity = gravity;
    return Sheet::create(d);
  }
  // Float positions are the fast backend's state; the reference's are rounded from double
  // (a few float ulps of coordinates near 1, relative to distances near 0.25).
  double tolerance() const { return GetParam() == "fast" ? 2e-6 : 1e-6; }
};

std::set<std::uint32_t> live(const Sheet& s) { return {s.triangles().begin(), s.triangles().end()}; }

double dot3(const float* x, const std::array<double, 3>& p, const std::array<double, 3>& n) {
  return (x[0] - p[0]) * n[0] + (x[1] - p[1]) * n[1] + (x[2] - p[2]) * n[2];
}

// Catches a pin applied before a later pass moves its vertex (the integration, the obstacles or
// the adapt pass), or one not applied: the pinned corner must sit at its target after every
// step, to the bit of the backend's float or double rounded to float.
TEST_P(Manip, PinnedVertexStaysExactlyAtItsTarget) {
  Sheet s = sheet();
  const int corner = s.nearest_vertex({0, 0, 0});
  ASSERT_EQ(corner, 0);
  const std::array<double, 3> target = {s.positions()[0], s.positions()[1], s.positions()[2]};
  s.manipulators().pins.push_back({corner, target});
  s.manipulators().spheres.push_back({{0.05, 0.05, -0.1}, 0.12});  // pushes right at the pin
  for (int f = 0; f < 60; ++f) {
    s.manipulators().spheres[0].center[2] += 0.004;
    s.step(1.0 / 60);
    for (int d = 0; d < 3; ++d) ASSERT_EQ(s.positions()[d], float(target[d])) << "frame " << f;
  }
  // The sheet did move (gravity), so the pin had something to hold.
  EXPECT_LT(s.positions()[3 * (s.vertex_ids() - 1) + 2], target[2] - 0.01);
}

// Catches a plane that lets vertices through (a sign error, a missing pass after the adapt
// pass's new vertices) or that is never reached (then the test would assert nothing).
TEST_P(Manip, TiltedPlaneKeepsEveryVertexOnItsSide) {
  Sheet s = sheet();
  const double r = 1 / std::sqrt(1.0 + 0.04);
  const KinematicPlane table{{0.5, 0.5, -0.05}, {0.2 * r, 0, r}};
  s.manipulators().planes.push_back(table);
  double closest = 1;
  for (int f = 0; f < 90; ++f) {
    s.step(1.0 / 60);
    for (std::uint32_t v : live(s)) {
      const double d = dot3(&s.positions()[3 * v], table.point, table.normal);
      ASSERT_GE(d, -tolerance()) << "vertex " << v << " frame " << f;
      closest = std::min(closest, d);
    }
  }
  EXPECT_LT(closest, 1e-4) << "the sheet never reached the plane";
}

// Catches a sphere that lets vertices in, or one applied with the scene sphere's sense (keeping
// vertices inside), or never touched.
TEST_P(Manip, SphereKeepsEveryVertexOutside) {
  Sheet s = sheet();
  s.manipulators().spheres.push_back({{0.5, 0.5, -0.3}, 0.25});
  double closest = 1;
  for (int f = 0; f < 60; ++f) {
    KinematicSphere& b = s.manipulators().spheres[0];
    b.center[2] += 0.01;  // rises through the falling sheet
    s.step(1.0 / 60);
    for (std::uint32_t v : live(s)) {
      const float* x = &s.positions()[3 * v];
      const double d = std::sqrt(std::pow(x[0] - b.center[0], 2) + std::pow(x[1] - b.center[1], 2) +
                                 std::pow(x[2] - b.center[2], 2));
      ASSERT_GE(d, b.radius * (1 - tolerance())) << "vertex " << v << " frame " << f;
      closest = std::min(closest, d - b.radius);
    }
  }
  EXPECT_LT(closest, 1e-4) << "the sheet never touched the sphere";
}

// Catches a grab force with a wrong sign, stiffness, damping or row term, or applied to
// another vertex: the test hook's total force with the grab minus the one without must be
// F = k (p - x - h v) / (1 + h^2 k / M), M = m + sum_e (h^2 kappa_e + h c_e) (sim/manipulators.h)
// on the grabbed vertex, and zero elsewhere; kappa_e [Eq 5] and c_e (D17) from the snapshot's
// masses. Without and with viscosity (the row's h c_e term).
TEST_P(Manip, GrabForceIsItsDefinition) {
  for (double viscosity : {0.0, 20.0}) {
    Params p = test::fixed_step_params();  // the approximate implicit row the force is defined by
    p.viscosity = viscosity;
    auto sim = make_simulator(GetParam(), make_grid(12), p, 1);
    for (int k = 0; k < 5; ++k) sim->step();  // some velocity
    const Snapshot s = sim->snapshot();
    const int v = 7;
    const Grab g{v, {0.3, 1.2, 0.4}, 2.0};
    const std::vector<Vec3d> f0 = sim->forces();
    Manipulators m;
    m.grabs.push_back(g);
    sim->set_manipulators(m);
    const std::vector<Vec3d> f1 = sim->forces();
    const double h = p.h(), k = g.stiffness;
    double row = s.mass[v];
    for (const EdgeView& e : s.edges)
      if (e.a == v || e.b == v) row += (h * h * p.kappa + h * p.viscosity) * (s.mass[e.a] + s.mass[e.b]);
    ASSERT_GT(row, 2 * s.mass[v]) << "the springs' part of the row is what the test is about";
    for (std::size_t u = 0; u < f0.size(); ++u) {
      for (int d = 0; d < 3; ++d) {
        const double want = u == std::size_t(v)
            ? k * (g.target[d] - s.position[v][d] - h * s.velocity[v][d]) / (1 + h * h * k / row) : 0.0;
        const double scale = std::abs(f0[u][d]) + std::abs(want);
        EXPECT_NEAR(f1[u][d] - f0[u][d], want, (GetParam() == "fast" ? 1e-6 : 1e-12) * scale + 1e-15)
            << "viscosity " << viscosity << " vertex " << u << " axis " << d;
      }
    }
  }
}

// Catches a grab that pushes away or does nothing: a dragged corner follows its target.
TEST_P(Manip, GrabbedCornerFollowsItsTarget) {
  Sheet s = sheet(1, 0.0);
  const int corner = s.nearest_vertex({1, 1, 0});
  const std::array<double, 3> target = {1.2, 1.2, 0.5};
  s.manipulators().grabs.push_back({corner, target, 5.0});
  auto gap = [&] {
    const float* x = &s.positions()[3 * corner];
    return std::sqrt(std::pow(x[0] - target[0], 2) + std::pow(x[1] - target[1], 2) + std::pow(x[2] - target[2], 2));
  };
  const double start = gap();
  for (int f = 0; f < 60; ++f) s.step(1.0 / 60);
  EXPECT_LT(gap(), 0.5 * start);
}

// Catches manipulator passes whose result depends on the thread count or on running in the
// caller's arena (threads = 0) rather than the sheet's own.
TEST_P(Manip, BitIdenticalOnAnyThreadsAndInTheCallersArena) {
  auto run = [&](int threads, int arena) {
    Sheet s = sheet(threads);
    Manipulators& m = s.manipulators();
    m.spheres.push_back({{0.5, 0.5, -0.3}, 0.25});
    m.planes.push_back({{0, 0, -0.2}, {0, 0, 1}});
    m.pins.push_back({0, {0, 0, 0.1}});
    m.grabs.push_back({s.nearest_vertex({1, 1, 0}), {1.2, 1.2, 0.5}, 5.0});
    auto frames = [&] {
      for (int f = 0; f < 60; ++f) {
        m.spheres[0].center[2] += 0.01;
        s.step(1.0 / 60);
      }
    };
    if (arena > 0) {
      tbb::task_arena a(arena);
      a.execute(frames);
    } else {
      frames();
    }
    return std::vector<float>(s.positions().begin(), s.positions().end());
  };
  const std::vector<float> one = run(1, 0);
  EXPECT_EQ(run(2, 0), one);
  EXPECT_EQ(run(4, 0), one);
  EXPECT_EQ(run(0, 2), one);
  EXPECT_EQ(run(0, 4), one);
}

INSTANTIATE_TEST_SUITE_P(Backends, Manip, ::testing::Values("reference", "fast"));

}  // namespace
}  // namespace crumple
