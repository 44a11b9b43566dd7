// The fast backend's internal machinery, which must not change what is simulated: the slot
// layout (core/fast/layout.h) changes only where things are stored; the parallel rounds of
// splits and waves of restores (split_rounds.h, restore_waves.h) give what one event after the
// other gives (serial_events.h); the wide rows (wide.h) add lane by lane as scalars do; the
// arrays keep their room when copied; vectorized kernels run in chunks aligned to lanes
// (parallel.h).
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "fast/fast_sim.h"
#include "fast/layout.h"
#include "fast/parallel.h"
#include "fast/radix.h"
#include "fast/wide.h"
#include "support/fixtures.h"

namespace crumple::test {
namespace {

// A row sum is the per-lane scalar sum, bit for bit: the gather's exactness rests on it.
TEST(Wide, RowArithmeticIsPerLaneScalarArithmetic) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1e3f, 1e3f);
  float a[16], b[16], c[16];
  for (int round = 0; round < 100; ++round) {
    for (int k = 0; k < 16; ++k) a[k] = u(rng), b[k] = u(rng), c[k] = u(rng);
    fast::Wide<16> sum = fast::Wide<16>::load(a);
    sum += fast::Wide<16>::load(b) * fast::Wide<16>::load(c);
    const fast::Wide<16> scaled = 0.5f * fast::Wide<16>::load(b);
    for (int k = 0; k < 16; ++k) {
      volatile float product = b[k] * c[k];  // rounded on its own, as the row's product is
      const float want = a[k] + product;
      // The row's multiply-add may be contracted to one fused rounding: accept either result.
      const float fused = std::fma(b[k], c[k], a[k]);
      EXPECT_TRUE(sum[k] == want || sum[k] == fused) << "lane " << k;
      EXPECT_EQ(scaled[k], 0.5f * b[k]) << "lane " << k;
    }
  }
  // Scaling by 1, -1 and 0 (the gather's role rows) is exact, and adding +0 keeps a sum.
  const fast::Wide<4> x{{3.25f, -7.5f, 1e-30f, 0.0f}}, signs{{1, -1, 0, 1}};
  const fast::Wide<4> y = x * signs;
  EXPECT_EQ(y[0], 3.25f);
  EXPECT_EQ(y[1], 7.5f);
  EXPECT_EQ(y[2], 0.0f);
  fast::Wide<4> acc = fast::Wide<4>::zero();
  acc += y;
  acc += fast::Wide<4>::zero() * x;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(acc[k], y[k]);
  const fast::Wide<4> d = x - signs;  // the gather's v_o - v, lane by lane
  for (int k = 0; k < 4; ++k) EXPECT_EQ(d[k], x[k] - signs[k]);
}

// A copy keeps the reserved room (a clone grows without reallocating, as the original does),
// and faulting the room in changes neither the size nor the elements.
TEST(Array, CopyKeepsRoomAndWarmingKeepsElements) {
  fast::Array<int> a;
  a.reserve_warm(1000);
  for (int k = 0; k < 10; ++k) a.push_back(k * k);
  const fast::Array<int> b(a);
  EXPECT_GE(b.capacity(), 1000u);
  ASSERT_EQ(b.size(), 10u);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(b[k], k * k);
  fast::Array<int> c;
  c = a;
  EXPECT_GE(c.capacity(), 1000u);
  c.resize(500);  // past the warmed eighth: the next part is touched
  c.keep_warm();
  EXPECT_EQ(c.size(), 500u);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(c[k], k * k);
  const int* before = c.data();
  c.resize(1000);
  EXPECT_EQ(c.data(), before);  // grew into its room, no reallocation
}


// Small arrays start on a cache line, large ones on a huge page (so that transparent huge pages
// can back them from their first byte), and both keep their elements through growth. Catches an
// allocation that loses the alignment the kernels' aligned loads assume, or a large array left
// on 4 KiB-aligned memory the kernel cannot give huge pages to.
TEST(Array, SmallArraysStartOnALineLargeOnesOnAHugePage) {
  auto offset = [](const void* p, std::size_t align) { return reinterpret_cast<std::uintptr_t>(p) % align; };
  for (std::size_t n : {std::size_t(1), std::size_t(100), fast::kHugePage / sizeof(float) - 1}) {
    fast::Array<float> small(n, 1.0f);
    EXPECT_EQ(offset(small.data(), 64), 0u) << n;
  }
  fast::Array<fast::Float4> large;
  large.reserve(fast::kHugePage / sizeof(fast::Float4) * 3);
  EXPECT_EQ(offset(large.data(), fast::kHugePage), 0u);
  for (int k = 0; k < 1000; ++k) large.push_back(fast::Float4{float(k), 0, 0, 1});
  large.reserve(large.capacity() * 2);  // reallocates: the elements move to another huge page
  EXPECT_EQ(offset(large.data(), fast::kHugePage), 0u);
  for (int k = 0; k < 1000; ++k) ASSERT_EQ(large[k].x, float(k));
}
// Scratch resized at alternating lengths keeps its buffer: resize_scratch at least doubles the
// room when it must grow. Catches a plain resize, which grows from the size (here 50 + 51) and
// would reallocate, and fault in a new buffer, at the next longer use.
TEST(Array, ScratchAtAlternatingLengthsKeepsItsBuffer) {
  std::vector<int> v(100);
  fast::resize_scratch(v, 50);
  fast::resize_scratch(v, 101);
  EXPECT_GE(v.capacity(), 200u);
  const int* buffer = v.data();
  fast::resize_scratch(v, 50);
  fast::resize_scratch(v, 190);
  EXPECT_EQ(v.data(), buffer);
  EXPECT_EQ(v.size(), 190u);
  fast::resize_scratch(v, 1000);  // past twice the room: exactly what is asked
  EXPECT_EQ(v.size(), 1000u);
  EXPECT_GE(v.capacity(), 1000u);
}

// A copy of the relayout's scratch (a clone's) has the original's room, so the clone's first
// relayout reallocates nothing the original's would not. Catches a member copied as a plain
// vector (room = size: every scratch vector reallocated and faulted in at the clone's first
// relayout) or left out of the copy.
TEST(Layout, ScratchCopyKeepsTheRoom) {
  fast::LayoutScratch a;
  a.reserve(1000, 3000, 2000, 2);
  a.key.resize(10);
  a.spare_springs.reserve(5000);
  a.spare_rows.reserve(700);
  const fast::LayoutScratch b(a);
  EXPECT_GE(b.vorder.capacity(), 1000u);
  EXPECT_GE(b.eorder.capacity(), 3000u);
  EXPECT_GE(b.tnew.capacity(), 2000u);
  EXPECT_GE(b.key.capacity(), 2000u);
  EXPECT_EQ(b.key.size(), 10u);
  EXPECT_GE(b.count.capacity(), 2u * 1001u);
  EXPECT_GE(b.spare_springs.capacity(), 5000u);
  EXPECT_GE(b.spare_rows.capacity(), 700u);
}

// LayoutScratch::claim_whole (FastSimulator::make_resident's part for the scratch) gives each
// array its room and keeps its elements: within a relayout the edges' order is read by the next
// phase. Catches a reserve that reallocates an array empty (a clear before it), which happens
// when an array lacks room: a scratch never reserved, as here, or a mesh past its reserve.
TEST(Layout, ClaimWholeKeepsTheScratchsElements) {
  const fast::FastSimulator sim(make_grid(16), Params{}, 1);
  fast::LayoutScratch s;
  s.eorder.resize(3);
  s.eorder[0] = 7, s.eorder[1] = 5, s.eorder[2] = 9;
  ASSERT_FALSE(s.resident(sim.topology(), 1));
  std::vector<fast::ColdRange> cold;
  fast::ColdClaims claims(cold);
  s.claim_whole(sim.topology(), 1, claims);
  fast::touch_pages(fast::Parallel(1), cold);
  EXPECT_TRUE(s.resident(sim.topology(), 1));
  ASSERT_EQ(s.eorder.size(), 3u);
  EXPECT_EQ(s.eorder[0], 7);
  EXPECT_EQ(s.eorder[1], 5);
  EXPECT_EQ(s.eorder[2], 9);
}

// warm_to faults in the room from where the touched part ends (the elements, or room warmed
// before) up to the target, no further than the capacity or the budget allows, and a copy is
// touched as far as its original. Catches a warm that starts at the elements' end again (it
// would return the bytes of room already touched), one that ignores the budget or runs past
// the capacity, and a copy touched only as far as keep_warm's eighth.
TEST(Array, WarmToTouchesUpToTheTargetWithinTheBudget) {
  fast::Array<int> a;
  a.reserve(100000);
  a.resize(100);
  EXPECT_EQ(a.warm_to(50000, 4000), 4000u);  // 1,000 elements
  EXPECT_EQ(a.touched(), 1100u);
  EXPECT_EQ(a.warm_to(50000, SIZE_MAX), 4u * 48900);
  EXPECT_EQ(a.touched(), 50000u);
  EXPECT_EQ(a.warm_to(40000, SIZE_MAX), 0u);
  EXPECT_EQ(a.warm_to(200000, SIZE_MAX), 4u * 50000);  // to the capacity, no further
  EXPECT_EQ(a.touched(), a.capacity());
  fast::Array<int> b;  // on huge pages: a copy is touched as far as b, not keep_warm's eighth
  b.reserve(3000000);
  b.resize(10);
  b.warm_to(600000, SIZE_MAX);
  const fast::Array<int> c(b);
  EXPECT_EQ(c.touched(), b.touched());
  EXPECT_GE(c.touched(), 600000u);
}

