#include "fast/layout.h"

#include <algorithm>
#include <cstring>
#include <utility>
#include <vector>

#include "fast/layout_order.h"
#include "fast/radix.h"

namespace crumple::fast {

using layout_order::block_starts;
using layout_order::inverse;
using layout_order::kGrain;

namespace {

/// How far ahead a permutation or repack prefetches its scattered sources: its body is a few
/// instructions, so a miss must start many items before its item is reached.
constexpr int kAhead = 16;

/// One array of a permutation group: a[new] = rename(a[order[new]], order[new]), gathered into
/// `spare`, which then swaps with a.
template <class T, class F>
struct Gathered {
  Array<T>& a;
  Array<T>& spare;
  F rename;
  const T* src = nullptr;
  T* dst = nullptr;
};
template <class T, class F>
Gathered<T, F> gathered(Array<T>& a, Array<T>& spare, F rename) {
  return {a, spare, rename};
}
template <class T>
auto gathered(Array<T>& a, Array<T>& spare) {
  return gathered(a, spare, [](const T& v, int) { return v; });
}

/// Readies a spare buffer to receive n elements gathered from `from` and then to swap with it:
/// at least from's room, so the swap keeps the array's reserved room. Growing it drops its old
/// content first (a reserve would copy it); the elements that resize adds are value-initialized,
/// which is why arrays of different lengths do not share a spare (LayoutScratch).
template <class T>
T* ready_spare(Array<T>& out, const Array<T>& from, std::size_t n) {
  if (out.capacity() < from.capacity()) out.clear(), out.reserve(from.capacity());
  out.resize(n);
  return out.data();
}

/// Readies g to gather into its spare buffer.
template <class G>
void ready(G& g) {
  g.src = g.a.data();
  g.dst = ready_spare(g.spare, g.a, g.a.size());
}

/// Gathers every array of one group in the new order, in one loop over `order` (one read of
/// the order and one loop for all of them). Each array gathers into its own spare buffer, which
/// then swaps with it, keeping the array's reserved room.
template <class... G>
void permute(const Parallel& par, const Array<int>& order, G... g) {
  (ready(g), ...);
  par.run(int(order.size()), kGrain, [&](int b, int e) {
    const int* __restrict o = order.data();
    auto copy = [&](int k) {
      const int from = o[k];
      ((g.dst[k] = g.rename(g.src[from], from)), ...);
    };
    // The sources are scattered (new elements sit at the end until a relayout): fetch them
    // kAhead on. Not the renaming tables' entries: prefetching those too made it slower
    // (docs/PERFORMANCE.md).
    const int ahead = std::max(b, e - kAhead);
    for (int k = b; k < ahead; ++k) {
      const int next = o[k + kAhead];
      (__builtin_prefetch(&g.src[next]), ...);
      copy(k);
    }
    for (int k = ahead; k < e; ++k) copy(k);
  });
  (g.a.swap(g.spare), ...);
  (g.a.keep_warm(), ...);  // the spare's room ahead may be untouched: growth must not fault there
}

/// One adjacency pool and the spare buffer it is repacked into.
struct Pool {
  Array<std::int32_t>& a;
  Array<std::int32_t>& spare;
};

/// Repacks one adjacency pool (list) and its parallel pool in the new vertex order: the vertex
/// now in slot k (heads already permuted) gets a block of room_for(count) entries, the blocks
/// packed in slot order, so neighbouring vertices' lists share cache lines and no garbage is
/// left. f and g rename the entries of list and parallel; both pools are copied in one loop.
/// The blocks are placed a fixed block of vertices at a time (block_starts), so no loop over
/// every vertex is serial.
template <class F, class G>
void repack(const Parallel& par, LayoutScratch& s, Pool list, Pool parallel, Array<ListHead>& heads, F f, G g) {
  const int n = int(heads.size());
  const int total = block_starts(par, n, s.count, [&](int begin, int end) {
    int room = 0;
    for (int k = begin; k < end; ++k) room += room_for(heads[k].count);
    return room;
  });
  const int* __restrict start = s.count.data();
  std::int32_t* __restrict to_list = ready_spare(list.spare, list.a, std::size_t(total));
  std::int32_t* __restrict to_parallel = ready_spare(parallel.spare, parallel.a, std::size_t(total));
  const std::int32_t* __restrict from_list = list.a.data();
  const std::int32_t* __restrict from_parallel = parallel.a.data();
  ListHead* __restrict head = heads.data();
  par.run_blocks(n, kGrain, [&](int b, int begin, int end) {
    int to = start[b];
    for (int k = begin; k < end; ++k) {
      if (k + kAhead < end) {  // a head this block has not rewritten yet: it still holds the old start
        const int ahead = head[k + kAhead].at;
        __builtin_prefetch(&from_list[ahead]), __builtin_prefetch(&from_parallel[ahead]);
      }
      ListHead& h = head[k];
      const int from = h.at, count = h.count;
      for (int w = 0; w < count; ++w) {
        to_list[to + w] = f(from_list[from + w]);
        to_parallel[to + w] = g(from_parallel[from + w]);
      }
      h.at = to;
      h.room = std::uint16_t(room_for(count));
      to += h.room;
    }
  });
  list.a.swap(list.spare);
  parallel.a.swap(parallel.spare);
  list.a.keep_warm();
  parallel.a.keep_warm();
}

}  // namespace

void LayoutScratch::reserve(std::size_t nv, std::size_t ne, std::size_t nt, int threads) {
  for (auto* v : {&vorder, &vnew, &idx}) v->reserve(nv);
  for (auto* v : {&eorder, &enew}) v->reserve(ne);
  for (auto* v : {&torder, &tnew}) v->reserve(nt);
  key.reserve(nt);
  code.reserve(nv);
  code2.reserve(nv);
  // The counting sorts' histograms: a block's counts per vertex slot (radix.h's stable_pass).
  count.reserve(std::size_t(std::clamp(threads, 1, kMaxRadixBlocks)) * (nv + 1));
}

namespace {
/// Calls room(array, target, capacity) for each array of the scratch: how far the next relayout
/// writes it (elements), and the capacity it must have by then. A spare takes its array's place
/// at the swap, with its room, and keeps it warm as far as the array did (warm_target); an
/// order's scratch holds an entry a slot of its kind, and the slots grow until the relayout
/// about as far as the state's arrays keep warm.
template <class S, class F>
void for_each_room(S& s, const Topology& m, int threads, F room) {
  const auto ahead = [](const auto& a) { return a.eighth_ahead(); };
  const auto swapped = [&](auto& spare, const auto& a) { room(spare, a.warm_target(), a.capacity()); };
  const Vertices& V = m.V;
  swapped(s.spare_rows, V.xm), swapped(s.spare_heads, V.spring_list), swapped(s.spare_vid, V.lid);
  swapped(s.spare_springs, V.springs), swapped(s.spare_nbrs, V.nbrs);
  swapped(s.spare_tris, V.tris), swapped(s.spare_wings, V.wings);
  swapped(s.spare_faces, m.T.slots), swapped(s.spare_tid, m.T.lid), swapped(s.spare_alive, m.T.alive);
  swapped(s.spare_edges, m.E.slots), swapped(s.spare_eid, m.E.lid);
  const std::size_t nv = ahead(V.xm), ne = ahead(m.E.slots), nt = ahead(m.T.slots);
  for (auto* a : {&s.vorder, &s.vnew, &s.idx}) room(*a, nv, nv);
  for (auto* a : {&s.code, &s.code2}) room(*a, nv, nv);
  for (auto* a : {&s.eorder, &s.enew}) room(*a, ne, ne);
  for (auto* a : {&s.torder, &s.tnew}) room(*a, nt, nt);
  room(s.key, nt, nt);  // the triangles' sort keys (the edge order needs none)
  const std::size_t counts = std::size_t(std::clamp(threads, 1, kMaxRadixBlocks)) * (nv + 1);  // stable_pass
  room(s.count, counts, counts);
}
}  // namespace

std::size_t LayoutScratch::warm(const Topology& m, const Parallel& par, std::size_t budget) {
  std::vector<ColdRange> cold;
  const std::size_t touched = claim_cold(m, par.threads(), budget, cold);
  touch_pages(par, cold);
  return touched;
}

std::size_t LayoutScratch::claim_cold(const Topology& m, int threads, std::size_t budget,
                                      std::vector<ColdRange>& cold) {
  ColdClaims claims(cold, budget);
  for_each_room(*this, m, threads, [&](auto& a, std::size_t target, std::size_t capacity) {
    if (claims.claimed() >= budget) return;
    if (a.capacity() < capacity) a.clear(), a.reserve(capacity);  // dead between relayouts: not copied
    claims.claim(a, target);
  });
  return claims.claimed();
}

std::size_t LayoutScratch::cold_bytes(const Topology& m, int threads) const {
  std::size_t cold = 0;
  for_each_room(*this, m, threads, [&](const auto& a, std::size_t target, std::size_t capacity) {
    // A spare whose array has more room is reallocated empty by warm: all of it is cold.
    cold += a.capacity() < capacity ? target * sizeof(typename std::decay_t<decltype(a)>::value_type) : a.cold_bytes(target);
  });
  return cold;
}

void LayoutScratch::claim_whole(const Topology& m, int threads, ColdClaims& claims) {
  for_each_room(*this, m, threads, [&](auto& a, std::size_t, std::size_t capacity) {
    a.reserve(capacity);  // with the elements: within a relayout the edges' order is read next
    claims.whole(a);
  });
}

bool LayoutScratch::resident(const Topology& m, int threads) const {
  bool whole = true;
  for_each_room(*this, m, threads, [&](const auto& a, std::size_t, std::size_t capacity) {
    whole = whole && a.capacity() >= capacity && a.touched() == a.capacity();
  });
  return whole;
}

bool layout_stale(const Topology& m, double fraction) {
  if (fraction < 0) return false;
  return double(m.V.created) >= fraction * m.V.size();
}

namespace {
/// Old slot -> new slot of one kind (-1, "none", stays -1).
struct Rename {
  const Array<int>& to;
  std::int32_t operator()(std::int32_t x) const { return x >= 0 ? std::int32_t(to[x]) : x; }
};

/// Renames each split record's entries in place (free records too: their stale ids stay in
/// range and are overwritten on reuse).
template <class F>
void rename_records(Array<SplitRecord>& records, const Parallel& par, F rename) {
  par.run(int(records.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) rename(records[k]);
  });
}

/// One pool's entries of every vertex's list renamed where they are, a vertex's block at a time
/// (only the blocks in use are read: the garbage a move left behind holds nothing to rename).
template <class F>
void rename_pool(const Parallel& par, const Array<ListHead>& heads, Array<std::int32_t>& pool, F rename) {
  std::int32_t* __restrict entry = pool.data();
  par.run(int(heads.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      const ListHead h = heads[k];
      for (int w = h.at; w < h.at + h.count; ++w) entry[w] = rename(entry[w]);
    }
  });
}

