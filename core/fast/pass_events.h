// What the topology pass's two units (split_rounds.h, restore_waves.h) and one event's edits
// (fast_edits.cpp) hand each other: the candidates and plans of splits and restores, the
// stamps that mark the triangles an accepted event of this pass changed (MODEL.md §4: an event
// is skipped when an earlier one of the pass changed one of its triangles), and the pass's
// shared loops (the byte scan of the decisions, the grouping of rounds and waves).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <iterator>
#include <vector>

#if defined(__AVX2__) && !CRUMPLE_DISABLE_SIMD
#include <immintrin.h>
#endif

#include "fast/aligned.h"

namespace crumple::fast {

/// What a split of edge e needs to know before it is planned (read in parallel).
struct SplitCandidate {
  int e = -1;                               ///< the edge (-1: not splittable)
  float flat_draw = 0;                      ///< the FlatSign draw of [Eq 7]
  std::array<int, 2> tris{-1, -1};          ///< tri0, tri1 at the start of the pass
  std::array<int, 4> ends{-1, -1, -1, -1};  ///< i, j, l, r (-1: no wing)
};

/// A split with its new ids taken in advance (serially, in event order), so that splits of
/// disjoint vertex sets can then apply in parallel.
struct SplitPlan {
  int e = -1;                                ///< the edge (-1: not splittable)
  float flat_draw = 0;                       ///< the FlatSign draw of [Eq 7]
  std::array<int, 4> ends{-1, -1, -1, -1};   ///< i, j, l, r (-1: no wing)
  int n = -1;                                ///< the new vertex
  std::array<int, 4> edges{-1, -1, -1, -1};  ///< e_in, e_nj, e_ln, e_nr
  std::array<int, 2> tris{-1, -1};           ///< (n,j,l), (n,i,r)
  int record = -1;                           ///< the split record
};

constexpr int kByteLine = 64;  ///< bytes a scan tests at once: one cache line

/// Bit k set where p[k] == value, for the kByteLine bytes at p.
inline std::uint64_t bytes_equal(const std::uint8_t* p, std::uint8_t value) {
#if defined(__AVX2__) && !CRUMPLE_DISABLE_SIMD
  const __m256i v = _mm256_set1_epi8(char(value));
  const __m256i lo = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  const __m256i hi = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32));
  const std::uint32_t mlo = std::uint32_t(_mm256_movemask_epi8(_mm256_cmpeq_epi8(lo, v)));
  const std::uint32_t mhi = std::uint32_t(_mm256_movemask_epi8(_mm256_cmpeq_epi8(hi, v)));
  return std::uint64_t(mhi) << 32 | mlo;
#else
  std::uint64_t mask = 0;
  for (int k = 0; k < kByteLine; ++k) mask |= std::uint64_t(p[k] == value) << k;
  return mask;
#endif
}

/// Calls f(k), in order, for each k in [begin, end) where bytes[k] == value (equal) or
/// bytes[k] != value (!equal). The bytes sought are few (a pass's events among every edge): a
/// line of bytes is tested at once, and only its matches are visited.
template <bool equal, class F>
void for_each_byte(const std::uint8_t* bytes, std::uint8_t value, int begin, int end, F&& f) {
  int k = begin;
  for (; k + kByteLine <= end; k += kByteLine)
    for (std::uint64_t m = equal ? bytes_equal(bytes + k, value) : ~bytes_equal(bytes + k, value); m; m &= m - 1)
      f(k + std::countr_zero(m));
  for (; k < end; ++k)
    if ((bytes[k] == value) == equal) f(k);
}

/// Orders the items 0..n-1 by group (group(k) in [0, groups)), in item order within a group
/// (a counting sort): the rounds and waves of the topology pass, in event order within each.
/// order gets the items; group g's are order[first[g], first[g + 1]).
template <class Group>
void order_by_group(int n, int groups, Group group, std::vector<int>& first, std::vector<int>& order) {
  first.assign(std::size_t(groups) + 2, 0);
  for (int k = 0; k < n; ++k) ++first[std::size_t(group(k)) + 2];
  for (int g = 2; g <= groups + 1; ++g) first[g] += first[g - 1];
  order.resize(std::size_t(n));
  // first[g + 1] is group g's fill position here, and its end (group g + 1's first) after.
  for (int k = 0; k < n; ++k) order[first[std::size_t(group(k)) + 1]++] = k;
  first.pop_back();
}

/// The elements a pass has marked: the triangles its accepted events changed. A pass's tag, not
/// a flag: a new pass forgets the last one's marks without clearing an array the size of the
/// mesh. One byte an element, so that the stamps read at random (a restore candidate's four
/// triangles) are a small array that stays in the caches; the tags cycle through 1-255, and the
/// array is cleared once a cycle, before a tag comes round again.
class PassStamps {
 public:
  void reserve(std::size_t elements) { stamp_.reserve_warm(elements); }
  /// Claims the whole room for the caller to touch (FastSimulator::make_resident).
  void claim_whole(ColdClaims& claims) { claims.whole(stamp_); }
  /// Starts a pass: nothing is marked yet.
  void begin_pass() {
    tag_ = std::uint8_t(tag_ % kTags + 1);
    if (tag_ == 1) std::fill(stamp_.begin(), stamp_.end(), std::uint8_t(0));
  }
  /// Element t (-1: none) was marked by this pass.
  bool touched(int t) const { return t >= 0 && t < int(stamp_.size()) && stamp_[t] == tag_; }
  /// Some triangle of `tris` (a split record's slots, say) was changed by this pass.
  template <class Range>
  bool any_touched(const Range& tris) const {
    return std::any_of(std::begin(tris), std::end(tris), [this](int t) { return touched(t); });
  }
  /// Marks element t (-1: none) for this pass. Serial, but for elements below cover()'s count,
  /// which distinct events may mark in parallel (one stamp each, no growth).
  void mark(int t) {
    if (t < 0) return;
    if (t >= int(stamp_.size())) cover(std::size_t(t) + 1);
    stamp_[t] = tag_;
  }
  /// Room for the stamps of the first `elements` slots. Growing by an eighth at least keeps the
  /// growth's fill off the per-event path (a stamp of 0 is an unmarked element, so slots past
  /// the mesh's are harmless).
  void cover(std::size_t elements) {
    if (elements > stamp_.size()) stamp_.resize(std::max(elements, stamp_.size() + stamp_.size() / 8), 0);
  }
  /// For prefetching t's stamp ahead of a mark or a test (nullptr past the array).
  const std::uint8_t* line_of(int t) const { return t >= 0 && t < int(stamp_.size()) ? &stamp_[t] : nullptr; }

 private:
  static constexpr int kTags = 255;  ///< 0 is no pass's tag
  Array<std::uint8_t> stamp_;        ///< tag of the pass that last marked each element
  std::uint8_t tag_ = 0;
};

}  // namespace crumple::fast