// On huge pages a claim runs on to the end of the huge page its last byte is in (the touch maps
// all of it), never into the next one, and at most to the capacity; under a huge page it ends
// at its target. Catches a claim that stops at its target on huge pages (its budget would not
// bound the huge pages it maps), one rounded past the boundary (its last element's touch would
// map the next huge page too) or past the capacity, and rounding on small pages.
TEST(Array, AClaimOnHugePagesRunsToTheEndOfItsHugePage) {
  constexpr std::size_t kHuge = fast::kHugePage;
  struct Record {  // an EdgeRecord's size: 2 MiB is not a whole number of them
    char bytes[36];
  };
  fast::Array<Record> a;
  a.reserve(3 * kHuge / sizeof(Record));  // huge-page aligned (allocate_aligned)
  ASSERT_EQ(reinterpret_cast<std::uintptr_t>(a.data()) % kHuge, 0u);
  const char* base = reinterpret_cast<const char*>(a.data());
  fast::ColdRange r = a.claim_cold(10, SIZE_MAX);
  EXPECT_EQ(r.begin, base);
  EXPECT_EQ(a.touched(), kHuge / sizeof(Record));  // 58,254 records: the last ends 8 bytes short
  EXPECT_LE(r.end, base + kHuge);
  EXPECT_GT(r.end + sizeof(Record), base + kHuge);
  r = a.claim_cold(a.touched() + 1, 100);  // the straddling record: on to the second boundary
  EXPECT_EQ(a.touched(), 2 * kHuge / sizeof(Record));
  EXPECT_LE(r.end, base + 2 * kHuge);
  r = a.claim_cold(a.capacity(), sizeof(Record));  // a budget of one record: on to the capacity
  EXPECT_EQ(a.touched(), a.capacity());
  EXPECT_EQ(r.end, base + a.capacity() * sizeof(Record));
  fast::Array<Record> b;  // 2.5 MiB: its second huge page ends past the capacity
  b.reserve(5 * kHuge / 4 / sizeof(Record));
  b.claim_cold(kHuge / sizeof(Record) + 1, SIZE_MAX);
  EXPECT_EQ(b.touched(), b.capacity());
  fast::Array<int> small;  // 400 KB: 4 KiB pages, nothing to round to
  small.reserve(100000);
  small.claim_cold(1000, SIZE_MAX);
  EXPECT_EQ(small.touched(), 1000u);
}

// ColdClaims spends its budget in array order: once spent, the next arrays claim nothing and
// get their turn at a later call; a claim on huge pages counts the bytes to its huge page's end
// (what its touch faults in), so a small budget faults in one huge page, not one in every
// array. Catches a budget ignored or counted by the claims' targets rather than their ends (the
// second array would claim at once) and a claim not collected for the touch.
TEST(Array, ColdClaimsSpendABudgetInArrayOrder) {
  constexpr std::size_t kHuge = fast::kHugePage;
  fast::Array<int> a, b;
  a.reserve(2 * kHuge / sizeof(int)), b.reserve(2 * kHuge / sizeof(int));  // on huge pages
  std::vector<fast::ColdRange> ranges;
  fast::ColdClaims first(ranges, 4096);
  first.claim(a, 1000), first.claim(b, 1000);
  EXPECT_EQ(ranges.size(), 1u);
  EXPECT_EQ(first.claimed(), kHuge);
  EXPECT_EQ(b.touched(), 0u);
  fast::ColdClaims second(ranges, 4096);
  second.claim(a, 1000), second.claim(b, 1000);  // a is touched past 1000: b's turn
  ASSERT_EQ(ranges.size(), 2u);
  EXPECT_EQ(ranges[1].begin, reinterpret_cast<char*>(b.data()));
  EXPECT_EQ(b.touched(), kHuge / sizeof(int));
}

// touch_pages writes one byte in every 4 KiB page of [begin, end) and nothing outside it: a
// write past `end` would corrupt the element after the warmed room, a skipped page would leave
// a fault inside a step. Catches an off-by-one at either end and a stride other than the page.
TEST(Array, TouchPagesWritesEveryPageOfTheRangeAndNothingElse) {
  constexpr std::size_t kPage = 4096;
  std::vector<unsigned char> buffer(8 * kPage, 0xff);
  const std::uintptr_t base = reinterpret_cast<std::uintptr_t>(buffer.data());
  unsigned char* page0 = buffer.data() + ((base + kPage - 1) / kPage * kPage - base);  // first boundary
  for (std::size_t from : {std::size_t(0), std::size_t(1), kPage - 1}) {
    for (std::size_t length : {std::size_t(0), std::size_t(1), kPage, 3 * kPage + 5}) {
      std::fill(buffer.begin(), buffer.end(), 0xff);
      unsigned char* begin = page0 + from;
      fast::touch_pages(begin, begin + length);
      for (unsigned char* p = buffer.data(); p < buffer.data() + buffer.size(); ++p) {
        const bool inside = p >= begin && p < begin + length;
        if (!inside) {
          ASSERT_EQ(*p, 0xff) << "written outside: from " << from << " length " << length;
        }
      }
      // Each page the range overlaps has a written byte inside the range.
      for (unsigned char* page = page0; page < begin + length; page += kPage) {
        unsigned char* lo = std::max(page, begin);
        unsigned char* hi = std::min(page + kPage, begin + length);
        if (lo >= hi) continue;
        EXPECT_NE(std::find(lo, hi, 0), hi) << "page not touched: from " << from << " length " << length;
      }
    }
  }
}

// touch_pages on a Parallel (LayoutScratch::warm, FastSimulator::warm_ahead) cuts its ranges
// into chunks at huge-page boundaries and touches them on any thread: every page of every range
// is written, nothing outside the ranges. Catches a chunk cut short, a range or chunk that no
// thread touches, and a write past a range's end. Ranges that start and end inside huge pages
// and between them, one within one page, one empty; each set spans several huge pages, so its
// chunks run as a parallel loop.
TEST(Parallel, TouchPagesOnThreadsWritesEveryPageOfEveryRangeAndNothingElse) {
  constexpr std::size_t kPage = 4096, kHuge = fast::kHugePage;
  std::vector<unsigned char> buffer(5 * kHuge, 0xff);
  const std::uintptr_t base = reinterpret_cast<std::uintptr_t>(buffer.data());
  unsigned char* huge0 = buffer.data() + ((base + kHuge - 1) / kHuge * kHuge - base);  // first boundary
  auto range = [&](std::size_t from, std::size_t to) {
    return fast::ColdRange{reinterpret_cast<char*>(huge0 + from), reinterpret_cast<char*>(huge0 + to)};
  };
  // In ascending order, disjoint: the gaps between them are what must stay unwritten.
  // Over a huge page in all; and under a huge page in all but in three huge pages, which run
  // as a parallel loop too.
  const std::vector<std::vector<fast::ColdRange>> sets = {
      {range(5, 5), range(100, kHuge + 5000), range(kHuge + 3 * kPage, 3 * kHuge + 1),
       range(3 * kHuge + 10, 3 * kHuge + 20)},
      {range(kHuge - 10, kHuge + 3 * kPage), range(2 * kHuge + 7, 2 * kHuge + 9)}};
  const auto written = [](const unsigned char* begin, const unsigned char* end) {
    return std::find_if(begin, end, [](unsigned char c) { return c != 0xff; }) != end;
  };
  for (int threads : {1, 2, 4}) {
    for (const std::vector<fast::ColdRange>& ranges : sets) {
      std::fill(buffer.begin(), buffer.end(), 0xff);
      fast::touch_pages(fast::Parallel(threads), ranges);
      const unsigned char* gap = buffer.data();
      for (const fast::ColdRange& r : ranges) {
        EXPECT_FALSE(written(gap, reinterpret_cast<unsigned char*>(r.begin)))
            << "written before a range, " << threads << " threads";
        gap = std::max(gap, reinterpret_cast<const unsigned char*>(r.end));
      }
      EXPECT_FALSE(written(gap, buffer.data() + buffer.size())) << "written after the ranges, " << threads << " threads";
      for (const fast::ColdRange& r : ranges) {
        auto* begin = reinterpret_cast<unsigned char*>(r.begin);
        auto* end = reinterpret_cast<unsigned char*>(r.end);
        for (unsigned char* page = huge0 + (begin - huge0) / kPage * kPage; page < end; page += kPage) {
          unsigned char* lo = std::max(page, begin);
          unsigned char* hi = std::min(page + kPage, end);
          if (lo >= hi) continue;  // the empty range
          EXPECT_NE(std::find(lo, hi, 0), hi) << "page at " << page - huge0 << " not touched, " << threads << " threads";
        }
      }
    }
  }
}

// A vectorized kernel's chunks start on lane boundaries, on any thread count, and cover the
// range once: so each item is computed by the same code path however the range is split.
TEST(Parallel, LaneChunksStartOnLaneBoundariesAndCoverTheRangeOnce) {
  for (int threads : {1, 2, 4}) {
    const fast::Parallel par(threads);
    for (int n : {0, 1, 63, 64, 65, 4097, 100003}) {
      std::vector<std::atomic<int>> seen(static_cast<std::size_t>(n));
      std::atomic<int> misaligned{0};
      par.run_lanes(n, 256, [&](int b, int e) {
        if (b % fast::Parallel::kLanes != 0 || e < b || e > n) ++misaligned;
        for (int k = b; k < e; ++k) ++seen[std::size_t(k)];
      });
      EXPECT_EQ(misaligned.load(), 0) << "threads " << threads << ", n " << n;
      int once = 0;
      for (auto& s : seen) once += s.load() == 1;
      EXPECT_EQ(once, n) << "threads " << threads << ", n " << n;
    }
  }
}

