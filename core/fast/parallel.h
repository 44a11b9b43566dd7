// How the fast backend runs a kernel over [0, n): a plain loop on one thread, or
// tbb::parallel_for in the backend's own task_arena (its thread count is the backend's, never
// left to whatever TBB would pick). Reductions use fixed blocks, summed in block order, so the
// result does not depend on the thread count.
#pragma once

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_invoke.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "fast/aligned.h"

// ThreadSanitizer cannot see the synchronization inside libtbb (not built with it): that a
// parallel_for's chunks (or a parallel_invoke's jobs) start after what the caller did before
// it, and end before it returns. Without telling it, it reports the caller's next writes as
// races with finished chunks (seen with many short loops in a row). These annotations state
// exactly that guarantee, and nothing between concurrent chunks or jobs, so real races between
// them are still reported.
#if defined(__SANITIZE_THREAD__)
#include <sanitizer/tsan_interface.h>
#define CRUMPLE_TSAN_RELEASE(p) __tsan_release(p)
#define CRUMPLE_TSAN_ACQUIRE(p) __tsan_acquire(p)
#else
#define CRUMPLE_TSAN_RELEASE(p) ((void)(p))
#define CRUMPLE_TSAN_ACQUIRE(p) ((void)(p))
#endif

namespace crumple::fast {

/// The grain of a loop over blocks already cut to a chunk's worth of work each (fixed-block
/// reductions and scans): one block per chunk, so any thread may take any block.
constexpr int kBlockGrain = 1;
/// Minimum items per parallel chunk of a per-element pass of the step (forces, sweeps, XPBD's
/// colours, the manipulators): large enough that a chunk's scheduling is small beside its work,
/// small enough that a mid-size sheet gives every thread several chunks.
constexpr int kPassGrain = 2048;
/// Fixed block of the step's deterministic reductions: fixed, so the sums do not depend on the
/// thread count; large, so the serial sum of the block results stays short.
constexpr int kReduceBlock = 8192;

class Parallel {
 public:
  /// threads >= 1: a task_arena of that many (1: plain loops, no TBB at all). threads == 0:
  /// no arena of its own; parallel_for runs in whatever arena the caller is in, so an engine
  /// decides the threads (the embedding API's "caller's arena"). Negative counts as 1.
  explicit Parallel(int threads) : threads_(threads < 0 ? 1 : threads) {
    if (threads_ > 1) arena_ = std::make_unique<tbb::task_arena>(threads_);
  }
  Parallel(const Parallel& o) : Parallel(o.threads_) {}
  Parallel& operator=(const Parallel& o) {
    if (this != &o) *this = Parallel(o.threads_);
    return *this;
  }
  Parallel(Parallel&&) = default;
  Parallel& operator=(Parallel&&) = default;

  /// Worker count: the arena's own, or the caller's arena's concurrency (threads == 0).
  int threads() const { return threads_ > 0 ? threads_ : tbb::this_task_arena::max_concurrency(); }

