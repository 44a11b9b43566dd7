// Cache-line aligned storage for the structure-of-arrays state: every attribute is one
// contiguous array, 64-byte aligned so that AVX-512 loads of a lane group never split a line.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace crumple::fast {

template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlign{64};
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlign)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlign); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

/// One attribute of the SoA state. A copy keeps the room reserved in the original (a plain
/// vector copy would not), so a clone of a simulator appends without reallocating, as the
/// original does: the benchmarks time frames of clones. The room is faulted in when it is
/// reserved or copied (warm), so that growth into it never page-faults inside a step: the
/// real-time practice of touching a memory budget up front (docs/DECISIONS.md D16).
template <class T>
class Array : public std::vector<T, AlignedAllocator<T>> {
  using Base = std::vector<T, AlignedAllocator<T>>;

 public:
  using Base::Base;
  Array() = default;
  Array(const Array& o) : Base() {
    this->reserve(o.capacity());
    warm();
    this->assign(o.begin(), o.end());
  }
  Array& operator=(const Array& o) {
    if (this != &o) {
      if (this->capacity() < o.capacity()) this->reserve(o.capacity()), warm();
      this->assign(o.begin(), o.end());
    }
    return *this;
  }
  /// Reserves room for n elements with every page of it touched (see the class comment).
  void reserve_warm(std::size_t n) {
    this->reserve(n);
    warm();
  }
  /// Touches every page of the reserved room (value-initializes it and shrinks back).
  void warm() {
    const std::size_t n = this->size();
    this->resize(this->capacity());
    this->resize(n);
  }
  Array(Array&&) noexcept = default;
  Array& operator=(Array&&) noexcept = default;
};

}  // namespace crumple::fast