// run_blocks hands each fixed block b exactly [b * block, min(n, (b + 1) * block)), once, on any
// thread count: what makes the per-block sums of the totals and the layout's histograms
// independent of the threads. Catches a last block cut short or run past n, and a block index
// that does not match its range.
TEST(Parallel, FixedBlocksAreTheirOwnRangeOnceOnAnyThreadCount) {
  for (int threads : {1, 2, 4}) {
    const fast::Parallel par(threads);
    for (int n : {0, 1, 7, 8, 9, 8193, 100003}) {
      const int block = n < 100 ? 8 : 8192;
      const int blocks = fast::Parallel::blocks_of(n, block);
      std::vector<std::atomic<int>> seen(static_cast<std::size_t>(n)), calls(static_cast<std::size_t>(blocks));
      std::atomic<int> wrong{0};
      par.run_blocks(n, block, [&](int b, int begin, int end) {
        if (b < 0 || b >= blocks || begin != b * block || end != std::min(n, (b + 1) * block)) ++wrong;
        else ++calls[std::size_t(b)];
        for (int k = begin; k < end && k < n; ++k) ++seen[std::size_t(k)];
      });
      EXPECT_EQ(wrong.load(), 0) << "threads " << threads << ", n " << n;
      for (auto& c : calls) EXPECT_EQ(c.load(), 1) << "threads " << threads << ", n " << n;
      int once = 0;
      for (auto& v : seen) once += v.load() == 1;
      EXPECT_EQ(once, n) << "threads " << threads << ", n " << n;
    }
  }
}

// The byte scan of the decisions' listing, against a plain loop, over ranges that start and end
// inside a line and across lines, for both senses. Catches halves of a line's mask swapped, a
// match past bit 31 lost, a tail left unvisited, a range's start rounded to its line.
TEST(ForEachByte, VisitsTheMatchesOfAnyRangeInOrder) {
  std::vector<std::uint8_t> bytes(300, 0);
  for (std::size_t k = 0; k < bytes.size(); ++k)
    if (k % 7 == 3 || k % 64 == 63 || k % 64 == 32 || k == 31) bytes[k] = std::uint8_t(1 + k % 3);
  for (auto [begin, end] : {std::pair{0, 300}, {5, 290}, {64, 128}, {33, 97}, {100, 100}, {250, 300}})
    for (std::uint8_t value : {std::uint8_t(0), std::uint8_t(2)}) {
      std::vector<int> want_equal, want_other, got_equal, got_other;
      for (int k = begin; k < end; ++k) (bytes[std::size_t(k)] == value ? want_equal : want_other).push_back(k);
      fast::for_each_byte<true>(bytes.data(), value, begin, end, [&](int k) { got_equal.push_back(k); });
      fast::for_each_byte<false>(bytes.data(), value, begin, end, [&](int k) { got_other.push_back(k); });
      EXPECT_EQ(got_equal, want_equal) << begin << ".." << end << " value " << int(value);
      EXPECT_EQ(got_other, want_other) << begin << ".." << end << " value " << int(value);
    }
}

// The rounds' and waves' grouping: every item once, groups in order, item order within a group,
// each group's range at first[g]..first[g + 1], and an empty group (the splits' round 0, a round
// no split reached) an empty range. Catches an unstable fill, ranges off by one group, and a
// first that runs past the last group's end.
TEST(OrderByGroup, GroupsInOrderItemsInOrderWithinEach) {
  const std::vector<int> group_of{2, 0, 3, 2, 0, 3, 3, 2};
  std::vector<int> first{7, 7}, order{9};
  fast::order_by_group(int(group_of.size()), 4, [&](int k) { return group_of[std::size_t(k)]; }, first, order);
  EXPECT_EQ(order, (std::vector<int>{1, 4, 0, 3, 7, 2, 5, 6}));
  EXPECT_EQ(first, (std::vector<int>{0, 2, 2, 5, 8}));
  fast::order_by_group(0, 0, [](int) { return 0; }, first, order);
  EXPECT_TRUE(order.empty());
  EXPECT_EQ(first, (std::vector<int>{0}));
}

// A triangle's mark holds for its pass alone, over many more passes than there are tags (the
// stamps are one byte: tags cycle): a mark of the first pass must not read as one when its tag
// comes round again, and a triangle never marked never reads as marked. Catches a cycle without
// the clear, a tag of 0 (the value of a stamp never written), and a mark that lasts a pass.
TEST(PassStamps, AMarkHoldsForItsPassAloneThroughTheTagsCycles) {
  fast::PassStamps s;
  s.begin_pass();
  s.cover(1000);
  s.mark(7);
  EXPECT_TRUE(s.touched(7));
  for (int pass = 1; pass <= 1000; ++pass) {
    s.begin_pass();
    ASSERT_FALSE(s.touched(7)) << "pass " << pass;
    ASSERT_FALSE(s.touched(500)) << "pass " << pass;
    ASSERT_FALSE(s.touched(8)) << "pass " << pass;
    s.mark(8);
    ASSERT_TRUE(s.touched(8)) << "pass " << pass;
  }
}

// invoke runs each of its two jobs exactly once, in the backend's arena, and returns only when
// both are done, a parallel loop inside a job covering its range once (the topology pass's
// freed ids beside its events' ids, SplitRounds' room beside its ids' parallel loop). Catches a
// job skipped or run twice, jobs run outside the arena (on whatever threads TBB would pick), a
// return before a job has finished, and a nested loop that loses chunks inside the arena.
TEST(Parallel, InvokeRunsBothJobsOnceAndReturnsWhenBothAreDone) {
  for (int threads : {1, 2, 4}) {
    const fast::Parallel par(threads);
    constexpr int n = 100003;
    std::vector<std::atomic<int>> seen(static_cast<std::size_t>(n));
    std::vector<int> serial;
    std::atomic<int> firsts{0}, seconds{0}, outside{0};
    const auto in_arena = [&] { return threads == 1 || tbb::this_task_arena::max_concurrency() == threads; };
    par.invoke(
        [&] {
          ++firsts;
          outside += !in_arena();
          for (int k = 0; k < 1000; ++k) serial.push_back(k);
        },
        [&] {
          ++seconds;
          outside += !in_arena();
          par.run(n, 256, [&](int b, int e) {
            for (int k = b; k < e; ++k) ++seen[std::size_t(k)];
          });
        });
    EXPECT_EQ(firsts.load(), 1) << threads << " threads";
    EXPECT_EQ(seconds.load(), 1) << threads << " threads";
    EXPECT_EQ(outside.load(), 0) << threads << " threads";
    ASSERT_EQ(serial.size(), 1000u) << threads << " threads";
    EXPECT_EQ(serial.back(), 999) << threads << " threads";
    int once = 0;
    for (auto& s : seen) once += s.load() == 1;
    EXPECT_EQ(once, n) << threads << " threads";
  }
}

// The edge pass's input, as a step prepares it: a crumpled state with splits and auxiliary edges
// (40 explicit steps of a 12 x 12 sheet), its triangle areas and vertex normals, and the
// constants and scratch of a step.
class EdgeLanes : public ::testing::Test {
 protected:
  void SetUp() override {
    p.integrator = Integrator::Explicit;
    fast::FastSimulator sim(make_grid(12), p, 1);
    for (int s = 0; s < 40; ++s) sim.step();
    m = sim.topology();
    c.kappa = float(p.kappa), c.bend = float(p.bend), c.damping = 0.5f, c.implicit = 1e-3f;
    fast::triangle_areas(m, 1.0f, m.T.area.data(), 0, m.T.size());
    fast::vertex_normals(m, m.V.nr.data(), 0, m.V.size());
    step.fit(m);
  }
  Params p;
  fast::Topology m;
  fast::StepConstants c;
  fast::StepScratch step;
};

// The edge pass runs eight edges in AVX lanes (lanes8.h), the last block of a range padded with
// its last edge: an edge's record must be the same bits whichever lane and chunk computed it,
// and a range must write no record outside itself. Ranges split at every offset and run last
// part first, so a block that stored its padding lanes past the end of its range would overwrite
// the records of the part already done. Both forms of the pass: with damping and without (which
// reads no velocity rows).
TEST_F(EdgeLanes, ARecordDoesNotDependOnItsChunkAndNoRangeWritesPastItsEnd) {
  const int n = m.E.size();
  fast::EdgeOut* out = step.edge_out.data();
  for (const float damping : {0.5f, 0.0f}) {
    c.damping = damping;
    fast::edge_forces(m.E, m.V, c, out, 0, n);
    const std::vector<fast::EdgeOut> whole(out, out + n);
    int hinges = 0;
    for (const fast::EdgeOut& r : whole) hinges += r.kb != 0;
    ASSERT_GT(hinges, n / 4);  // bending is exercised, not only springs
    for (int split = 1; split < 20; ++split) {
      for (auto& r : step.edge_out) r = fast::EdgeOut{-1, -1, -1, -1, -1, -1, -1, -1};
      fast::edge_forces(m.E, m.V, c, out, split, n);
      fast::edge_forces(m.E, m.V, c, out, 0, split);
      EXPECT_EQ(std::memcmp(whole.data(), out, sizeof(fast::EdgeOut) * std::size_t(n)), 0)
          << "split at " << split << ", damping " << damping;
    }
  }
}

// The edge pass bends only hinges, mesh edges with both wings [Eq 8-9]: an auxiliary edge keeps
// its split's crease wings in wl and wr (the restoration test reads them) and a boundary edge
// has a wing of -1, and neither may bend. The eight-lane pass reads the stencils of eight
// records at once; a mask that missed the mesh flag would bend the auxiliary edges, one that
// missed a wing's sign would read row -1.
TEST_F(EdgeLanes, OnlyHingesBend) {
  const int n = m.E.size();
  fast::edge_forces(m.E, m.V, c, step.edge_out.data(), 0, n);
  int hinges_bent = 0, creases = 0, boundary = 0;
  for (int e = 0; e < n; ++e) {
    const fast::EdgeRecord& r = m.E[e];
    const bool mesh = r.flags & fast::kMesh, wings = r.wl >= 0 && r.wr >= 0;
    const fast::EdgeOut& o = step.edge_out[std::size_t(e)];
    if (mesh && wings) {
      hinges_bent += o.kb != 0;
      continue;
    }
    creases += (r.flags & fast::kAlive) && !mesh && wings;
    boundary += mesh && !wings;
    EXPECT_EQ(o.kb, 0.0f) << "edge " << e;
    EXPECT_TRUE(o.bx == 0 && o.by == 0 && o.bz == 0) << "edge " << e;
  }
  EXPECT_GT(hinges_bent, n / 4);
  EXPECT_GT(creases, 0);   // auxiliary edges with their crease's wings are in the state
  EXPECT_GT(boundary, 0);  // and mesh edges with one wing
}

