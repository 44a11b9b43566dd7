// The embedding API (crumple/crumple.h) as an engine meets it: creation from a grid or from its
// own arrays, one-line errors (the command's text) with nothing half-built, the fixed-step
// clock, the render views and the topology generation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <vector>

#include "crumple/crumple.h"
#include "../support/fixed_step.h"

namespace crumple {
namespace {

SheetDesc small_grid(const std::string& backend, int n = 16) {
  SheetDesc d;
  d.grid = n;
  d.backend = backend;
  d.threads = 1;
  d.params = test::fixed_step_params();
  return d;
}

// The command's error line for `args`, without its "crumple: error: " prefix and newline.
std::string command_error(const std::string& args) {
  const std::string cmd = std::string(CRUMPLE_EXE) + " " + args + " 2>&1 >/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (p && std::fgets(buf, sizeof buf, p)) out += buf;
  if (p) pclose(p);
  const std::string prefix = "crumple: error: ";
  if (out.rfind(prefix, 0) != 0) return "(no error line: " + out + ")";
  out = out.substr(prefix.size());
  if (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

class Api : public ::testing::TestWithParam<std::string> {};

TEST(ApiVersion, IsTheProjectVersion) { EXPECT_STREQ(version(), CRUMPLE_EXPECTED_VERSION); }

// Catches a bad parameter, mesh, backend or thread count that is not refused, or refused with
// other words than the command's; and a vertex budget below the mesh's vertices that is not
// refused (mutation checked: SheetAccess::create without that check).
TEST(ApiErrors, OneLineWithTheCommandsText) {
  SheetDesc d = small_grid("fast");
  d.params.phi = 1.5;
  std::string error;
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, command_error("run --phi 1.5"));
  d = small_grid("reference");
  d.params.max_vertices = 100;
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, command_error("run --grid 16 --max-vertices 100"));
  d = small_grid("fast", 1);
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, command_error("run --grid 1"));
  d = small_grid("gpu");
  EXPECT_THROW(Sheet::create(d), Error);
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, "unknown backend 'gpu'");
  d = small_grid("fast");
  d.threads = -1;
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, "threads must be in [0, 256] (0: the caller's arena)");
  const std::vector<float> x = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<std::uint32_t> t = {0, 1, 3};
  d = small_grid("reference");
  d.positions = x;
  d.triangles = t;
  EXPECT_FALSE(Sheet::try_create(d, error).has_value());
  EXPECT_EQ(error, "mesh: triangle 0 (0,1,3) refers to vertex 3 but the mesh has 3 vertices");
  EXPECT_EQ(std::count(error.begin(), error.end(), '\n'), 0);
}

// Catches an instability reported with other words or at another frame than the command's,
// or not reported (then a renderer would draw NaNs), and steps taken after it.
TEST(ApiErrors, UnstableLikeTheCommandAndThenRefused) {
  SheetDesc d = small_grid("reference", 10);
  d.params = paper_params();  // the command with --paper
  d.params.scene = Scene::Free;
  d.params.integrator = Integrator::Explicit;
  d.params.kappa = 1e6;
  Sheet s = Sheet::create(d);
  std::string error;
  for (int f = 0; f < 200 && error.empty(); ++f) error = s.try_step(d.params.frame_dt);
  EXPECT_EQ(error, command_error("run --paper --backend reference --grid 10 --scene free --integrator explicit --kappa 1e6 --frames 200"));
  const std::uint64_t steps = s.steps();
  EXPECT_EQ(s.try_step(d.params.frame_dt), error);
  EXPECT_EQ(s.steps(), steps);
}

// Catches a check made after the sheet has moved (a half-done step), or an unchecked bad id.
TEST_P(Api, BadManipulatorRefusedBeforeAnyStep) {
  Sheet s = Sheet::create(small_grid(GetParam()));
  const std::vector<float> before(s.positions().begin(), s.positions().end());
  s.manipulators().pins.push_back({s.vertex_ids(), {0, 0, 0}});
  try {
    s.step(1.0 / 60);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "pin 0: vertex 256 does not exist (the sheet has 256 vertex ids)");
  }
  EXPECT_EQ(s.steps(), 0u);
  EXPECT_TRUE(std::equal(before.begin(), before.end(), s.positions().begin()));
  s.manipulators().pins.clear();
  s.manipulators().spheres.push_back({{0, 0, 0}, 0});
  EXPECT_EQ(s.try_step(1.0 / 60), "sphere 0: needs a finite centre and a finite radius > 0");
  s.manipulators().spheres.clear();
  EXPECT_EQ(s.try_step(-1), "frame_dt must be a finite number in [0, 1] seconds");
  EXPECT_EQ(s.try_step(1.0 / 60), "");
  EXPECT_EQ(s.steps(), 1u);
}

// Catches a vertex or triangle copied out of order, or normals not packed per vertex id.
TEST_P(Api, CallersMeshKeepsItsIds) {
  // A unit square as two triangles, flat (no dome), in the caller's own arrays.
  const std::vector<float> x = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<std::uint32_t> t = {0, 1, 2, 0, 2, 3};
  SheetDesc d = small_grid(GetParam());
  d.positions = x;
  d.triangles = t;
  d.params.perturb = 0;
  Sheet s = Sheet::create(d);
  EXPECT_EQ(s.vertex_ids(), 4);
  EXPECT_EQ(s.live_vertices(), 4);
  EXPECT_EQ(s.live_triangles(), 2);
  EXPECT_TRUE(std::equal(x.begin(), x.end(), s.positions().begin(), s.positions().end()));
  EXPECT_TRUE(std::equal(t.begin(), t.end(), s.triangles().begin(), s.triangles().end()));
  for (int k = 0; k < 4; ++k) EXPECT_FLOAT_EQ(s.normals()[3 * k + 2], 1.0f) << k;
}

