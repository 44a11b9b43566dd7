// The order in which the fast backend's XPBD projects its distance constraints (MODEL.md §3,
// docs/DECISIONS.md D19): Gauss-Seidel by colour. Each spring gets the smallest colour that no
// spring of a smaller logical id sharing an endpoint has (greedy, in ascending id); the
// springs of one colour share no vertex, so they are projected in parallel and in any order with
// the same result, and the whole pass equals Gauss-Seidel in the order (colour, id). The colouring
// depends on the logical mesh only: not on slots (relayout), not on the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "fast/aligned.h"
#include "fast/topology.h"

namespace crumple::fast {

class ConstraintColors {
 public:
  /// The topology changed (events, relayout): the next update() colours again.
  void invalidate() { stale_ = true; }
  /// Colours the live edges of m if the colouring is stale (serial, O(edges x valence)).
  void update(const Topology& m);
  int colors() const { return int(start_.size()) - 1; }
  /// The edge slots of colour c, in ascending slot order (memory order, for the caches).
  const std::int32_t* slots(int c) const { return order_.data() + start_[std::size_t(c)]; }
  int count(int c) const { return start_[std::size_t(c) + 1] - start_[std::size_t(c)]; }
  /// Colour of each edge slot (-1: dead), for tests.
  const std::vector<std::int32_t>& color_of_slot() const { return color_; }

 private:
  bool stale_ = true;
  std::vector<std::int32_t> color_;   ///< per edge slot
  std::vector<std::uint32_t> taken_;  ///< per colour: the id whose neighbours took it last
  std::vector<int> start_{0};         ///< colour c's slots are order_[start_[c], start_[c + 1])
  std::vector<std::int32_t> order_;
};

}  // namespace crumple::fast
