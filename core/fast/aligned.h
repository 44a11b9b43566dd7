// Cache-line aligned storage for the structure-of-arrays state: every attribute is one
// contiguous array, 64-byte aligned so that AVX-512 loads of a lane group never split a line,
// large arrays on transparent huge pages.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

namespace crumple::fast {

/// Arrays of at least this many bytes start on a huge-page boundary and ask the kernel for
/// transparent huge pages (madvise mode, Debian's default, gives them only to memory that asks):
/// the passes and the events read the large arrays at random, and with 4 KiB pages nearly every
/// such read also misses the TLB (the L2 TLB maps a few MB; the state of N = 256 is ~100 MB).
constexpr std::size_t kHugePage = std::size_t(2) << 20;

/// Allocation of `bytes` bytes, 64-byte aligned (huge-page aligned and advised when large).
void* allocate_aligned(std::size_t bytes);
void free_aligned(void* p, std::size_t bytes);
/// Faults in the pages of [begin, end) by writing a zero byte to each: for room that holds no
/// element yet (its content is left to whatever constructs the elements there).
void touch_pages(void* begin, void* end);

/// Bytes [begin, end) of an array's room that nothing has touched yet: what touch_pages faults in.
struct ColdRange {
  char* begin = nullptr;
  char* end = nullptr;
  std::size_t bytes() const { return std::size_t(end - begin); }
};

template <class T>
struct AlignedAllocator {
  using value_type = T;
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_aligned(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) { free_aligned(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

/// One attribute of the SoA state. A copy keeps the room reserved in the original (a plain
/// vector copy would not), so a clone of a simulator appends without reallocating, as the
/// original does: the benchmarks time frames of clones. Part of the room ahead of the elements
/// is kept faulted in (an eighth of the capacity: some twenty frames of a crumple's growth; all
/// of it when it is smaller than a huge page: warm_target), so that growth into it does not
/// page-fault inside a step. The fast backend's steps touch it ahead on all threads, within a
/// budget (claim_cold, FastSimulator::warm_ahead); keep_warm touches the next part when growth
/// has used up what was touched (docs/DECISIONS.md D16).
template <class T>
class Array : public std::vector<T, AlignedAllocator<T>> {
  using Base = std::vector<T, AlignedAllocator<T>>;

 public:
  using Base::Base;
  Array() = default;
  Array(const Array& o) : Base() { *this = o; }
  Array& operator=(const Array& o) {
    if (this != &o) {
      this->reserve(o.capacity());
      this->assign(o.begin(), o.end());
      keep_warm();
      warm_to(o.touched(), SIZE_MAX);  // as far as the original's room is faulted in
    }
    return *this;
  }
  /// std::vector's reserve, which moves the elements to new room that nothing has touched yet.
  void reserve(std::size_t n) {
    if (n <= this->capacity()) return;
    Base::reserve(n);
    warmed_ = 0;
  }
  /// Reserves room for n elements, the first part of it faulted in (see the class comment).
  void reserve_warm(std::size_t n) {
    this->reserve(n);
    keep_warm();
  }
  void swap(Array& o) noexcept {
    Base::swap(o);
    std::swap(warmed_, o.warmed_);
  }
  /// Elements [0, touched()) of the room are faulted in (the elements and the room warmed ahead).
  std::size_t touched() const { return std::max(this->size(), warmed_); }
  /// Faults in the room up to element `target` (at most the capacity), at most `budget` bytes
  /// of it, and on huge pages on to the end of the huge page it ends in (huge_page_end): memory
  /// that a later step will write, faulted in ahead. Returns the bytes it touched.
  std::size_t warm_to(std::size_t target, std::size_t budget) {
    const ColdRange cold = claim_cold(target, budget);
    touch_pages(cold.begin, cold.end);
    return cold.bytes();
  }
  /// The room warm_to(target, budget) would fault in, counted as faulted in from now on: the
  /// caller touches it (LayoutScratch::warm and FastSimulator::warm_ahead touch many arrays'
  /// ranges on every thread: touch_pages in parallel.h).
  ColdRange claim_cold(std::size_t target, std::size_t budget) {
    const std::size_t from = touched(), capacity = this->capacity();
    if (from >= capacity) return {};
    // The budget in elements, at most the room left: from + SIZE_MAX / sizeof(T) would wrap
    // for one-byte elements (an unbounded budget) and touch nothing.
    const std::size_t to = std::min({target, capacity, from + std::min(budget / sizeof(T), capacity - from)});
    if (to <= from) return {};
    warmed_ = huge_page_end(to);
    return {reinterpret_cast<char*>(this->data() + from), reinterpret_cast<char*>(this->data() + warmed_)};
  }
  /// Where a claim ending at element `to` ends on huge pages: the first touch of a huge page
  /// maps all of it, so a claim runs on to the last element that ends within the huge page of
  /// its last byte (at most the capacity, never into the next huge page). The bytes a claim
  /// returns are then the bytes its touch faults in, and a budget bounds the faults (a budget
  /// of small claims spread over many arrays would otherwise map a huge page for each). A room
  /// under a huge page (on 4 KiB pages: allocate_aligned) ends where it ended.
  std::size_t huge_page_end(std::size_t to) const {
    if (this->capacity() * sizeof(T) < kHugePage) return to;
    const std::uintptr_t base = reinterpret_cast<std::uintptr_t>(this->data());
    const std::uintptr_t boundary = ((base + to * sizeof(T) - 1) / kHugePage + 1) * kHugePage;
    return std::min(this->capacity(), std::size_t(boundary - base) / sizeof(T));
  }
  /// The bytes short of `target` (warm_to(target) touches them, and on huge pages up to the
  /// end of the last one).
  std::size_t cold_bytes(std::size_t target) const {
    const std::size_t to = std::min(target, this->capacity()), from = touched();
    return to > from ? (to - from) * sizeof(T) : 0;
  }
  /// Where keep_warm keeps room on huge pages faulted in to: an eighth of the capacity ahead of
  /// the elements (some twenty frames of a crumple's growth).
  std::size_t eighth_ahead() const { return std::min(this->capacity(), this->size() + this->capacity() / 8); }
  /// The room a budgeted fault-in claims first, whatever its budget (FastSimulator::warm_ahead):
  /// a sixteenth of the capacity ahead of the elements, half of what warm_target keeps, so that
  /// growth never reaches cold room while the budget catches up.
  std::size_t warm_floor() const { return std::min(warm_target(), this->size() + this->capacity() / 16); }
  /// How far the room is kept faulted in: eighth_ahead(), or the whole room when it is smaller
  /// than a huge page (it is on small pages, whose faults cost the most: docs/PERFORMANCE.md,
  /// and it holds at most kHugePage bytes).
  std::size_t warm_target() const {
    const bool small_pages = this->capacity() * sizeof(T) < kHugePage;
    return small_pages ? this->capacity() : eighth_ahead();
  }
  /// Faults in the room ahead of the elements once growth has used up what was touched.
  void keep_warm() {
    const std::size_t n = this->size();
    if (n < warmed_ && warmed_ <= this->capacity()) return;
    warmed_ = warm_target();
    // A write a page, not a value-initialization of every element of the room: the elements are
    // initialized when growth constructs them.
    touch_pages(this->data() + n, this->data() + warmed_);
  }

 private:
  std::size_t warmed_ = 0;  ///< elements [size, warmed_) of the room are faulted in
  Array(Array&&) noexcept = default;
  Array& operator=(Array&&) noexcept = default;
};

/// Claims of cold room from arrays in turn within a budget of bytes (the claims' bytes: on huge
/// pages the bytes their touch faults in, Array::huge_page_end), collected for one touch_pages
/// loop. Once the budget is spent the next arrays claim nothing: they get their turn at a later
/// call, so a budget spreads a large claim over calls instead of faulting it in at once.
class ColdClaims {
 public:
  explicit ColdClaims(std::vector<ColdRange>& ranges, std::size_t budget = SIZE_MAX)
      : ranges_(ranges), budget_(budget) {}
  /// Claims a's room up to element `target` within what is left of the budget.
  template <class A>
  void claim(A& a, std::size_t target) {
    if (claimed_ >= budget_) return;
    const ColdRange r = a.claim_cold(target, budget_ - claimed_);
    if (r.bytes() > 0) ranges_.push_back(r), claimed_ += r.bytes();
  }
  /// Claims all of a's room, for the caller to touch (the fast backend touches all its arrays'
  /// ranges at once on every thread: FastSimulator::make_resident).
  template <class A>
  void whole(A& a) { claim(a, a.capacity()); }
  std::size_t claimed() const { return claimed_; }

 private:
  std::vector<ColdRange>& ranges_;
  std::size_t budget_, claimed_ = 0;
};

/// Resizes scratch (a std::vector or an Array whose content the caller rewrites) to n elements,
/// at least doubling its room when it must grow. std::vector grows from its size, so a scratch
/// used at alternating lengths (edges, then triangles) or growing a little at every use would
/// be reallocated at nearly every use, and each new buffer's pages faulted in again.
template <class V>
void resize_scratch(V& v, std::size_t n) {
  if (n > v.capacity()) v.reserve(std::max(n, 2 * v.capacity()));
  v.resize(n);
}

}  // namespace crumple::fast