// Phase one. The vertices' state that lives across steps (forces, sums and guesses are
// rewritten by the next step before anything reads them) is permuted with the list heads, which
// still point into the pools where the lists are, and the neighbours are renamed there; the
// other entries (edge and triangle slots) keep their values until their phases. A group's
// arrays have distinct spares.
void move_vertices(Vertices& V, const Parallel& par, LayoutScratch& s, const Rename& v) {
  const Array<int>& vorder = s.vorder;
  permute(par, vorder, gathered(V.xm, s.spare_rows), gathered(V.spring_list, s.spare_heads), gathered(V.lid, s.spare_vid));
  permute(par, vorder, gathered(V.vm, s.spare_rows), gathered(V.tri_list, s.spare_heads));
  permute(par, vorder, gathered(V.nr, s.spare_rows));
  permute(par, vorder, gathered(V.rest, s.spare_rows));
  rename_pool(par, V.spring_list, V.nbrs, v);
}

// Phase two: the adjacency pools repacked in vertex slot order, so that neighbouring vertices'
// lists share cache lines and no garbage is left (no entry changes).
void pack_lists(Vertices& V, const Parallel& par, LayoutScratch& s) {
  const auto same = [](std::int32_t x) { return x; };
  repack(par, s, {V.springs, s.spare_springs}, {V.nbrs, s.spare_nbrs}, V.spring_list, same, same);
  repack(par, s, {V.tris, s.spare_tris}, {V.wings, s.spare_wings}, V.tri_list, same, same);
  V.garbage_e = V.garbage_t = 0;
}