  /// Runs kernel(begin, end) over [0, n) in chunks of at least `grain`.
  template <class Kernel>
  void run(int n, int grain, const Kernel& kernel) const {
    if (n <= 0) return;
    if (threads_ == 1 || n <= grain) {
      kernel(0, n);
      return;
    }
    int before = 0, after = 0;  // addresses for the annotations above
    CRUMPLE_TSAN_RELEASE(&before);
    in_arena([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, grain), [&](const tbb::blocked_range<int>& r) {
        CRUMPLE_TSAN_ACQUIRE(&before);
        kernel(r.begin(), r.end());
        CRUMPLE_TSAN_RELEASE(&after);
      });
    });
    CRUMPLE_TSAN_ACQUIRE(&after);
  }

  /// run() for a vectorized kernel: every chunk starts at a multiple of kLanes items, so each
  /// item is computed in the same vector lane of the same code path (vector body, vector
  /// epilogue or scalar tail) on any thread count. The compiler may contract a*b+c into an FMA
  /// differently in those paths; aligned chunks make per-item results independent of that.
  static constexpr int kLanes = 64;
  template <class Kernel>
  void run_lanes(int n, int grain, const Kernel& kernel) const {
    const int blocks = (n + kLanes - 1) / kLanes;
    run(blocks, std::max(1, grain / kLanes), [&](int b0, int b1) { kernel(b0 * kLanes, std::min(n, b1 * kLanes)); });
  }

  /// Runs first() and second(), which may run at once and in either order (on one thread: first,
  /// then second): for two serial jobs that touch disjoint data, so that one core need not wait
  /// while the other runs a serial phase. A parallel loop inside either job runs on the threads
  /// the other leaves. Returns when both are done.
  template <class First, class Second>
  void invoke(const First& first, const Second& second) const {
    if (threads_ == 1) {
      first();
      second();
      return;
    }
    int before = 0, after_first = 0, after_second = 0;  // addresses for the annotations above
    CRUMPLE_TSAN_RELEASE(&before);
    in_arena([&] {
      tbb::parallel_invoke(
          [&] {
            CRUMPLE_TSAN_ACQUIRE(&before);
            first();
            CRUMPLE_TSAN_RELEASE(&after_first);
          },
          [&] {
            CRUMPLE_TSAN_ACQUIRE(&before);
            second();
            CRUMPLE_TSAN_RELEASE(&after_second);
          });
    });
    CRUMPLE_TSAN_ACQUIRE(&after_first);
    CRUMPLE_TSAN_ACQUIRE(&after_second);
  }

  /// How many fixed blocks of `block` items cover [0, n).
  static int blocks_of(int n, int block) { return (n + block - 1) / block; }

  /// Runs each(b, begin, end) for every fixed block b = [begin, end) of `block` items of
  /// [0, n), any block on any thread: per-block results combined in block order give the same
  /// bits on any thread count.
  template <class Each>
  void run_blocks(int n, int block, const Each& each) const {
    run(blocks_of(n, block), kBlockGrain, [&](int b0, int b1) {
      for (int b = b0; b < b1; ++b) each(b, b * block, std::min(n, (b + 1) * block));
    });
  }

  /// Sums partial(begin, end, out[K]) over fixed blocks of `block` items, in block order.
  template <int K, class Partial>
  void sum(int n, int block, const Partial& partial, double out[K]) const {
    const int blocks = blocks_of(n, block);
    std::vector<double> parts(K * std::size_t(blocks), 0.0);
    run_blocks(n, block, [&](int b, int begin, int end) { partial(begin, end, &parts[K * std::size_t(b)]); });
    std::fill(out, out + K, 0.0);
    for (int b = 0; b < blocks; ++b)
      for (int d = 0; d < K; ++d) out[d] += parts[K * std::size_t(b) + d];
  }

 private:
  /// Runs work() in the backend's arena (already inside it: at once), or in the caller's.
  template <class Work>
  void in_arena(const Work& work) const {
    if (arena_)
      arena_->execute(work);
    else
      work();
  }

  int threads_ = 1;
  std::unique_ptr<tbb::task_arena> arena_;
};

/// Faults in the ranges (touch_pages) on all of par's threads, a huge page at a time: a first
/// touch is the kernel's work (zeroing the page; on a VM often the host's too) on the touching
/// core, so two threads fault in about twice the pages in the time of one. No chunk spans two
/// huge pages, so no two threads fault on one huge page of a huge-page array (the second would
/// wait for it). Ranges within one huge page are touched inline: not worth a parallel loop. (A
/// few bytes in each of several huge pages are worth one: each first touch maps a whole huge
/// page.)
inline void touch_pages(const Parallel& par, const std::vector<ColdRange>& ranges) {
  std::vector<ColdRange> chunks;
  for (const ColdRange& r : ranges)
    for (char* p = r.begin; p < r.end;) {
      const std::uintptr_t boundary = (reinterpret_cast<std::uintptr_t>(p) / kHugePage + 1) * kHugePage;
      char* const end = std::min(r.end, reinterpret_cast<char*>(boundary));
      chunks.push_back({p, end});
      p = end;
    }
  if (chunks.size() < 2) {
    for (const ColdRange& c : chunks) touch_pages(c.begin, c.end);
    return;
  }
  par.run(int(chunks.size()), kBlockGrain, [&](int begin, int end) {
    for (int k = begin; k < end; ++k) touch_pages(chunks[std::size_t(k)].begin, chunks[std::size_t(k)].end);
  });
}

}  // namespace crumple::fast
