#include "fast/constraint_colors.h"

#include <algorithm>

namespace crumple::fast {

void ConstraintColors::update(const Topology& m) {
  if (!stale_) return;
  const Edges& E = m.E;
  const int ne = E.size();
  color_.assign(std::size_t(ne), -1);
  std::fill(taken_.begin(), taken_.end(), 0u);
  int ncolors = 0;
  for (int id = 0; id < ne; ++id) {
    const int e = E.phys[id];
    if (!(E[e].flags & kAlive)) continue;
    const std::uint32_t stamp = std::uint32_t(id) + 1;
    for (const int v : {E[e].a, E[e].b}) {  // the colours of the springs at v coloured so far
      const std::int32_t* springs = m.springs_of(v);
      for (int k = 0, n = m.V.spring_list[v].count; k < n; ++k) {
        const int c = color_[std::size_t(springs[k] >> 1)];
        if (c >= 0) taken_[std::size_t(c)] = stamp;
      }
    }
    int c = 0;
    while (c < int(taken_.size()) && taken_[std::size_t(c)] == stamp) ++c;
    if (c == int(taken_.size())) taken_.push_back(0);
    color_[std::size_t(e)] = c;
    ncolors = std::max(ncolors, c + 1);
  }
  start_.assign(std::size_t(ncolors) + 1, 0);
  for (const int c : color_)
    if (c >= 0) ++start_[std::size_t(c) + 1];
  for (int c = 0; c < ncolors; ++c) start_[std::size_t(c) + 1] += start_[std::size_t(c)];
  order_.resize(std::size_t(start_.back()));
  std::vector<int> next(start_.begin(), start_.end() - 1);
  for (int e = 0; e < ne; ++e)
    if (color_[std::size_t(e)] >= 0) order_[std::size_t(next[std::size_t(color_[std::size_t(e)])]++)] = e;
  stale_ = false;
}

}  // namespace crumple::fast