// Phase one: the edges' and triangles' vertex entries renamed where they are (one streaming
// pass each). A dead edge keeps joining slot 0 to itself and a dead triangle keeps corners 0,
// as the topology's convention says (release_edge, kNoFace): their zeros are not slots.
void rename_vertices(Topology& m, const Parallel& par, const Rename& v) {
  Edges& E = m.E;
  par.run(E.size(), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      EdgeRecord& r = E[k];
      if (r.flags & kAlive) r.a = v(r.a), r.b = v(r.b);
      r.wl = v(r.wl), r.wr = v(r.wr);
    }
  });
  Triangles& T = m.T;
  par.run(T.size(), kGrain, [&](int b, int e) {
    for (int t = b; t < e; ++t)
      if (T.alive[t])
        for (int k = 0; k < 3; ++k) T[t].v[k] = v(T[t].v[k]);
  });
  rename_records(m.records, par, [&](SplitRecord& r) {
    r.n = v(r.n);
    for (int q = 0; q < 4; ++q) r.k[q] = v(r.k[q]);
  });
}

// Phase three: the triangles permuted (the areas are not moved: they are per-step values that
// compute_normals writes for every slot before anything reads them), then their slots renamed
// where they are: in the edges' sides, the vertices' triangle lists and the split records.
void move_triangles(Topology& m, const Parallel& par, LayoutScratch& s, const Rename& t) {
  Triangles& T = m.T;
  permute(par, s.torder, gathered(T.slots, s.spare_faces), gathered(T.lid, s.spare_tid), gathered(T.alive, s.spare_alive));
  Edges& E = m.E;
  par.run(E.size(), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) E[k].tri0 = t(E[k].tri0), E[k].tri1 = t(E[k].tri1);
  });
  rename_pool(par, m.V.tri_list, m.V.tris, [&](std::int32_t x) { return (t.to[x >> 2] << 2) | (x & 3); });
  rename_records(m.records, par, [&](SplitRecord& r) {
    for (int q = 0; q < 4; ++q) r.t[q] = t(r.t[q]);
  });
}

