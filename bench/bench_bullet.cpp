// BM_Frame/bullet/1/<N>: the Bullet peer (bullet_sheet.h): one 1/60 s frame of a btSoftBody
// cloth patch over the same N x N grid of the unit square, hanging from two pinned corners.
// A different method: position-based constraint projection with a fixed topology, no fracture
// and no sphere; it answers "what does a common soft-body library cost per frame at this size".
//
// Preparation: kPrepFrames frames are stepped first (the sheet is falling and swinging).
// Comparable work per iteration: a Bullet world cannot be cloned, so the sheet simply keeps
// going; that is comparable work because a Bullet soft-body step costs the same whatever the
// state: fixed node/link counts, fixed iteration counts (piterations, no velocity/drift
// solver iterations by default), no contacts (no rigid bodies, self-collision off by default).
// Timing as in bench_frame.cpp: manual time over a batch of frames_per_iteration(N) frames.
// Boundedness: after every batch (untimed) every node coordinate must be finite and within 1e3,
// else the benchmark reports an error instead of a time.
#include <LinearMath/btScalar.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "bench_common.h"
#include "bullet_sheet.h"

namespace crumple::bench {
namespace {

/// Bullet's position-solver iterations: the smallest count that keeps the sheet bounded at
/// every size benchmarked, one value for all sizes so the sizes compare. Measured with
/// crumple_bullet_probe (frames until a coordinate passes 1e3): piterations = 1 leaves the bound
/// at frame ~77 for N = 64, 128, 256 and at frame 545 for N = 32; 2 stays bounded for 5000
/// frames at N <= 128 but leaves it at frame 291 for N = 256; 3 stays bounded at N = 256 (2000
/// frames) and N = 512 (400 frames). Bounded is not taut: with so few iterations a fine sheet
/// sags far (largest |coordinate| seen: with 2, 2.9 at N = 32, 9.8 at 64, 42 at 128; with 3,
/// 128 at 256 and 206 at 512), since one projection pass moves information one link.
constexpr int kPiterations = 3;
/// Largest N benchmarked: a frame must cost under ~2 s; with piterations = 3 a frame costs
/// ~0.5 s at N = 512 and ~4.5 s at N = 1024, so N = 1024 is left out.
constexpr int kMaxN = 512;
constexpr int kPrepFrames = 30;

struct Sheet {
  std::unique_ptr<BulletSheet> sheet;
  std::string error;
};

Sheet& prepared(int n) {
  static std::map<int, Sheet> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  Sheet& s = cache[n];
  const Clock::time_point t0 = Clock::now();
  s.sheet = std::make_unique<BulletSheet>(n, kPiterations);
  for (int f = 1; f <= kPrepFrames; ++f) s.sheet->frame();
  if (!s.sheet->bounded())
    s.error = "Bullet sheet unbounded after " + std::to_string(kPrepFrames) + " preparation frames";
  std::fprintf(stderr, "crumple_bench: prepared bullet, N = %d in %.1f s%s%s\n", n,
               seconds_between(t0, Clock::now()), s.error.empty() ? "" : ": ", s.error.c_str());
  return s;
}

void BM_Bullet(benchmark::State& state, int n) {
  Sheet& s = prepared(n);
  if (!s.error.empty()) {
    state.SkipWithError(s.error.c_str());
    return;
  }
  const int k = frames_per_iteration(n);
  FrameTally tally;
  for (auto _ : state) {
    const Clock::time_point t0 = Clock::now();
    for (int f = 0; f < k; ++f) s.sheet->frame();
    const Clock::time_point t1 = Clock::now();
    tally.add_batch(state, seconds_between(t0, t1), k);
    if (!s.sheet->bounded()) {  // untimed check of every node
      s.error = "Bullet sheet unbounded: a node coordinate is past 1e3 or not finite";
      state.SkipWithError(s.error.c_str());
      break;
    }
  }
  if (!s.error.empty()) return;
  tally.set_counters(state, double(s.sheet->nodes()), double(s.sheet->links()));
  state.counters["piterations"] = double(s.sheet->piterations());
}

void register_bullet_benchmarks() {
  for (int n : kSizes) {
    if (n > kMaxN) continue;
    const std::string name = "BM_Frame/bullet/1/" + std::to_string(n);
    benchmark::RegisterBenchmark(name.c_str(), BM_Bullet, n)->Unit(benchmark::kMillisecond)->UseManualTime();
  }
  benchmark::AddCustomContext("bullet_piterations", std::to_string(kPiterations));
  benchmark::AddCustomContext("bullet_version", std::to_string(btGetVersion() / 100) + "." + std::to_string(btGetVersion() % 100) +
                                                    (sizeof(btScalar) == 8 ? " (double)" : " (float)"));
}

}  // namespace

CRUMPLE_BENCH_REGISTRAR(register_bullet_benchmarks);

}  // namespace crumple::bench
