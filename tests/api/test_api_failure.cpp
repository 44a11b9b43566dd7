// A step that fails part way. Its own executable: it replaces the global operator new and delete
// with versions that can be told to throw std::bad_alloc at one chosen allocation, so that
// running out of memory can be tested at every allocation of a frame.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "crumple/crumple.h"
#include "../support/fixed_step.h"

namespace {
std::atomic<std::uint64_t> g_allocations{0};  ///< operator new calls so far
std::atomic<std::uint64_t> g_fail_at{0};      ///< the call that throws (0: none)
std::atomic<bool> g_fail_all{false};          ///< every call throws (no memory left at all)

void* allocate(std::size_t size, std::size_t align) {
  if (++g_allocations == g_fail_at.load() || g_fail_all) throw std::bad_alloc();
  void* p = nullptr;
  if (align <= alignof(std::max_align_t)) {
    p = std::malloc(size ? size : 1);
  } else if (posix_memalign(&p, align, size ? size : 1) != 0) {
    p = nullptr;
  }
  if (!p) throw std::bad_alloc();
  return p;
}
/// Arms the failure of allocation `call` (a count of g_allocations) for its scope, whatever the
/// scope throws.
struct FailAt {
  explicit FailAt(std::uint64_t call) { g_fail_at = call; }
  ~FailAt() { g_fail_at = 0; }
  FailAt(const FailAt&) = delete;
  FailAt& operator=(const FailAt&) = delete;
};

/// Disarms the failure of every allocation (set by the code under test) when its scope ends.
struct FailAll {
  FailAll() = default;
  ~FailAll() { g_fail_all = false; }
  FailAll(const FailAll&) = delete;
  FailAll& operator=(const FailAll&) = delete;
};

void* allocate_or_null(std::size_t size, std::size_t align) noexcept {
  try {
    return allocate(size, align);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
}  // namespace

// Every form, so that no allocation or release reaches another runtime's operator (the
// sanitizers' among them) and each pointer is freed by the allocator that made it.
void* operator new(std::size_t n) { return allocate(n, 0); }
void* operator new[](std::size_t n) { return allocate(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return allocate(n, std::size_t(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocate(n, std::size_t(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return allocate_or_null(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return allocate_or_null(n, 0); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_or_null(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_or_null(n, std::size_t(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace crumple {
namespace {

constexpr double kFrame = 1.0 / 60;

// The paper's crumple on a small grid, on one thread (plain loops: every allocation on the
// calling thread, in the same order on every run).
Sheet crumpling_sheet(const std::string& backend) {
  SheetDesc d;
  d.grid = 24;
  d.backend = backend;
  d.threads = 1;
  d.params = test::fixed_step_params();
  d.params.scene = Scene::Sphere;
  return Sheet::create(d);
}

struct Frame {
  int index;                  ///< 0-based
  std::uint64_t allocations;  ///< operator new calls inside its step()
};

// The frames of a crumple whose step() split or restored something and allocated.
std::vector<Frame> frames_with_events(const std::string& backend, int frames) {
  Sheet s = crumpling_sheet(backend);
  std::vector<Frame> out;
  for (int f = 0; f < frames; ++f) {
    const std::uint64_t before = g_allocations;
    const FrameEvents ev = s.step(kFrame);
    const std::uint64_t calls = g_allocations - before;
    if (ev.splits + ev.restores > 0 && calls > 0) out.push_back({f, calls});
  }
  return out;
}

class ApiFailure : public ::testing::TestWithParam<std::string> {};

// A step cannot undo the time steps and mesh events it has already applied, so a step() that
// throws after it began stepping (here std::bad_alloc, at each allocation of a frame with mesh
// events in turn) must leave a sheet that refuses every later step() rather than one that steps
// a half-edited mesh, and that will not write that mesh as an OBJ. Catches a step() that forgets
// its failure: the next call then steps on (and may crash on the fast backend's half-taken ids).
TEST_P(ApiFailure, AStepThatFailsPartWayRefusesEveryLaterStep) {
  const std::vector<Frame> frames = frames_with_events(GetParam(), 60);
  ASSERT_GE(frames.size(), 2u) << "no frame of the crumple had mesh events and allocations";
  int failed = 0;
  for (const Frame& frame : {frames.front(), frames[frames.size() / 2]}) {
    for (std::uint64_t k = 1; k <= frame.allocations && !HasFailure(); ++k) {
      Sheet s = crumpling_sheet(GetParam());
      for (int f = 0; f < frame.index; ++f) s.step(kFrame);
      bool threw = false;
      {
        const FailAt fail(g_allocations + k);  // nothing else allocates until the step's k-th call
        try {
          s.step(kFrame);
        } catch (const std::bad_alloc&) {
          threw = true;
        }
      }
      ASSERT_TRUE(threw) << "frame " << frame.index << ", allocation " << k;
      ++failed;
      EXPECT_THROW(s.step(kFrame), UnstableError) << "frame " << frame.index << ", allocation " << k;
      const std::string error = s.try_step(kFrame);
      EXPECT_NE(error.find("a step failed part way"), std::string::npos) << error;
      EXPECT_EQ(error.find('\n'), std::string::npos) << error;
      std::FILE* obj = std::tmpfile();
      ASSERT_NE(obj, nullptr);
      EXPECT_THROW(s.write_obj(obj), Error);  // the backend's mesh may be half edited
      std::fclose(obj);
    }
  }
  EXPECT_GT(failed, 1);
}

// The event callback is the caller's code and may throw anything, std::exception or not: the
// step() it throws from passes it on (try_step() returns it as its line), and the sheet refuses
// every later step(). Catches a step() that marks only std::exception failures (the int below
// then steps on) and a try_step() that lets a non-standard exception out (std::terminate).
TEST_P(ApiFailure, ACallbackThatThrowsLeavesTheSheetRefusingSteps) {
  for (const bool standard : {true, false}) {
    Sheet s = crumpling_sheet(GetParam());
    s.on_events([&](const StepEventIds&) {
      if (standard) throw std::runtime_error("the engine's callback failed");
      throw 7;
    });
    int frame = 0;
    std::string error;
    while (error.empty() && frame < 60) {
      ++frame;
      if (!standard) {
        error = s.try_step(kFrame);
        continue;
      }
      try {
        s.step(kFrame);
      } catch (const std::runtime_error& e) {
        error = e.what();
      }
    }
    const std::string part_way = "a step failed part way at frame " + std::to_string(frame);
    EXPECT_EQ(error, standard ? "the engine's callback failed" : part_way);
    EXPECT_EQ(s.try_step(kFrame), part_way + (standard ? ": the engine's callback failed" : ""));
    EXPECT_THROW(s.step(kFrame), UnstableError);
  }
}

// With no memory left at all from the callback's throw on, try_step() cannot copy the failure's
// line (a std::exception's what(), or the sheet's line for another type: both longer than a
// string's own buffer) and, being noexcept, must still return: "out of memory". The sheet's own
// line could not be built either, so later calls give its short form. Catches a try_step() whose
// copy of the line throws out of its handler (std::terminate ends the test binary) and a step()
// whose failed line build replaces the exception in flight.
TEST_P(ApiFailure, TryStepReturnsALineWhenNoMemoryIsLeft) {
  for (const bool standard : {true, false}) {
    Sheet s = crumpling_sheet(GetParam());
    const std::runtime_error failure(std::string(200, 'x'));  // copied without allocating (shared)
    bool armed = false;
    s.on_events([&](const StepEventIds&) {
      if (!armed) armed = true, g_fail_all = true;  // once: a later call must not fail gtest's own allocations
      if (standard) throw failure;
      throw 7;
    });
    std::string error;
    {
      const FailAll until_scope_end;  // disarmed however the loop ends
      for (int frame = 0; frame < 60 && error.empty(); ++frame) error = s.try_step(kFrame);
    }
    ASSERT_TRUE(armed) << "no frame of the crumple had mesh events";
    EXPECT_EQ(error, "out of memory");
    EXPECT_EQ(s.try_step(kFrame), "a step failed part way");
    EXPECT_THROW(s.step(kFrame), UnstableError);
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, ApiFailure, ::testing::Values("fast", "reference"));

}  // namespace
}  // namespace crumple
