// Prefetches for the topology pass. Each event touches a few hundred bytes in some fifty cache
// lines of the SoA arrays, far from the previous event's: prefetching the next events' lines
// while one applies overlaps those misses (the events themselves still apply in order). kFar
// ahead: the first lines (the edge, the record); kNear ahead: what those lines point to, found
// in the events' own copies where the pass keeps them (a split's plan, a restore's record).
#pragma once

#include <array>

#include "fast/topology.h"

namespace crumple::fast {

constexpr int kFar = 8;   ///< beyond kNear, so the first lines are cached when kNear reads through them
constexpr int kNear = 3;  ///< few: kNear events' lines (some fifty each) must stay in L1 until used

template <class T>
void prefetch(const T* p) {  // for lines the event will write
  __builtin_prefetch(p, 1, 3);
}
template <class T>
void prefetch_read(const T* p) {  // for lines it only reads (no claim on other cores' copies)
  __builtin_prefetch(p, 0, 3);
}
/// The per-edge lines an event on edge e reads first.
inline void prefetch_edge(const Topology& m, int e) {
  const Edges& E = m.E;
  const char* record = reinterpret_cast<const char*>(&E[e]);  // 36 bytes: its first and last line
  prefetch(record), prefetch(record + sizeof(EdgeRecord) - 1), prefetch(&E.lid[e]);
}
inline void prefetch_vertex(const Topology& m, int v) {
  if (v < 0) return;
  const Vertices& V = m.V;
  prefetch(&V.xm[v]), prefetch(&V.vm[v]), prefetch(&V.nr[v]);
  prefetch(&V.rest[v]);
  prefetch(&V.spring_list[v]), prefetch(&V.tri_list[v]);
  prefetch(m.springs_of(v)), prefetch(m.nbrs_of(v)), prefetch(m.tris_of(v)), prefetch(m.wings_of(v));
}
inline void prefetch_triangle(const Topology& m, int t) {
  if (t < 0) return;
  const Triangles& T = m.T;
  const char* record = reinterpret_cast<const char*>(&T[t]);  // 24 bytes: its first and last line
  prefetch(record), prefetch(record + sizeof(Face) - 1), prefetch(&T.alive[t]), prefetch(&T.area[t]);
}
/// Everything a split reads beyond its edge (prefetch_edge), from its own copy of the edge's
/// ends (i, j, l, r) and triangles: the edge's line itself is not read, so a miss on it does
/// not hold the prefetches back.
inline void prefetch_split(const Topology& m, const std::array<int, 4>& ends, const std::array<int, 2>& tris) {
  for (int v : ends) prefetch_vertex(m, v);
  for (int t : tris) prefetch_triangle(m, t);
}
/// Everything a restore of the split record r reads (r must be cached already).
inline void prefetch_restore(const Topology& m, const SplitRecord& r) {
  prefetch_vertex(m, r.n);
  for (int q = 0; q < 4; ++q) {
    prefetch_vertex(m, r.k[q]);
    if (r.e[q] >= 0) prefetch_edge(m, r.e[q]);
    prefetch_triangle(m, r.t[q]);
  }
}

}  // namespace crumple::fast