// Phase five: the edges permuted (the edge pass's output is per step and is not kept), then
// their slots renamed where they are: in the triangles' sides, the vertices' spring and wing
// lists and the split records.
void move_edges(Topology& m, const Parallel& par, LayoutScratch& s, const Rename& e) {
  Edges& E = m.E;
  permute(par, s.eorder, gathered(E.slots, s.spare_edges), gathered(E.lid, s.spare_eid));
  Triangles& T = m.T;
  par.run(T.size(), kGrain, [&](int b, int end) {
    for (int t = b; t < end; ++t)
      for (int k = 0; k < 3; ++k) T[t].e[k] = e(T[t].e[k]);
  });
  rename_pool(par, m.V.spring_list, m.V.springs, [&](std::int32_t x) { return (e.to[x >> 1] << 1) | (x & 1); });
  rename_pool(par, m.V.tri_list, m.V.wings, e);
  rename_records(m.records, par, [&](SplitRecord& r) {
    for (int q = 0; q < 4; ++q) r.e[q] = e(r.e[q]);
  });
}

void relayout_vertices(Topology& m, const Parallel& par, LayoutScratch& s) {
  layout_order::vertex_order(par, m.V, s);
  inverse(par, s.vorder, s.vnew);
  const Rename v{s.vnew};
  move_vertices(m.V, par, s, v);
  rename_vertices(m, par, v);
  inverse(par, m.V.lid, m.V.phys);  // free lists hold logical ids and do not change
  m.V.created = 0;
}

void relayout_triangles(Topology& m, const Parallel& par, LayoutScratch& s) {
  layout_order::triangle_order(m, par, s);
  move_triangles(m, par, s, Rename{s.tnew});
  inverse(par, m.T.lid, m.T.phys);
}

// Phase four: the edge order, from the lists as phase two packed them. Phase five applies it a
// step later, to the edges as they are then: the slots that step added go last in the order they
// have, and a slot it freed or reused keeps its place in the order (dead slots are harmless
// anywhere, layout.h).
void order_edges(Topology& m, const Parallel& par, LayoutScratch& s) { layout_order::edge_order(m, par, s); }

void relayout_edges(Topology& m, const Parallel& par, LayoutScratch& s) {
  const int ordered = int(s.eorder.size()), ne = m.E.size();
  if (ordered > ne) throw std::logic_error("relayout: the edge order has more slots than the edges");
  resize_scratch(s.eorder, std::size_t(ne));
  for (int e = ordered; e < ne; ++e) s.eorder[std::size_t(e)] = e;
  inverse(par, s.eorder, s.enew);
  move_edges(m, par, s, Rename{s.enew});
  inverse(par, m.E.lid, m.E.phys);
}
}  // namespace

void relayout(Topology& m, const Parallel& par, LayoutScratch& s) {
  for (int phase = 0; phase < kLayoutPhases; ++phase) relayout_phase(phase, m, par, s);
}

void relayout_phase(int phase, Topology& m, const Parallel& par, LayoutScratch& s) {
  switch (phase) {
    case 0: relayout_vertices(m, par, s); break;
    case 1: pack_lists(m.V, par, s); break;
    case 2: relayout_triangles(m, par, s); break;
    case 3: order_edges(m, par, s); break;
    default: relayout_edges(m, par, s); break;
  }
}

}  // namespace crumple::fast