// The fracture and restoration test runs in fixed blocks on any thread (adapt_decide): a
// decision must not depend on the range that made it, and no range may write a byte outside
// itself (another thread's block: a race even where it writes the right value; a kernel that
// pads its last lanes, as an eight-lane version of it did, must not store them). Both kinds of decision
// must occur: a huge budget breaks every compressed mesh edge that can, an epsilon of 0 restores
// every crease. Both P_step forms: the exact one (step_exponent 1) and the pow.
TEST(AdaptTest, ADecisionDoesNotDependOnItsRangeAndNoRangeWritesOutsideItself) {
  fast::FastSimulator sim(make_grid(12), Params{}, 1);
  for (int s = 0; s < 40; ++s) sim.step();  // a crumpled state with splits and auxiliary edges
  fast::Topology m = sim.topology();
  for (int v = 0; v < m.V.size(); ++v) {  // shrunk by a tenth: nearly every edge compressed
    fast::Float4& x = m.V.xm[v];
    x = fast::Float4{0.9f * x.x, 0.9f * x.y, 0.9f * x.z, x.w};
  }
  fast::triangle_areas(m, 1.0f, m.T.area.data(), 0, m.T.size());
  fast::vertex_normals(m, m.V.nr.data(), 0, m.V.size());
  const int n = m.E.size();
  for (const float exponent : {1.0f, 0.25f}) {
    fast::AdaptConstants c;
    c.phi = 0.75f, c.epsilon = 0.0f, c.floor_length = 0.0f, c.step_exponent = exponent, c.budget = 1e3f;
    c.seed = 7, c.step = 40;
    std::vector<std::uint8_t> whole(std::size_t(n), 9), out(whole.size());
    fast::adapt_test(m, c, whole.data(), 0, n);
    const auto count = [&](std::uint8_t d) { return std::count(whole.begin(), whole.end(), d); };
    ASSERT_GT(count(1), 10) << "exponent " << exponent;
    ASSERT_GT(count(2), 10) << "exponent " << exponent;
    ASSERT_EQ(count(1) + count(2) + count(0), n);  // every edge decided
    // Each part alone into a buffer of 9s: its own bytes are the whole range's, the rest still 9.
    auto part = [&](int begin, int end) {
      std::vector<std::uint8_t> expected(whole.size(), 9);
      std::copy(whole.begin() + begin, whole.begin() + end, expected.begin() + begin);
      std::fill(out.begin(), out.end(), std::uint8_t(9));
      fast::adapt_test(m, c, out.data(), begin, end);
      return out == expected;
    };
    for (int split = 1; split < 20; ++split) {
      EXPECT_TRUE(part(split, n)) << "exponent " << exponent << ", [" << split << ", n)";
      EXPECT_TRUE(part(0, split)) << "exponent " << exponent << ", [0, " << split << ")";
    }
  }
}

/// Asserts two runs had the same events frame by frame, and totals them.
void same_events(const std::vector<StepEvents>& a, const std::vector<StepEvents>& b, long& splits, long& restores) {
  for (std::size_t f = 0; f < a.size(); ++f) {
    ASSERT_EQ(a[f].splits, b[f].splits) << "frame " << f;
    ASSERT_EQ(a[f].restores, b[f].restores) << "frame " << f;
    ASSERT_EQ(a[f].split_edges, b[f].split_edges) << "frame " << f;
    ASSERT_EQ(a[f].restored_edges, b[f].restored_edges) << "frame " << f;
    splits += a[f].splits;
    restores += a[f].restores;
  }
}

/// Steps `frames` frames with the relayout off: the slots keep every vertex, edge and triangle
/// that the splits appended, in the order they came.
void grow_without_relayouts(fast::FastSimulator& sim, int frames) {
  sim.set_layout_fraction(-1);
  for (int f = 0; f < frames; ++f) sim.step();
}

/// |slot(a) - slot(b)| of every live edge: how far apart neighbours are stored.
std::vector<int> slot_distances(const fast::Topology& m) {
  std::vector<int> d;
  for (int e = 0; e < m.E.size(); ++e)
    if (m.E[e].flags & fast::kAlive) d.push_back(std::abs(m.E[e].a - m.E[e].b));
  return d;
}

/// The mean of slot_distances(m).
double mean_slot_distance(const fast::Topology& m) {
  const std::vector<int> d = slot_distances(m);
  return std::accumulate(d.begin(), d.end(), 0.0) / double(d.size());
}

// The sphere crumple with symplectic Euler (no momentum correction, whose block sums follow
// the slot order): relayout after every step and never give bit-identical logical states,
// through hundreds of splits and restores, on one and two threads.
TEST(Layout, RelayoutEveryStepChangesNoBit) {
  Params p;
  p.integrator = Integrator::Explicit;
  p.kappa = 50;  // inside symplectic Euler's limit at h = 1/60
  for (int threads : {1, 2}) {
    // One simulator alive at a time: ThreadSanitizer cannot see oneTBB's synchronization when
    // two task arenas take turns (libtbb is not instrumented) and reports false races.
    auto run = [&](double fraction, std::vector<StepEvents>& events, int& moved) {
      fast::FastSimulator sim(make_grid(20), p, threads);
      sim.set_layout_fraction(fraction);
      for (int f = 0; f < 90; ++f) {
        events.push_back(sim.step());
        EXPECT_EQ(sim.check_topology(), "") << "frame " << f;
      }
      moved = 0;
      for (int v = 0; v < sim.topology().V.size(); ++v) moved += sim.topology().V.lid[v] != v;
      return sim.snapshot();
    };
    std::vector<StepEvents> ea, eb;
    int moved = 0, unmoved = 0;
    const Snapshot every = run(0, ea, moved), never = run(-1, eb, unmoved);
    long splits = 0, restores = 0;
    ASSERT_NO_FATAL_FAILURE(same_events(ea, eb, splits, restores));
    EXPECT_GT(splits, 300);
    EXPECT_GT(restores, 30);
    EXPECT_TRUE(same_snapshot(every, never)) << threads << " threads";
    // The layout did move slots: logical ids are no longer the identity (and without it they are).
    EXPECT_GT(moved, int(every.mass.size()) / 2);
    EXPECT_EQ(unmoved, 0);
  }
}

// The totals (fast_state.cpp: the vertex sums in blocks of logical ids, read through the slot
// map; the edges' counts, largest strain and squared strains in blocks of slots) are the plain
// sums over the snapshot (the counts exactly, the sums to round-off: the compiler may fuse the
// core's multiply-adds), with splits, restores and freed ids in the state; the same state with
// slots moved by a relayout every step and with slots never moved gives the same totals bit for
// bit but for the squared strains' sum (summed in slot order: rms_strain to round-off); one and
// four threads give the same bits. Catches a vertex sum in slot order, a dead or auxiliary edge
// counted as a mesh edge or strained (a dead slot's strain is -1), a block of edges left out (the
// vertices here fill one block), and edge sums whose blocks follow the threads.
TEST(FastTotals, AreTheSumsOverTheSnapshotWhereverTheSlotsAre) {
  Params p = churn_params();
  auto run = [&](double fraction, int threads) {
    auto sim = std::make_unique<fast::FastSimulator>(make_grid(40), p, threads);
    sim->set_layout_fraction(fraction);
    long restores = 0;
    for (int step = 0; step < 120; ++step) restores += sim->step().restores;
    EXPECT_GT(restores, 50);
    EXPECT_FALSE(sim->topology().V.free_ids.empty());
    EXPECT_GT(sim->topology().E.size(), fast::kReduceBlock) << "the edges span one block: nothing to add up";
    return sim;
  };
  const auto sim = run(-1, 2);
  const Snapshot s = sim->snapshot();
  const Totals never = sim->totals(), every = run(0, 2)->totals();
  const auto mesh_edges = std::count_if(s.edges.begin(), s.edges.end(), [](const EdgeView& e) { return e.a >= 0 && !e.auxiliary; });
  for (const Totals* t : {&never, &every}) {
    EXPECT_EQ(t->edges, mesh_edges);
    EXPECT_EQ(t->auxiliary, std::count_if(s.edges.begin(), s.edges.end(), [](const EdgeView& e) { return e.a >= 0 && e.auxiliary; }));
  }
  double mass = 0, momentum[3] = {0, 0, 0}, kinetic = 0;
  for (std::size_t v = 0; v < s.mass.size(); ++v) {
    const double m = s.mass[v];
    mass += m;
    for (int d = 0; d < 3; ++d) momentum[d] += m * s.velocity[v][d];
    kinetic += 0.5 * m * (s.velocity[v][0] * s.velocity[v][0] + s.velocity[v][1] * s.velocity[v][1] + s.velocity[v][2] * s.velocity[v][2]);
  }
  double max_strain = 0, strain2 = 0;
  for (const EdgeView& e : s.edges) {
    if (e.a < 0 || e.auxiliary) continue;
    const Vec3d &xa = s.position[std::size_t(e.a)], &xb = s.position[std::size_t(e.b)];
    const double strain = std::hypot(xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]) / e.rest - 1.0;
    max_strain = std::max(max_strain, std::abs(strain));
    strain2 += strain * strain;
  }
  EXPECT_EQ(never.mass, mass);  // float masses summed in double in one order: no product to fuse
  EXPECT_NEAR(never.kinetic, kinetic, 1e-12 * kinetic);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(never.momentum[d], momentum[d], 1e-12 * mass) << d;
  // Each strain to a few ulps of 1 (the core's square root of fused products, the test's hypot).
  EXPECT_NEAR(never.max_strain, max_strain, 1e-12 * max_strain + 1e-14);
  const double rms = std::sqrt(strain2 / double(mesh_edges));
  EXPECT_NEAR(never.rms_strain, rms, 1e-12 * rms + 1e-14);
  EXPECT_NEAR(every.rms_strain, rms, 1e-12 * rms + 1e-14);
  EXPECT_EQ(every.mass, never.mass);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(every.momentum[d], never.momentum[d]) << d;
  EXPECT_EQ(every.kinetic, never.kinetic);
  EXPECT_EQ(every.max_strain, never.max_strain);
  EXPECT_EQ(every.max_speed, never.max_speed);
  EXPECT_EQ(every.max_distance, never.max_distance);
  for (int threads : {1, 4}) {
    const Totals t = run(-1, threads)->totals();
    EXPECT_EQ(t.mass, never.mass) << threads;
    for (int d = 0; d < 3; ++d) EXPECT_EQ(t.momentum[d], never.momentum[d]) << threads;
    EXPECT_EQ(t.kinetic, never.kinetic) << threads;
    EXPECT_EQ(t.rms_strain, never.rms_strain) << threads;
    EXPECT_EQ(t.max_strain, never.max_strain) << threads;
    EXPECT_EQ(t.max_speed, never.max_speed) << threads;
    EXPECT_EQ(t.max_distance, never.max_distance) << threads;
    EXPECT_EQ(t.edges, never.edges) << threads;
    EXPECT_EQ(t.auxiliary, never.auxiliary) << threads;
  }
}

