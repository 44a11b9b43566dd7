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

/// One attribute of the SoA state.
template <class T>
using Array = std::vector<T, AlignedAllocator<T>>;

}  // namespace crumple::fast
