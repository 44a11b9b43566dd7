#include "fast/serial_events.h"

#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
/// Appends the vertices of [first, last) that exist (>= 0): an applied event's vertices, for
/// the serial edits' normal renewal.
template <class It>
void append_live(It first, It last, std::vector<int>& out) {
  for (; first != last; ++first)
    if (*first >= 0) out.push_back(*first);
}
}  // namespace

int SerialEvents::splits(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps, std::vector<int>& touched) {
  const Topology& m = sim.topo_;
  int done = 0;
  for (int e : splits) {
    if (stamps.touched(m.E[e].tri0) || stamps.touched(m.E[e].tri1)) continue;
    if (!sim.split_edge(e)) continue;
    const SplitRecord& r = m.records[m.E[e].record];
    for (int t : r.t) stamps.mark(t);
    append_live(r.k.begin(), r.k.end(), touched);
    touched.push_back(r.n);
    ++done;
  }
  return done;
}

int SerialEvents::restores(FastSimulator& sim, const std::vector<int>& restores, PassStamps& stamps,
                           std::vector<int>& touched) {
  const Topology& m = sim.topo_;
  int done = 0;
  for (int e : restores) {
    const SplitRecord& r = m.records[m.E[e].record];
    if (stamps.any_touched(r.t) || !sim.can_restore(e)) continue;
    const auto t = r.t;
    append_live(r.k.begin(), r.k.end(), touched);
    sim.restore_edge(e);
    for (int q : t) stamps.mark(q);
    ++done;
  }
  return done;
}

}  // namespace crumple::fast