// The render buffers (fast_manipulators.cpp: vertices copied in slot order to their ids'
// places, triangles in fixed blocks of ids, each block written at its offset) are the snapshot's
// vertices and live triangles in id order, with slots moved by relayouts, freed ids in the state
// and over two blocks of triangle ids, into buffers that an earlier frame filled (a caller
// reuses them) while a vertex id was live that is free now. Catches a vertex written at its slot
// instead of its id, a free id left with the earlier frame's position or normal, a dead
// triangle emitted, and blocks out of order or at overlapping offsets.
TEST(FastRender, BuffersAreTheSnapshotInIdOrder) {
  Params p = churn_params();
  fast::FastSimulator sim(make_grid(72), p, 2);  // 10,082 triangles: two blocks of 8,192 ids
  sim.set_layout_fraction(0);
  RenderBuffers r;
  std::vector<bool> live_then;
  long restores = 0;
  for (int step = 0; step < 40; ++step) {
    restores += sim.step().restores;
    if (step == 20) sim.render(r, true), live_then = sim.snapshot().vertex_alive;
  }
  ASSERT_GT(restores, 20);
  ASSERT_FALSE(sim.topology().T.free_ids.empty());
  const std::vector<int>& free_now = sim.topology().V.free_ids;
  ASSERT_TRUE(std::any_of(free_now.begin(), free_now.end(), [&](int id) { return id < int(live_then.size()) && live_then[id]; }));
  sim.render(r, true);
  const Snapshot s = sim.snapshot();
  const std::vector<Vec3d> normals = sim.normals();
  ASSERT_EQ(r.positions.size(), 3 * s.position.size());
  ASSERT_EQ(r.normals.size(), 3 * s.position.size());
  for (std::size_t k = 0; k < s.position.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(r.positions[3 * k + c], float(s.position[k][c])) << k;
      ASSERT_EQ(r.normals[3 * k + c], s.vertex_alive[k] ? float(normals[k][c]) : 0.0f) << k;
    }
  std::vector<std::uint32_t> live;
  for (const std::array<int, 3>& t : s.triangles)
    if (t[0] >= 0) live.insert(live.end(), t.begin(), t.end());
  EXPECT_EQ(r.triangles, live);
}

// The relayout's sorts run as per-thread blocks on two threads (layout.cpp's stable_pass): the
// slot order they give must be the one thread's, element for element. 192 x 192, so that every
// sort has over two blocks' worth of items.
TEST(Layout, SlotOrderIsTheSameOnAnyThreadCount) {
  Params p;
  struct Order {
    std::vector<std::int32_t> v, e, t;
  };
  auto relaid = [&](int threads) {  // one simulator alive at a time (see RelayoutEveryStep...)
    fast::FastSimulator sim(make_grid(192), p, threads);
    grow_without_relayouts(sim, 40);
    sim.run_pass(fast::Pass::Layout);
    EXPECT_EQ(sim.check_topology(), "");
    const fast::Topology& m = sim.topology();
    EXPECT_GT(m.V.size(), 2 * fast::kRadixBlock);  // two blocks of the vertex sort
    return Order{{m.V.lid.begin(), m.V.lid.end()}, {m.E.lid.begin(), m.E.lid.end()}, {m.T.lid.begin(), m.T.lid.end()}};
  };
  const Order one = relaid(1), two = relaid(2);
  EXPECT_EQ(one.v, two.v);
  EXPECT_EQ(one.e, two.e);
  EXPECT_EQ(one.t, two.t);
}

