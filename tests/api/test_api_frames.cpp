// The embedding API's frames against the backend driven directly (sim/run.h, as the tests of
// the model drive it): --substeps auto chosen the same way, the same states, the same totals
// and OBJ, and the events of the frame that went unstable.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "crumple/crumple.h"
#include "../support/fixed_step.h"
#include "sim/backends.h"
#include "sim/run.h"

namespace crumple {
namespace {

class ApiFrames : public ::testing::TestWithParam<std::string> {};

constexpr double kFrame = 1.0 / 60;  // Params' frame_dt

// Symplectic Euler on a stiff sheet relaxing from a squeeze: unstable at one step per frame
// (ApiErrors.UnstableLikeTheCommandAndThenRefused), stable with the steps auto chooses.
Params stiff_params() {
  Params p;
  p.scene = Scene::Free;
  p.integrator = Integrator::Explicit;
  p.kappa = 1e6;
  return p;
}

SheetDesc stiff_desc(const std::string& backend, bool auto_substeps) {
  SheetDesc d;
  d.grid = 10;
  d.backend = backend;
  d.threads = 1;
  d.params = stiff_params();
  d.params.auto_substeps = auto_substeps;
  return d;
}

std::string obj_text(const std::function<void(std::FILE*)>& write) {
  char* data = nullptr;
  std::size_t size = 0;
  std::FILE* f = open_memstream(&data, &size);
  write(f);
  std::fclose(f);
  std::string text(data, size);
  std::free(data);
  return text;
}

// Catches an API that ignores params.auto_substeps (mutation checked: SheetAccess::adopt without
// its begin_block() call, so h stays frame_dt / substeps: the sheet goes unstable at the frame
// the control run does) or chooses the count on another state than run_frame does (mutation
// checked: take_step without its begin_block() call, the count of creation kept for good: the
// counts part from the directly driven backend's as fracture lightens vertices).
TEST_P(ApiFrames, AutoSubstepsAsTheCommandChoosesThem) {
  Sheet fixed = Sheet::create(stiff_desc(GetParam(), false));
  int unstable_at = 0;
  for (int f = 1; f <= 200 && unstable_at == 0; ++f)
    if (!fixed.try_step(kFrame).empty()) unstable_at = f;
  ASSERT_GT(unstable_at, 0) << "stable at one step per frame: the test tests nothing";

  const SheetDesc d = stiff_desc(GetParam(), true);
  Sheet sheet = Sheet::create(d);
  auto sim = make_simulator(d.backend, make_grid(d.grid), d.params, d.threads);
  int most = 0;
  for (int f = 1; f <= std::max(unstable_at + 10, 60); ++f) {
    FrameEvents ev;
    ASSERT_EQ(sheet.try_step(d.params.frame_dt, &ev), "") << f;
    const FrameStats want = run_frame(*sim, d.params, f);
    ASSERT_EQ(ev.steps, want.substeps) << f;
    most = std::max(most, ev.steps);
  }
  EXPECT_GT(most, 1);
  EXPECT_EQ(sheet.time(), sim->time());
  const Snapshot s = sim->snapshot();
  for (std::size_t k = 0; k < s.position.size(); ++k)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(sheet.positions()[3 * k + c], float(s.position[k][c])) << k;
}

// Catches a SheetStats field filled from another total (mutation checked: edges from
// Totals::auxiliary), stats not refreshed by step(), and an OBJ other than the command's.
TEST_P(ApiFrames, StatsAndObjAreTheBackendsOwn) {
  SheetDesc d;
  d.grid = 16;
  d.backend = GetParam();
  d.threads = 1;
  d.params = Params{};  // the sphere crumple: splits, restores and creases within 60 frames
  Sheet sheet = Sheet::create(d);
  auto sim = make_simulator(d.backend, make_grid(d.grid), d.params, d.threads);
  for (int f = 1; f <= 60; ++f) {
    sheet.step(d.params.frame_dt);
    const Totals t = run_frame(*sim, d.params, f).totals;
    const SheetStats& s = sheet.stats();
    ASSERT_EQ(s.vertices, t.vertices) << f;
    ASSERT_EQ(s.edges, t.edges) << f;
    ASSERT_EQ(s.triangles, t.triangles) << f;
    ASSERT_EQ(s.mass, t.mass) << f;
    ASSERT_EQ(s.momentum, t.momentum) << f;
    ASSERT_EQ(s.kinetic, t.kinetic) << f;
    ASSERT_EQ(s.max_strain, t.max_strain) << f;
  }
  ASSERT_GT(sim->totals().auxiliary, 0) << "no crease: the OBJ's l lines are untested";
  EXPECT_EQ(obj_text([&](std::FILE* f) { sheet.write_obj(f); }),
            obj_text([&](std::FILE* f) { write_snapshot_obj(f, sim->snapshot()); }));
}

// Catches a failing frame whose events are lost (the command writes its stats.csv row from
// them; mutation checked: try_step filling `events` only on success) and a refused call that
// is not an UnstableError or reports steps.
TEST_P(ApiFrames, UnstableFrameKeepsItsEvents) {
  Sheet sheet = Sheet::create(stiff_desc(GetParam(), false));
  FrameEvents ev;
  std::string error;
  for (int f = 1; f <= 200 && error.empty(); ++f) error = sheet.try_step(kFrame, &ev);
  ASSERT_NE(error, "");
  EXPECT_EQ(ev.steps, 1);
  try {
    sheet.step(kFrame);
    FAIL() << "a step after the instability was taken";
  } catch (const UnstableError& e) {
    EXPECT_EQ(e.what(), error);
    EXPECT_EQ(e.events().steps, 0);
  }
}

// Catches a steps_ms (stats.csv's step_ms) that times more than the steps (mutation checked:
// steps_ms set to the whole call's ms: a call that takes no step then reports a time) or that
// is not part of the call's time. Only zero and order are asserted, never a duration.
TEST_P(ApiFrames, StepsTimeIsPartOfTheCall) {
  SheetDesc d;
  d.grid = 16;
  d.backend = GetParam();
  d.threads = 1;
  d.params = test::fixed_step_params();
  d.params.substeps = 2;
  Sheet sheet = Sheet::create(d);
  FrameEvents ev = sheet.step(1.0 / 240);  // half a step owed: no step
  EXPECT_EQ(ev.steps, 0);
  EXPECT_EQ(ev.steps_ms, 0.0);
  ev = sheet.step(kFrame);
  EXPECT_EQ(ev.steps, 2);
  EXPECT_GT(ev.steps_ms, 0.0);
  EXPECT_LE(ev.steps_ms, ev.ms);
}

INSTANTIATE_TEST_SUITE_P(Backends, ApiFrames, ::testing::Values("reference", "fast"));

}  // namespace
}  // namespace crumple
