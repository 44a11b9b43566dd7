#include "fast/aligned.h"

#include <sys/mman.h>

#include <cstdint>

namespace crumple::fast {

namespace {
constexpr std::align_val_t kLineAlign{64};
constexpr std::align_val_t kHugeAlign{kHugePage};
constexpr std::size_t kPage = 4096;

/// A large allocation's size: whole huge pages, so that its last part is a huge page too (the
/// kernel maps one only where the advised range covers all of it; a 3 MiB array advised as
/// such would keep its last 1 MiB on 4 KiB pages, whose faults cost the most).
std::size_t huge_bytes(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }
}  // namespace

void* allocate_aligned(std::size_t bytes) {
  if (bytes < kHugePage) return ::operator new(bytes, kLineAlign);
  void* p = ::operator new(huge_bytes(bytes), kHugeAlign);
  // Advice only: where the kernel has no huge pages (or THP is off) the array keeps 4 KiB pages.
  madvise(p, huge_bytes(bytes), MADV_HUGEPAGE);
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

void free_aligned(void* p, std::size_t bytes) {
  if (bytes < kHugePage) ::operator delete(p, bytes, kLineAlign);
  else ::operator delete(p, huge_bytes(bytes), kHugeAlign);
}

}  // namespace crumple::fast