// One relayout of a crumpled state (default approximate implicit method): the interface sees
// the same state, forces, normals and decisions, bit for bit; the next step agrees to float
// round-off (only the momentum correction's summation order changed); neighbours are stored
// much closer together than before.
TEST(Layout, OneRelayoutKeepsTheStateAndBringsNeighboursTogether) {
  Params p;
  fast::FastSimulator sim(make_grid(24), p, 1);
  grow_without_relayouts(sim, 60);
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

/// The median of slot_distances(m).
double median_slot_distance(const fast::Topology& m) {
  std::vector<int> d = slot_distances(m);
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// The vertex order is a curve over the sheet's two dimensions and puts the dead slots after
// every live one. On a grid, an order by one coordinate (rows) leaves every edge across the
// rows a row's length of slots apart, at least half the edges; a curve through square cells
// keeps most neighbours a few slots apart (a median of 5 here, against 39 by rows). Catches an
// order along fewer axes than the sheet spans (one of them dropped, or the flat axis taken in
// their place) and a dead slot's code that does not sort last.
TEST(Layout, VertexOrderIsACurveOverTheSheetWithTheDeadLast) {
  Params p;
  fast::FastSimulator sim(make_grid(32), p, 2);
  grow_without_relayouts(sim, 90);
  const fast::Topology& m = sim.topology();
  ASSERT_GT(m.V.free_ids.size(), 0u);  // restores freed vertex slots
  sim.run_pass(fast::Pass::Layout);
  ASSERT_EQ(sim.check_topology(), "");
  const int live = m.live_vertices();
  for (int v = 0; v < m.V.size(); ++v) ASSERT_EQ(m.V.mass(v) > 0, v < live) << v;
  const double row = std::sqrt(double(live));
  RecordProperty("median_slot_distance", std::to_string(median_slot_distance(m)));
  EXPECT_LT(median_slot_distance(m), row / 4);
}

// True when the live triangles are sorted by their lowest corner's slot and the dead ones
// follow them (what the relayout's third phase leaves).
bool triangles_in_vertex_order(const fast::Topology& m) {
  int last = -1;
  for (int t = 0; t < m.T.size(); ++t) {
    const auto& v = m.T[t].v;
    const int key = m.T.alive[t] ? std::min({v[0], v[1], v[2]}) : m.V.size();
    if (key < last) return false;
    last = key;
  }
  return true;
}

// The places where an edge's key (its lower endpoint's slot, dead ones past every slot) is
// smaller than the one before it.
int edge_order_descents(const fast::Topology& m) {
  int descents = 0, last = -1;
  for (int e = 0; e < m.E.size(); ++e) {
    const int key = (m.E[e].flags & fast::kAlive) ? std::min(m.E[e].a, m.E[e].b) : m.V.size();
    descents += key < last;
    last = key;
  }
  return descents;
}

// The edges sorted by their lower endpoint, dead ones last (the fifth phase).
bool edges_in_vertex_order(const fast::Topology& m) { return edge_order_descents(m) == 0; }

// True when both adjacency pools hold the vertices' blocks in slot order with no garbage
// between (what the relayout's second phase leaves).
bool lists_in_vertex_order(const fast::Topology& m) {
  for (const auto* heads : {&m.V.spring_list, &m.V.tri_list}) {
    int at = 0;
    for (int v = 0; v < m.V.size(); ++v) {
      if ((*heads)[v].at != at) return false;
      at += (*heads)[v].room;
    }
  }
  return true;
}

// A relayout runs in five steps (layout.h): the step that finds the layout stale moves the
// vertices only, the next one packs their lists, the next sorts the triangles, the next orders
// the edges and the one after moves them, even when no relayout is due any more; each leaves a
// valid topology; then none runs. Catches a later phase skipped, run early (two in one step) or
// cancelled by the layout fraction, and phases that run on when no relayout is due.
TEST(Layout, PhasesRunInConsecutiveSteps) {
  Params p;
  fast::FastSimulator sim(make_grid(24), p, 2);
  grow_without_relayouts(sim, 60);
  const fast::Topology& m = sim.topology();
  ASSERT_GT(m.V.created, 0);
  ASSERT_FALSE(triangles_in_vertex_order(m));  // splits appended triangles and edges
  ASSERT_FALSE(edges_in_vertex_order(m));
  ASSERT_FALSE(lists_in_vertex_order(m));  // and moved lists to the pools' ends
  sim.set_layout_fraction(0);
  sim.step();
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_EQ(m.V.created, 0);
  int moved = 0;
  for (int v = 0; v < m.V.size(); ++v) moved += m.V.lid[v] != v;
  EXPECT_GT(moved, m.V.size() / 2);
  EXPECT_FALSE(lists_in_vertex_order(m));
  EXPECT_FALSE(triangles_in_vertex_order(m));
  sim.set_layout_fraction(-1);
  // Each property is checked in the step of its phase: the events of a later step may append
  // triangles and edges and move lists again.
  sim.step();
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_TRUE(lists_in_vertex_order(m));
  EXPECT_FALSE(triangles_in_vertex_order(m));
  sim.step();
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_TRUE(triangles_in_vertex_order(m));
  EXPECT_FALSE(edges_in_vertex_order(m));
  sim.step();  // the edges' order only
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_FALSE(edges_in_vertex_order(m));
  sim.set_adaptivity(false, false);  // no edge created or freed between the order and the move
  sim.step();
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_TRUE(edges_in_vertex_order(m));
  EXPECT_EQ(sim.relayout_phases(), 5u);
  // Then no phase runs until the layout is stale again.
  sim.step();
  EXPECT_EQ(sim.relayout_phases(), 5u);
}

// An unbounded budget faults in the whole room of an array of any element size, one-byte ones
// included (alive bytes, decisions). Catches a budget in elements that wraps around for them
// (from + SIZE_MAX / 1), which touched nothing past keep_warm's eighth.
TEST(Array, WarmToWithoutBudgetTouchesTheWholeRoomOfByteArrays) {
  fast::Array<std::uint8_t> bytes;
  bytes.reserve_warm(4 * fast::kHugePage);  // past a huge page: keep_warm warms an eighth only
  bytes.resize(1000);
  ASSERT_LT(bytes.touched(), bytes.capacity());
  bytes.warm_to(bytes.capacity(), SIZE_MAX);
  EXPECT_EQ(bytes.touched(), bytes.capacity());
  fast::Array<std::uint8_t> copy(bytes);
  EXPECT_EQ(copy.touched(), copy.capacity());
}

// make_resident faults in every array's whole room, the steps that follow (relayouts among them,
// whose moves swap arrays with their spares) grow into it without reallocating, and a copy is
// resident too. Catches the large arrays named below left out of Topology::for_each_array, a
// spare made resident short of its array's room, a copy touched only as far as keep_warm's
// eighth, and a mesh that outgrew its reserve (the test would say nothing).
TEST(Resident, EveryArrayKeepsItsWholeRoomFaultedIn) {
  // N = 128: the named arrays' reserves pass a huge page, below which an array keeps all of its
  // room faulted in anyway (Array::keep_warm).
  fast::FastSimulator sim(make_grid(128), paper_params(), 2);
  sim.make_resident();
  const fast::Topology& m = sim.topology();
  auto cold_arrays = [](const fast::Topology& t) {
    std::string cold;
    t.for_each_array([&](const auto& a) {
      if (a.touched() != a.capacity()) cold += std::to_string(a.capacity()) + ' ';
    });
    auto whole = [](const auto& a) { return a.touched() == a.capacity(); };
    if (!(whole(t.V.springs) && whole(t.V.nbrs) && whole(t.V.tris) && whole(t.V.wings) && whole(t.E.slots) &&
          whole(t.E.lid) && whole(t.T.slots) && whole(t.T.alive) && whole(t.records)))
      cold += "named ";
    return cold;
  };
  EXPECT_EQ(cold_arrays(m), "");
  EXPECT_TRUE(sim.layout_scratch().resident(m, 2));
  const std::size_t edges_room = m.E.slots.capacity();
  const int vertices = m.V.size();
  sim.set_layout_fraction(0);  // relayouts through the steps: every move swaps arrays and spares
  for (int step = 0; step < 60; ++step) sim.step();
  ASSERT_GT(m.V.size(), vertices);  // it grew
  ASSERT_GE(sim.relayout_phases(), 10u);
  EXPECT_EQ(m.E.slots.capacity(), edges_room);  // within its reserve
  EXPECT_EQ(cold_arrays(m), "");
  EXPECT_TRUE(sim.layout_scratch().resident(m, 2));
  const fast::FastSimulator copy(sim);
  EXPECT_EQ(cold_arrays(copy.topology()), "");
}

// Pages of [begin, end) the kernel has not mapped (mincore): memory nothing has touched yet.
std::size_t unmapped_pages(const void* begin, const void* end) {
  const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
  const std::uintptr_t from = reinterpret_cast<std::uintptr_t>(begin) / page * page;
  const std::uintptr_t to = reinterpret_cast<std::uintptr_t>(end);
  if (to <= from) return 0;
  std::vector<unsigned char> mapped((to - from + page - 1) / page);
  if (mincore(reinterpret_cast<void*>(from), to - from, mapped.data()) != 0) {
    ADD_FAILURE() << "mincore failed";
    return 0;
  }
  return std::size_t(std::count_if(mapped.begin(), mapped.end(), [](unsigned char c) { return !(c & 1); }));
}

// Unmapped pages in the room of every array of sim's topology and relayout scratch.
std::size_t unmapped_room(const fast::FastSimulator& sim) {
  std::size_t n = 0;
  const auto room = [&](const auto&... a) { ((n += unmapped_pages(a.data(), a.data() + a.capacity())), ...); };
  sim.topology().for_each_array(room);
  const fast::LayoutScratch& s = sim.layout_scratch();
  room(s.vorder, s.vnew, s.eorder, s.enew, s.torder, s.tnew, s.key, s.idx, s.count, s.code, s.code2);
  room(s.spare_heads, s.spare_rows, s.spare_vid, s.spare_eid, s.spare_tid, s.spare_springs, s.spare_nbrs,
       s.spare_tris, s.spare_wings, s.spare_edges, s.spare_faces, s.spare_alive);
  return n;
}

// make_resident maps every page of the arrays' room, not only their bookkeeping: what mincore
// sees after it. Catches a make_resident that claims the ranges and leaves some untouched (the
// claims and the parallel touch are separate steps), which the bookkeeping tests above pass.
// The room must have unmapped pages before, or the test could not tell (an allocator handing
// back memory it had mapped already).
TEST(Resident, EveryPageOfTheRoomIsMapped) {
  fast::FastSimulator sim(make_grid(128), paper_params(), 2);
  ASSERT_GT(unmapped_room(sim), 0u) << "the room was mapped before make_resident: nothing to test";
  sim.make_resident();
  EXPECT_EQ(unmapped_room(sim), 0u);
}

// A step that runs no relayout phase faults in the topology's growth room towards the point
// Array::keep_warm keeps it at (warm_target: an eighth of its room ahead of its elements): after
// such a step no array is short of its warm_floor (half that), and all reach their warm target
// in most steps; after a relayout some lag (its phases' steps claim none) and the budget claims
// the lag over the next steps. So the growth finds its room touched, and keep_warm never faults
// in a whole eighth at once inside a step. The same step faults in part of what the next
// relayout will write: the relayout scratch's cold bytes shrink. Catches the growth room left to
// keep_warm or a topology array left out of FastSimulator::warm_ahead (they never reach their
// warm target: the step scratch's arrays are not reachable from here), the lag claimed at once
// (no step lags), and warm_ahead leaving the relayout's scratch out.
TEST(WarmAhead, EveryStepWithoutARelayoutLeavesTheGrowthRoomTouched) {
  // N = 128: the adjacency pools' and the edges' reserves pass a huge page, below which an array
  // keeps all of its room faulted in anyway.
  fast::FastSimulator sim(make_grid(128), paper_params(), 2);
  const fast::Topology& m = sim.topology();
  const int vertices = m.V.size();
  int checked = 0, relayout_warmed = 0, caught_up = 0, lagged = 0;
  for (int step = 0; step < 90; ++step) {
    const std::uint64_t phases = sim.relayout_phases();
    const std::size_t next_cold = sim.layout_scratch().cold_bytes(m, 2);
    sim.step();
    if (sim.relayout_phases() != phases) continue;
    if (next_cold > 0) {
      // A step claims at least a huge page, more than its growth adds to the cold part (all
      // within the reserve: an array reallocated past it would turn its whole spare cold).
      EXPECT_LT(sim.layout_scratch().cold_bytes(m, 2), next_cold) << "step " << step;
      ++relayout_warmed;
    }
    std::string short_of_floor;
    bool lagging = false;
    m.for_each_array([&](const auto& a) {
      if (a.touched() < a.warm_floor()) short_of_floor += std::to_string(a.capacity()) + ' ';
      lagging |= a.touched() < a.warm_target();
    });
    EXPECT_EQ(short_of_floor, "") << "step " << step;
    ++(lagging ? lagged : caught_up);
    ++checked;
  }
  ASSERT_GT(m.V.size(), vertices + vertices / 50);  // it grew
  ASSERT_GT(checked, 60);
  ASSERT_GT(relayout_warmed, 2);
  ASSERT_GT(caught_up, 50);
  ASSERT_GT(lagged, 0);  // the lag after a relayout, claimed over steps
}

// Grows sim without relayouts, then runs a relayout's first four phases (through the edges'
// order) with relayouts off after them: the next step moves the edges, and no other starts.
void stop_before_the_edges_move(fast::FastSimulator& sim) {
  grow_without_relayouts(sim, 60);
  sim.set_layout_fraction(0);
  for (int phase = 0; phase < 4; ++phase) sim.step();
  sim.set_layout_fraction(-1);
}

// make_resident called between the edges' order and their move (the one point where the
// relayout's scratch holds what the next phase reads) faults the scratch in and keeps the
// order. Catches a call that skips the scratch within a relayout, and one that empties the
// orders (the move would then not sort the edges, or break the topology); a reserve that
// drops the elements only where room is lacking is Layout.ClaimWholeKeepsTheScratchsElements'.
TEST(Resident, BetweenTheEdgesOrderAndTheirMoveKeepsTheOrder) {
  fast::FastSimulator sim(make_grid(128), paper_params(), 2);
  const fast::Topology& m = sim.topology();
  stop_before_the_edges_move(sim);
  ASSERT_EQ(sim.relayout_phases(), 4u);
  ASSERT_FALSE(sim.layout_scratch().resident(m, 2));
  sim.make_resident();
  EXPECT_TRUE(sim.layout_scratch().resident(m, 2));
  sim.set_adaptivity(false, false);  // no edge created or freed between the order and the move
  sim.step();
  ASSERT_EQ(sim.relayout_phases(), 5u);
  ASSERT_EQ(sim.check_topology(), "");
  EXPECT_TRUE(edges_in_vertex_order(m));
}

// The edges' order is taken a step before the edges move (phases four and five), so the events
// of the step between create and free edges that the order does not know: the move must still
// be a valid permutation of every slot (the new slots last), and every other edge must follow
// its lower endpoint. Each edge created or freed in between (three a split or a restore) breaks
// the order in at most two places. Catches new slots left out of the move (an invalid
// topology, or a throw) and an order that is not applied.
TEST(Layout, EdgesCreatedBetweenTheirOrderAndTheirMoveGoLast) {
  Params p;
  fast::FastSimulator sim(make_grid(24), p, 2);
  stop_before_the_edges_move(sim);
  const fast::Topology& m = sim.topology();
  ASSERT_EQ(sim.relayout_phases(), 4u);
  const int before = m.E.size();
  const StepEvents ev = sim.step();
  ASSERT_EQ(sim.relayout_phases(), 5u);
  ASSERT_EQ(sim.check_topology(), "");
  ASSERT_GT(ev.splits, 0);
  EXPECT_GT(m.E.size(), before);
  EXPECT_LE(edge_order_descents(m), 2 * 3 * (ev.splits + ev.restores));
  EXPECT_GT(m.E.size(), 20 * 2 * 3 * (ev.splits + ev.restores));  // so that the bound says something
}

// A clone taken between the edges' order and their move (phases four and five) carries the
// order with it: it steps on to the original's slots and state bit for bit. Catches a copy of
// the relayout's scratch that keeps the room but not the order (the clone's move would throw or
// put the edges elsewhere) and a clone that restarts the relayout.
TEST(Layout, ACloneBetweenTheEdgesOrderAndTheirMoveStepsAsTheOriginal) {
  Params p;
  fast::FastSimulator sim(make_grid(24), p, 2);
  stop_before_the_edges_move(sim);
  fast::FastSimulator copy(sim);
  for (fast::FastSimulator* s : {&sim, &copy}) {
    s->step();
    s->step();
    ASSERT_EQ(s->relayout_phases(), 5u);
    ASSERT_EQ(s->check_topology(), "");
  }
  const fast::Topology &a = sim.topology(), &b = copy.topology();
  ASSERT_EQ(a.E.size(), b.E.size());
  for (int e = 0; e < a.E.size(); ++e) ASSERT_EQ(a.E.lid[e], b.E.lid[e]) << e;
  ASSERT_EQ(a.V.size(), b.V.size());
  for (int v = 0; v < a.V.size(); ++v) {
    ASSERT_EQ(a.V.lid[v], b.V.lid[v]) << v;
    ASSERT_EQ(std::memcmp(&a.V.xm[v], &b.V.xm[v], sizeof(fast::Float4)), 0) << v;
  }
}

// After LayoutScratch::warm a relayout writes only memory that warm faulted in: no spare or
// order scratch is reallocated, each is written within its touched part, and an array that
// takes a spare's buffer finds the room ahead already warm (its keep_warm touches nothing).
// Catches a spare or a scratch array left out of warm (it is reallocated at the relayout, or
// written past its touched part) and targets short of what the relayout writes.
TEST(Layout, RelayoutAfterWarmWritesOnlyWarmedMemory) {
  Params p;
  fast::FastSimulator sim(make_grid(40), p, 2);
  grow_without_relayouts(sim, 60);
  fast::Topology m = sim.topology();  // grown by splits since its last relayout
  ASSERT_GT(m.V.created, 0);
  fast::LayoutScratch s;
  const fast::Parallel par(2);
  EXPECT_GT(s.cold_bytes(m, 2), 0u);
  s.warm(m, par, SIZE_MAX);
  EXPECT_EQ(s.cold_bytes(m, 2), 0u);
  std::map<const void*, std::size_t> warmed;  // buffer -> elements touched
  const auto note = [&](const auto&... a) { ((warmed[a.data()] = a.touched()), ...); };
  note(s.spare_rows, s.spare_heads, s.spare_vid, s.spare_springs, s.spare_nbrs, s.spare_tris, s.spare_wings,
       s.spare_faces, s.spare_tid, s.spare_alive, s.spare_edges, s.spare_eid);
  note(s.vorder, s.vnew, s.idx, s.code, s.code2, s.eorder, s.enew, s.torder, s.tnew, s.key, s.count);
  fast::relayout(m, par, s);
  ASSERT_EQ(m.check(), "");
  const auto within = [&](const char* name, const auto& a) {
    const auto it = warmed.find(a.data());
    ASSERT_NE(it, warmed.end()) << name << " is in a buffer warm did not prepare";
    EXPECT_LE(a.size(), it->second) << name;
    EXPECT_EQ(a.touched(), it->second) << name << ": its room ahead was faulted in by the relayout";
  };
  within("xm", m.V.xm), within("spring heads", m.V.spring_list), within("vertex ids", m.V.lid);
  within("springs", m.V.springs), within("nbrs", m.V.nbrs), within("tris", m.V.tris), within("wings", m.V.wings);
  within("faces", m.T.slots), within("triangle ids", m.T.lid), within("alive", m.T.alive);
  within("edges", m.E.slots), within("edge ids", m.E.lid);
  // The orders' scratch swaps buffers among itself (the radix sort's passes), so each is
  // looked up by its buffer.
  const auto reused = [&](const auto& a) {
    const auto it = warmed.find(a.data());
    ASSERT_NE(it, warmed.end()) << "an order's scratch was reallocated";
    EXPECT_LE(a.size(), it->second);
  };
  reused(s.vorder), reused(s.vnew), reused(s.idx), reused(s.code), reused(s.code2);
  reused(s.eorder), reused(s.enew), reused(s.torder), reused(s.tnew), reused(s.key), reused(s.count);
}

// Splits and restores applied in parallel rounds and waves of vertex-disjoint events against
// the same events applied one after the other in event order: bit-identical states through a
// crumple with thousands of splits and restores, on one thread (rounds and waves run as plain
// loops) and on two (in parallel).
TEST(FastTopology, ParallelRoundsAndWavesEqualSerialEdits) {
  Params p;
  for (int threads : {1, 2}) {
    std::uint64_t large_rounds = 0, large_waves = 0;
    auto run = [&](bool serial, std::vector<StepEvents>& events) {  // one simulator at a time
      // 48 x 48: some rounds of over 64 splits, which run as parallel loops (smaller ones inline).
      fast::FastSimulator sim(make_grid(48), p, threads);
      sim.set_serial_edits(serial);
      for (int f = 0; f < 110; ++f) events.push_back(sim.step());
      EXPECT_EQ(sim.check_topology(), "");
      if (!serial) large_rounds = sim.large_rounds(), large_waves = sim.large_waves();
      return sim.snapshot();
    };
    std::vector<StepEvents> ea, eb;
    const Snapshot rounds = run(false, ea), serial = run(true, eb);
    long splits = 0, restores = 0;
    ASSERT_NO_FATAL_FAILURE(same_events(ea, eb, splits, restores));
    EXPECT_GT(splits, 2000);
    EXPECT_GT(restores, 500);
    EXPECT_GT(large_rounds, 10u);  // the parallel paths did run
    EXPECT_GT(large_waves, 0u);
    EXPECT_TRUE(same_snapshot(rounds, serial)) << threads << " threads";
  }
}

// The rounds and waves renew each event's normals as it applies (a vertex at its last split of
// the pass, after that split read it, and at each restore), the serial edits after all events:
// after every pass with events the stored normals are those of a full recomputation on the new
// topology, bit for bit, on one thread and two. Catches a vertex of an event left out (a wing's,
// the new vertex's, a restore's), a renewal before the vertex's last split, and a tally whose
// rounds make_room reset (no split then counts as a vertex's last). Splits whose end had an
// earlier split of the pass must occur, or renewing at every split would pass unseen here (it
// fails ParallelRoundsAndWavesEqualSerialEdits, which compares what the splits read).
TEST(FastTopology, EventsLeaveTheNormalsOfTheNewTopology) {
  for (const bool serial : {false, true})
    for (int threads : {1, 2}) {
      fast::FastSimulator sim(make_grid(48), Params{}, threads);
      sim.set_serial_edits(serial);
      long passes = 0, splits = 0, restores = 0, ends_split_before = 0;
      for (int f = 0; f < 110 && !HasFailure(); ++f) {
        const StepEvents ev = sim.step();
        if (ev.splits + ev.restores == 0) continue;  // no event: the adapt pass may not have run
        ++passes, splits += ev.splits, restores += ev.restores;
        const std::vector<fast::SplitRounds::Applied> rounds = sim.split_rounds_applied();  // none if serial
        std::map<int, int> first_round;  // vertex -> round of its first split this pass
        for (const fast::SplitRounds::Applied& a : rounds)
          for (int q = 0; q < 4; ++q)
            if (a.verts[q] >= 0) first_round.try_emplace(a.verts[q], a.round);
        for (const fast::SplitRounds::Applied& a : rounds)
          ends_split_before += first_round[a.verts[0]] < a.round || first_round[a.verts[1]] < a.round;
        const std::vector<Vec3d> fresh = sim.normals();  // recomputed from scratch on a copy
        const std::vector<bool> alive = sim.snapshot().vertex_alive;
        const fast::Topology& m = sim.topology();
        for (int id = 0; id < int(fresh.size()); ++id) {
          if (!alive[std::size_t(id)]) continue;
          const fast::Float4 n = m.V.nr[m.V.phys[id]];
          ASSERT_EQ(Vec3d({n.x, n.y, n.z}), fresh[std::size_t(id)])
              << "vertex " << id << ", frame " << f << ", " << threads << " threads" << (serial ? ", serial" : "");
        }
      }
      EXPECT_GT(passes, 50);
      EXPECT_GT(splits, 2000);
      EXPECT_GT(restores, 500);
      if (!serial) {
        EXPECT_GT(ends_split_before, 100) << threads << " threads";
      }
    }
}

// Events of one pass applied in groups that run in parallel (split rounds, restore waves): no
// two events of a group share a vertex, and the events at each vertex come in event order
// across the groups. Returns the events in later groups (those that waited). T has event,
// verts and the group as member `group`.
template <class T, class Group>
long check_vertex_disjoint_groups(std::vector<T> events, Group group, int frame) {
  std::sort(events.begin(), events.end(),
            [&](const T& a, const T& b) { return std::pair(group(a), a.event) < std::pair(group(b), b.event); });
  std::map<int, std::pair<int, int>> last;  // vertex -> group and event of its latest event so far
  long later = 0;
  for (const T& r : events) {
    for (int v : r.verts) {
      if (v < 0) continue;
      if (auto it = last.find(v); it != last.end()) {
        EXPECT_LT(it->second.first, group(r)) << "two events of one group at vertex " << v << ", frame " << frame;
        EXPECT_LT(it->second.second, r.event) << "events out of event order at vertex " << v << ", frame " << frame;
      }
      last[v] = {group(r), r.event};
    }
    later += group(r) > group(events.front());
  }
  return later;
}

// The waves' own rule, which the comparison above cannot see: restores that share a vertex give
// the serial result even in one wave whenever the wave runs them in event order, as it does on
// one thread. No two restores of a wave share a vertex, and the restores at each vertex come in
// event order across the waves. A scan that lets nothing wait, or a waiting candidate that
// claims no vertices (a later one at its vertices goes first), fails it.
TEST(FastTopology, RestoreWavesShareNoVertexAndKeepEventOrder) {
  fast::FastSimulator sim(make_grid(48), Params{}, 2);
  long applied = 0, later_waves = 0;
  for (int f = 0; f < 110 && !HasFailure(); ++f) {
    sim.step();
    const std::vector<fast::RestoreWaves::Applied> restores = sim.restore_waves_applied();
    if (restores.empty()) continue;
    later_waves += check_vertex_disjoint_groups(restores, [](const auto& r) { return r.wave; }, f);
    applied += long(restores.size());
  }
  EXPECT_GT(applied, 500);
  EXPECT_GT(later_waves, 20);  // restores did share vertices and wait
}

// The same rule for the split rounds (DECISIONS.md D13), which the comparison with the serial
// edits sees only through races on two threads: a round rule that put every split in one round
// passed ParallelRoundsAndWavesEqualSerialEdits. Catches rounds that ignore a vertex (a wing's,
// say) or put every split in the first round.
TEST(FastTopology, SplitRoundsShareNoVertexAndKeepEventOrder) {
  fast::FastSimulator sim(make_grid(48), Params{}, 2);
  long applied = 0, later_rounds = 0;
  for (int f = 0; f < 110 && !HasFailure(); ++f) {
    sim.step();
    const std::vector<fast::SplitRounds::Applied> splits = sim.split_rounds_applied();
    if (splits.empty()) continue;
    later_rounds += check_vertex_disjoint_groups(splits, [](const auto& r) { return r.round; }, f);
    applied += long(splits.size());
  }
  EXPECT_GT(applied, 3000);
  EXPECT_GT(later_rounds, 300);  // splits did share vertices and wait
}

// A restore candidate's answer on the state after the pass's splits holds through the pass
// (DECISIONS.md D14), so the waves test each candidate once; the serial oracle tests each at its
// turn on the state the earlier restores left. Both agree over seeds and both configurations
// on one thread, where the waves' parallel loops run in order: a restore that changed another
// candidate's answer would show here, as does a waiting candidate that claims no vertices.
TEST(FastTopology, RestoreAnswersHoldThroughThePass) {
  for (const bool paper : {false, true})
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      Params p = paper ? paper_params() : Params{};
      p.seed = seed;
      auto run = [&](bool serial, std::vector<StepEvents>& events) {
        fast::FastSimulator sim(make_grid(32), p, 1);
        sim.set_serial_edits(serial);
        for (int f = 0; f < 90; ++f) events.push_back(sim.step());
        return sim.snapshot();
      };
      std::vector<StepEvents> ea, eb;
      const Snapshot waves = run(false, ea), serial = run(true, eb);
      long splits = 0, restores = 0;
      ASSERT_NO_FATAL_FAILURE(same_events(ea, eb, splits, restores));
      EXPECT_GT(restores, 30) << "seed " << seed;
      EXPECT_TRUE(same_snapshot(waves, serial)) << (paper ? "paper" : "default") << ", seed " << seed;
    }
}

// A split undone at once gives back the mesh exactly: every vertex's spring and triangle lists
// in the same order with the same parallel entries, every edge record and every triangle's
// corners and sides in the same rotation (the split rewrites its two triangles' entries in place
// and the restore rewrites them back, fast_edits.cpp). Every edge of a small grid, boundary ones
// included. Catches: an edit that erases and re-appends an entry (the list's order changes), a
// wrong wing edge or side left behind, a triangle stored in another rotation.
TEST(FastTopology, SplitUndoneGivesBackEveryListInOrder) {
  Params p;
  fast::FastSimulator sim(make_grid(6), p, 1);
  const fast::Topology& m = sim.topology();
  auto lists = [&m](int v) {
    const fast::ListHead s = m.V.spring_list[v], t = m.V.tri_list[v];
    std::vector<std::int32_t> out;
    for (int k = 0; k < s.count; ++k) out.push_back(m.springs_of(v)[k]), out.push_back(m.nbrs_of(v)[k]);
    out.push_back(-1);
    for (int k = 0; k < t.count; ++k) out.push_back(m.tris_of(v)[k]), out.push_back(m.wings_of(v)[k]);
    return out;
  };
  auto edge = [&m](int e) {
    const fast::EdgeRecord& r = m.E[e];
    return std::vector<double>{double(r.a), double(r.b), double(r.wl), double(r.wr), double(r.tri0), double(r.tri1),
                               double(r.l0), double(r.record), double(r.flags)};
  };
  const int nv = m.V.size(), ne = m.E.size(), nt = m.T.size();
  for (int e = 0; e < ne; ++e) {
    std::vector<std::vector<std::int32_t>> before_lists;
    std::vector<std::vector<double>> before_edges;
    std::vector<fast::Face> before_faces(m.T.slots.begin(), m.T.slots.begin() + nt);
    for (int v = 0; v < nv; ++v) before_lists.push_back(lists(v));
    for (int k = 0; k < ne; ++k) before_edges.push_back(edge(k));
    ASSERT_TRUE(sim.split(e)) << e;
    ASSERT_EQ(sim.check_topology(), "") << e;
    ASSERT_TRUE(sim.restore(e)) << e;
    ASSERT_EQ(sim.check_topology(), "") << e;
    for (int v = 0; v < nv; ++v) ASSERT_EQ(lists(v), before_lists[v]) << "edge " << e << ", vertex " << v;
    for (int k = 0; k < ne; ++k) ASSERT_EQ(edge(k), before_edges[k]) << "edge " << e << ", edge " << k;
    for (int t = 0; t < nt; ++t) {
      ASSERT_EQ(m.T[t].v, before_faces[t].v) << "edge " << e << ", triangle " << t;
      ASSERT_EQ(m.T[t].e, before_faces[t].e) << "edge " << e << ", triangle " << t;
    }
  }
}

// Issue 14, defect 1: adjacency memory followed the largest valence (one stride for every
// vertex), so a fan disk with one vertex of valence 10,000 needed gigabytes. With per-vertex blocks
// the pools hold about kMinRoom entries per vertex plus the hub's own list (about twice it,
// doubling leaves the smaller blocks behind), before and after a relayout repacks them.
// Catches: a per-vertex stride sized by the largest list; a repack that leaves garbage or
// sizes blocks by anything but each vertex's own count.
TEST(FastTopology, AdjacencyMemoryFollowsEachVertexsValence) {
  constexpr int kRim = 10000;
  InputMesh fan;
  fan.positions.push_back({0, 0, 0});
  for (int k = 0; k < kRim; ++k) {
    const double a = 2 * M_PI * k / kRim;
    fan.positions.push_back({std::cos(a), std::sin(a), 0});
  }
  for (int k = 0; k < kRim; ++k) fan.triangles.push_back({0, 1 + k, 1 + (k + 1) % kRim});
  Params p;
  p.fracture = false;  // one frame of the hub's springs, no refinement needed
  fast::FastSimulator sim(fan, p, 2);
  const fast::Vertices& V = sim.topology().V;
  const double nv = V.size();
  const double bound = 2 * fast::kMinRoom * nv + 4.0 * kRim;
  EXPECT_LT(double(V.springs.size()), bound);
  EXPECT_LT(double(V.tris.size()), bound);
  sim.step();
  ASSERT_EQ(sim.check_topology(), "");
  sim.run_pass(fast::Pass::Layout);
  ASSERT_EQ(sim.check_topology(), "");
  std::size_t want_e = 0, want_t = 0;
  for (int v = 0; v < V.size(); ++v) want_e += fast::room_for(V.spring_list[v].count), want_t += fast::room_for(V.tri_list[v].count);
  EXPECT_EQ(V.springs.size(), want_e);
  EXPECT_EQ(V.tris.size(), want_t);
  EXPECT_EQ(V.garbage_e + V.garbage_t, 0);
}

// The topology check sees the pools: a block that overlaps another, or a count past its room,
// is reported (it guards every edit of the tests above). Catches: a check_blocks that accepts
// overlapping or overfull blocks.
TEST(FastTopology, CheckFindsOverlappingAndOverfullBlocks) {
  const fast::FastSimulator sim(make_grid(6), Params{}, 1);
  ASSERT_EQ(sim.topology().check(), "");
  fast::Topology overlap = sim.topology();
  overlap.V.spring_list[1].at = overlap.V.spring_list[0].at + 1;
  EXPECT_NE(overlap.check().find("overlap"), std::string::npos) << overlap.check();
  fast::Topology overfull = sim.topology();
  overfull.V.tri_list[3].count = std::uint16_t(overfull.V.tri_list[3].room + 1);
  EXPECT_NE(overfull.check().find("block"), std::string::npos) << overfull.check();
}

}  // namespace
}  // namespace crumple::test
