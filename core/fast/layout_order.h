// The relayout's three orders (layout.h): where each vertex, triangle and edge slot goes, and
// the helpers that the orders and the moves (layout.cpp) share. Internal to the relayout.
#pragma once

#include <climits>
#include <cstdint>
#include <stdexcept>

#include "fast/layout.h"

namespace crumple::fast::layout_order {

/// Minimum items per parallel chunk of relayout's loops: an item is a load
/// or two and a store, so chunks must be large to repay their scheduling.
inline constexpr int kGrain = 4096;

/// of[old] = new from order[new] = old (each entry written once: no race).
template <class From, class To>
void inverse(const Parallel& par, const From& order, To& of) {
  resize_scratch(of, order.size());
  par.run(int(order.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) of[order[k]] = k;
  });
}

/// Fills start[b] with where fixed block b of kGrain items of [0, n) begins when each block
/// takes count(begin, end) places (start[0] = 0, start[blocks] the total, which it returns): the
/// blocks count in parallel and only the sum over the blocks is serial.
template <class Count>
int block_starts(const Parallel& par, int n, Array<int>& start, Count count) {
  const int blocks = Parallel::blocks_of(n, kGrain);
  resize_scratch(start, std::size_t(blocks) + 1);
  par.run_blocks(n, kGrain, [&](int b, int begin, int end) { start[std::size_t(b) + 1] = count(begin, end); });
  std::int64_t total = start[0] = 0;
  for (std::size_t b = 1; b <= std::size_t(blocks); ++b) {
    total += start[b];
    if (total > INT32_MAX) throw std::length_error("relayout: 2^31 places or more in one array");
    start[b] = int(total);
  }
  return int(total);
}

/// Phase one's order: the vertex slots along a Morton curve of their rest positions (over the
/// axes along which the live ones span a cell), dead slots last, into s.vorder.
void vertex_order(const Parallel& par, const Vertices& V, LayoutScratch& s);
/// Phase three's order and its inverse (s.torder, s.tnew[old] = new): triangles by their lowest
/// corner's slot, dead ones last.
void triangle_order(const Topology& m, const Parallel& par, LayoutScratch& s);
/// Phase four's order (s.eorder; phase five extends it to the slots added since and inverts
/// it): edges by their lower endpoint's slot, in each vertex's spring list order, dead ones
/// last in free-list order.
void edge_order(const Topology& m, const Parallel& par, LayoutScratch& s);

}  // namespace crumple::fast::layout_order
