// BM_FirstTouch/<pages>/<MiB>[/<threads>]: what the machine charges for the first touch of
// memory (a page fault: the kernel maps and zeroes a page), per 4 KiB, on 4 KiB pages ("small")
// and on transparent huge pages ("huge", advised as the fast backend advises its large arrays,
// fast/aligned.h), and on huge pages after the memory has sat free for kIdleSeconds ("idle").
// A simulation that grows (refinement's new elements, a relayout's scratch) pays this for every
// page it uses for the first time; on a virtual machine it can cost as much as streaming a few
// hundred KiB (docs/PERFORMANCE.md), which is why the fast backend reserves and faults in its
// room ahead (docs/DECISIONS.md D16).
// Each iteration maps kTouchMiB of fresh memory with mmap (not through an allocator, which may
// hand back memory it kept from the previous iteration, already faulted in), writes one byte a
// 4 KiB page (the timed part), and unmaps it. One thread, or (huge and idle, the name's
// /<threads> part) two through the fast backend's own parallel touch (touch_pages on a Parallel,
// parallel.h), as its steps fault in their growth room: a fault is the kernel's work on the
// faulting core, so two cores may fault memory in at up to twice the rate of one. The kernel
// hands an unmapped page back at the next map, still backed, so "small" and "huge" measure
// recycled memory. A virtual machine's kernel may report free memory to its host, which then
// discards it (Linux's free page reporting, a 2-second delay): the next touch of such memory
// faults on the host too, a 4 KiB at a time whatever the guest's page size, as growth into
// memory that has been free for a while does (docs/PERFORMANCE.md, "First touches of reported
// memory"). "idle" waits kIdleSeconds before each map, untimed; where the kernel reports nothing
// it measures what "huge" does. Reported: us_per_4kib (the mean time a 4 KiB of first touch
// costs) and the time per iteration (manual time).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "bench_common.h"
#include "fast/aligned.h"
#include "fast/parallel.h"

namespace crumple::bench {
namespace {

constexpr std::size_t kTouchMiB = 64;
constexpr std::size_t kTouchBytes = kTouchMiB << 20;
constexpr std::size_t kSmallPage = 4096;
constexpr std::size_t kMapped = kTouchBytes + fast::kHugePage;  ///< room to align kTouchBytes in
/// Past Linux's free page reporting delay (2 s), so that the memory the last iteration freed
/// has been reported before the next map.
constexpr unsigned kIdleSeconds = 3;
/// "idle" iterations a repetition: each waits kIdleSeconds.
constexpr int kIdleIterations = 2;

enum class Pages { Small, Huge, Idle };

/// kTouchBytes of fresh, untouched memory, huge-page aligned, advised for huge pages or against
/// them; `mapped` is what to unmap. p is null if the map failed.
struct Fresh {
  void* mapped = nullptr;
  char* p = nullptr;
};
Fresh map_fresh(Pages pages) {
  void* m = mmap(nullptr, kMapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) return {};
  const std::uintptr_t at = (reinterpret_cast<std::uintptr_t>(m) + fast::kHugePage - 1) / fast::kHugePage * fast::kHugePage;
  char* p = reinterpret_cast<char*>(at);
  madvise(p, kTouchBytes, pages == Pages::Small ? MADV_NOHUGEPAGE : MADV_HUGEPAGE);
  return {m, p};
}

void BM_FirstTouch(benchmark::State& state, Pages pages, int threads) {
  const fast::Parallel par(threads);
  par.run(threads, 1, [](int, int) {});  // the arena's threads created, untimed
  double seconds = 0;
  for (auto _ : state) {
    if (pages == Pages::Idle) sleep(kIdleSeconds);  // manual time: not timed
    const Fresh fresh = map_fresh(pages);
    if (!fresh.p) {
      state.SkipWithError("could not map memory to touch");
      return;
    }
    const Clock::time_point t0 = Clock::now();
    fast::touch_pages(par, {fast::ColdRange{fresh.p, fresh.p + kTouchBytes}});
    const double s = seconds_between(t0, Clock::now());
    state.SetIterationTime(s);
    seconds += s;
    munmap(fresh.mapped, kMapped);
  }
  const double kib4 = double(kTouchBytes / kSmallPage) * double(state.iterations());
  state.counters["us_per_4kib"] = 1e6 * seconds / kib4;
}

void register_first_touch_benchmarks() {
  for (const int threads : {1, 2})
    for (const auto& [label, pages] :
         {std::pair{"small", Pages::Small}, std::pair{"huge", Pages::Huge}, std::pair{"idle", Pages::Idle}}) {
      // The backend's parallel touches (touch_pages on a Parallel) are of arrays on huge pages,
      // but for small ones' ranges that happen to cross a 2 MiB boundary.
      if (threads > 1 && pages == Pages::Small) continue;
      // One thread keeps the name it had before threads were a parameter (the gate compares names).
      std::string name = std::string("BM_FirstTouch/") + label + "/" + std::to_string(kTouchMiB);
      if (threads > 1) name += '/' + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), BM_FirstTouch, pages, threads)
                    ->Unit(benchmark::kMillisecond)
                    ->UseManualTime();
      if (pages == Pages::Idle) b->Iterations(kIdleIterations);
    }
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_first_touch_benchmarks);

}  // namespace crumple::bench