// A resident sheet (SheetDesc::resident: its reserve faulted in at creation) steps bit for bit
// as one that is not, through splits and restores. Catches a make_resident that writes elements
// rather than room ahead of them.
TEST_P(Api, AResidentSheetStepsAsAnother) {
  SheetDesc d = small_grid(GetParam(), 24);
  d.params = paper_params();
  SheetDesc r = d;
  r.resident = true;
  Sheet a = Sheet::create(d), b = Sheet::create(r);
  int events = 0;
  for (int f = 0; f < 90; ++f) {
    const FrameEvents ea = a.step(1.0 / 60), eb = b.step(1.0 / 60);
    ASSERT_EQ(ea.splits, eb.splits) << f;
    ASSERT_EQ(ea.restores, eb.restores) << f;
    events += ea.splits + ea.restores;
  }
  EXPECT_GT(events, 0);
  ASSERT_EQ(a.vertex_ids(), b.vertex_ids());
  EXPECT_TRUE(std::equal(a.positions().begin(), a.positions().end(), b.positions().begin(), b.positions().end()));
}

// Catches a clock that rounds frame_dt into h differently from call to call (a varying step
// count at a constant frame rate) or drops the remainder of a short frame.
TEST_P(Api, FixedStepsWithTheRemainderCarried) {
  SheetDesc d = small_grid(GetParam());
  d.params.substeps = 3;
  Sheet s = Sheet::create(d);
  for (int f = 1; f <= 10; ++f) EXPECT_EQ(s.step(1.0 / 60).steps, 3) << f;
  EXPECT_EQ(s.step(1.0 / 360).steps, 0);  // half a step owed
  EXPECT_EQ(s.step(1.0 / 360).steps, 1);
  EXPECT_EQ(s.step(0).steps, 0);
  EXPECT_EQ(s.steps(), 31u);
  EXPECT_NEAR(s.time(), 31.0 / 180, 1e-12);
}

// Catches a generation that moves without a topology change (renderers re-uploading every
// frame), one that misses a change, stale triangles, and live counts that disagree with them.
TEST_P(Api, GenerationChangesExactlyWithTheTopology) {
  SheetDesc d = small_grid(GetParam(), 24);
  d.params.scene = Scene::Sphere;  // the paper's crumple: splits and restores within 90 frames
  Sheet s = Sheet::create(d);
  int changes = 0;
  for (int f = 0; f < 90; ++f) {
    const std::uint64_t gen = s.topology_generation();
    const std::vector<std::uint32_t> tris(s.triangles().begin(), s.triangles().end());
    const FrameEvents ev = s.step(1.0 / 60);
    EXPECT_EQ(ev.topology_changed, ev.splits + ev.restores > 0);
    EXPECT_EQ(s.topology_generation(), gen + (ev.topology_changed ? 1 : 0)) << f;
    if (!ev.topology_changed) {
      EXPECT_TRUE(std::equal(tris.begin(), tris.end(), s.triangles().begin(), s.triangles().end())) << f;
    }
    changes += ev.topology_changed;
    const std::set<std::uint32_t> used(s.triangles().begin(), s.triangles().end());
    ASSERT_EQ(int(used.size()), s.live_vertices()) << f;
    ASSERT_LT(int(*used.rbegin()), s.vertex_ids()) << f;
    ASSERT_EQ(s.live_triangles() * 3, int(s.triangles().size()));
  }
  EXPECT_GT(changes, 0) << "the scene never changed the topology: the test tests nothing";
  // Every normal of a live vertex has unit length.
  for (std::uint32_t v : std::set<std::uint32_t>(s.triangles().begin(), s.triangles().end())) {
    const float* n = &s.normals()[3 * v];
    ASSERT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-4f) << v;
  }
}

// Catches events whose ids do not add up to the counts step() reports, or ids out of order.
TEST_P(Api, EventCallbackIdsMatchTheCounts) {
  SheetDesc d = small_grid(GetParam(), 24);
  d.params.scene = Scene::Sphere;
  Sheet s = Sheet::create(d);
  long ids_split = 0, ids_restored = 0, calls = 0;
  s.on_events([&](const StepEventIds& e) {
    ++calls;
    EXPECT_EQ(e.step, s.steps());
    EXPECT_TRUE(std::is_sorted(e.split_edges.begin(), e.split_edges.end()));
    EXPECT_TRUE(std::is_sorted(e.restored_edges.begin(), e.restored_edges.end()));
    EXPECT_GT(e.split_edges.size() + e.restored_edges.size(), 0u);
    ids_split += long(e.split_edges.size());
    ids_restored += long(e.restored_edges.size());
  });
  long splits = 0, restores = 0;
  for (int f = 0; f < 90; ++f) {
    const FrameEvents ev = s.step(1.0 / 60);
    splits += ev.splits;
    restores += ev.restores;
  }
  EXPECT_GT(splits, 0);
  EXPECT_GT(calls, 0);
  EXPECT_EQ(ids_split, splits);
  EXPECT_EQ(ids_restored, restores);
}

INSTANTIATE_TEST_SUITE_P(Backends, Api, ::testing::Values("reference", "fast"));

}  // namespace
}  // namespace crumple
