#include "fast/aligned.h"

#include <sys/mman.h>

#include <cstdint>

namespace crumple::fast {

namespace {
constexpr std::align_val_t kLineAlign{64};
constexpr std::align_val_t kHugeAlign{kHugePage};
constexpr std::size_t kPage = 4096;
}  // namespace

void* allocate_aligned(std::size_t bytes) {
  if (bytes < kHugePage) return ::operator new(bytes, kLineAlign);
  void* p = ::operator new(bytes, kHugeAlign);
  // Advice only: where the kernel has no huge pages (or THP is off) the array keeps 4 KiB pages.
  madvise(p, (bytes + kPage - 1) / kPage * kPage, MADV_HUGEPAGE);
  return p;
}

void touch_pages(void* begin, void* end) {
  auto* p = static_cast<volatile char*>(begin);
  auto* last = static_cast<volatile char*>(end);
  if (p >= last) return;
  // One write a page (the first at begin, then at each page boundary): the fault is what counts.
  *p = 0;
  for (p = reinterpret_cast<volatile char*>((reinterpret_cast<std::uintptr_t>(p) | (kPage - 1)) + 1); p < last; p += kPage) *p = 0;
}

void free_aligned(void* p, std::size_t bytes) { ::operator delete(p, bytes < kHugePage ? kLineAlign : kHugeAlign); }

}  // namespace crumple::fast
