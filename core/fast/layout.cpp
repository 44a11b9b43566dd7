#include "fast/layout.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "fast/radix.h"

namespace crumple::fast {

namespace {

/// Minimum items per parallel chunk of relayout's loops: an item is a load
/// or two and a store, so chunks must be large to repay their scheduling.
constexpr int kGrain = 4096;
/// How far ahead a permutation or repack prefetches its scattered sources: its body is a few
/// instructions, so a miss must start many items before its item is reached.
constexpr int kAhead = 16;

/// Spreads the low 21 bits of v to every third bit (one axis of a 3-D Morton code).
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x1fffffULL;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

/// Spreads the low 32 bits of v to every second bit (one axis of a 2-D Morton code).
std::uint64_t spread2(std::uint64_t v) {
  v &= 0xffffffffULL;
  v = (v | v << 16) & 0x0000ffff0000ffffULL;
  v = (v | v << 8) & 0x00ff00ff00ff00ffULL;
  v = (v | v << 4) & 0x0f0f0f0f0f0f0f0fULL;
  v = (v | v << 2) & 0x3333333333333333ULL;
  v = (v | v << 1) & 0x5555555555555555ULL;
  return v;
}

/// One axis's cell spread for a Morton code of `axes` interleaved axes (1 to 3).
std::uint64_t spread(std::uint64_t cell, int axes) {
  return axes == 3 ? spread3(cell) : axes == 2 ? spread2(cell) : cell;
}

/// Stable LSD radix sort of the slots 0..n-1 by code (the low `bits` bits, at least one) into
/// `order`, in as few passes of at most kMaxDigit bits as cover them (stable: the order is the
/// same whatever the digits).
void radix_order(const Parallel& par, LayoutScratch& s, int bits, Array<int>& order) {
  const int n = int(s.code.size());
  resize_scratch(order, n);
  resize_scratch(s.idx, n);
  resize_scratch(s.code2, n);
  const RadixDigits d = radix_digits(bits);
  const int digit_bits = d.bits;
  const std::uint64_t mask = (std::uint64_t(1) << digit_bits) - 1;
  for (int shift = 0; shift < bits; shift += digit_bits) {
    const std::uint64_t* code = s.code.data();
    auto digit = [&](int k) { return int((code[k] >> shift) & mask); };
    const bool first = shift == 0;  // the order is the identity before the first pass
    stable_pass(par, s.count, n, 1 << digit_bits, digit, [&](int k, int to) {
      s.code2[to] = code[k];
      s.idx[to] = first ? k : order[k];
    });
    s.code.swap(s.code2);
    order.swap(s.idx);
  }
}

/// Stable counting sort of the slots by s.key (values in [0, buckets)) into `order`.
void counting_order(const Parallel& par, LayoutScratch& s, int buckets, Array<int>& order) {
  resize_scratch(order, s.key.size());
  const int* key = s.key.data();
  stable_pass(par, s.count, int(s.key.size()), buckets, [&](int k) { return key[k]; },
              [&](int k, int to) { order[to] = k; });
}

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

/// Morton order of the vertex slots by rest position, dead slots last, into s.vorder.
void vertex_order(const Parallel& par, const Vertices& V, LayoutScratch& s) {
  const int n = V.size();
  // The bounds of the live rest positions, per fixed block (min and max: the same on any
  // thread count); a dead slot's bounds are +inf / -inf, which no live one loses to.
  std::vector<std::array<float, 6>> bounds(std::size_t(Parallel::blocks_of(n, kGrain)));
  par.run_blocks(n, kGrain, [&](int b, int begin, int end) {
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int v = begin; v < end; ++v) {
      const Float4 X = V.rest[v];
      const bool live = V.mass(v) > 0;
      const float r[3] = {X.x, X.y, X.z};
      for (int d = 0; d < 3; ++d)
        lo[d] = std::min(lo[d], live ? r[d] : INFINITY), hi[d] = std::max(hi[d], live ? r[d] : -INFINITY);
    }
    bounds[b] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  });
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const auto& q : bounds)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], q[d]), hi[d] = std::max(hi[d], q[3 + d]);
  // Resolution: a sheet of n vertices has about sqrt(n) per axis; four times that per axis. A
  // live coordinate's cell is at most top, one short of all ones, so that the all-ones code,
  // the dead slots', sorts after every live vertex without a bit of its own.
  const int bits = std::clamp(int(std::ceil(std::log2(std::max(n, 2)) / 2)) + 2, 4, 21);
  const std::uint64_t top = (std::uint64_t(1) << bits) - 2;
  const double extent = std::max({double(hi[0]) - lo[0], double(hi[1]) - lo[1], double(hi[2]) - lo[2], 1e-30});
  const double scale = double(top) / extent;
  // Only the axes along which the live vertices span a cell or more are interleaved: a sheet
  // at rest is flat, and an axis without extent would only add radix passes.
  std::array<int, 3> axis{0, 1, 2};
  int axes = 0;
  for (int d = 0; d < 3; ++d)
    if ((double(hi[d]) - lo[d]) * scale >= 1) axis[std::size_t(axes++)] = d;
  axes = std::max(axes, 1);
  const std::uint64_t dead = (std::uint64_t(1) << (axes * bits)) - 1;
  resize_scratch(s.code, n);
  par.run(n, kGrain, [&](int b, int e) {
    for (int v = b; v < e; ++v) {
      if (!(V.mass(v) > 0)) {
        s.code[v] = dead;
        continue;
      }
      const Float4 X = V.rest[v];
      const float r[3] = {X.x, X.y, X.z};
      std::uint64_t code = 0;
      for (int k = 0; k < axes; ++k) {
        const int d = axis[std::size_t(k)];
        const double q = std::clamp((double(r[d]) - lo[d]) * scale, 0.0, double(top));
        code |= spread(std::uint64_t(q), axes) << k;
      }
      s.code[v] = code;
    }
  });
  radix_order(par, s, axes * bits, s.vorder);
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
/// at the swap, with its room, and keeps an eighth of that warm ahead of the elements; an
/// order's scratch holds an entry a slot of its kind, and the slots grow until the relayout
/// about as far as the state's arrays keep warm.
template <class S, class F>
void for_each_room(S& s, const Topology& m, int threads, F room) {
  const auto ahead = [](const auto& a) { return a.eighth_ahead(); };
  const auto swapped = [&](auto& spare, const auto& a) { room(spare, ahead(a), a.capacity()); };
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

std::size_t LayoutScratch::warm(const Topology& m, int threads, std::size_t budget) {
  std::size_t touched = 0;
  for_each_room(*this, m, threads, [&](auto& a, std::size_t target, std::size_t capacity) {
    if (touched >= budget) return;
    if (a.capacity() < capacity) a.clear(), a.reserve(capacity);  // dead between relayouts: not copied
    touched += a.warm_to(target, budget - touched);
  });
  return touched;
}

std::size_t LayoutScratch::cold_bytes(const Topology& m, int threads) const {
  std::size_t cold = 0;
  for_each_room(*this, m, threads, [&](const auto& a, std::size_t target, std::size_t capacity) {
    // A spare whose array has more room is reallocated empty by warm: all of it is cold.
    cold += a.capacity() < capacity ? target * sizeof(typename std::decay_t<decltype(a)>::value_type) : a.cold_bytes(target);
  });
  return cold;
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

// Phase one. The vertices' state that lives across steps (forces, sums and guesses are
// rewritten by the next step before anything reads them) is permuted, and the adjacency pools
// are repacked in the new vertex order with the neighbours renamed; the other entries (edge and
// triangle slots) keep their values until phases two and three. A group's arrays have distinct
// spares.
void move_vertices(Vertices& V, const Parallel& par, LayoutScratch& s, const Rename& v) {
  const Array<int>& vorder = s.vorder;
  permute(par, vorder, gathered(V.xm, s.spare_rows), gathered(V.spring_list, s.spare_heads), gathered(V.lid, s.spare_vid));
  permute(par, vorder, gathered(V.vm, s.spare_rows), gathered(V.tri_list, s.spare_heads));
  permute(par, vorder, gathered(V.nr, s.spare_rows));
  permute(par, vorder, gathered(V.rest, s.spare_rows));
  const auto same = [](std::int32_t x) { return x; };
  repack(par, s, {V.springs, s.spare_springs}, {V.nbrs, s.spare_nbrs}, V.spring_list, same, v);
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

/// Phase two's order and its inverse (s.tnew[old] = new): triangles by their lowest corner's
/// slot (a counting sort), dead ones last.
void triangle_order(const Topology& m, const Parallel& par, LayoutScratch& s) {
  const Triangles& T = m.T;
  const int nv = m.V.size(), nt = T.size();
  resize_scratch(s.key, nt);
  par.run(nt, kGrain, [&](int b, int e) {
    for (int t = b; t < e; ++t) s.key[t] = T.alive[t] ? std::min({T[t].v[0], T[t].v[1], T[t].v[2]}) : nv;
  });
  counting_order(par, s, nv + 1, s.torder);
  inverse(par, s.torder, s.tnew);
}

/// The springs in v's list whose other end has a higher slot: each live edge is listed once at
/// each end (Topology::check), so once at its lower end.
int owned_springs(const Vertices& V, int v) {
  const ListHead h = V.spring_list[v];
  const std::int32_t* nbr = &V.nbrs[std::size_t(h.at)];
  int owned = 0;
  for (int w = 0; w < h.count; ++w) owned += nbr[w] > v;
  return owned;
}

/// Phase three's order and its inverse (s.enew[old] = new): edges by their lower endpoint's
/// slot, in each vertex's spring list order, dead ones last in free-list order. Read from the
/// spring lists that phase one packed in vertex order (two streaming passes over them, a fixed
/// block of vertices at a time) rather than sorted by a key over every edge record: the passes
/// gather an edge's endpoints, not its neighbours in slot order, so any order within one lower
/// endpoint serves locality, and none changes a bit of what a step computes.
void edge_order(const Topology& m, const Parallel& par, LayoutScratch& s) {
  const Vertices& V = m.V;
  const int nv = V.size(), ne = m.E.size();
  const int live = block_starts(par, nv, s.count, [&](int begin, int end) {
    int owned = 0;
    for (int v = begin; v < end; ++v) owned += owned_springs(V, v);
    return owned;
  });
  if (live + int(m.E.free_ids.size()) != ne)
    throw std::logic_error("relayout: the spring lists do not hold every live edge once at its lower end");
  resize_scratch(s.eorder, ne);
  par.run_blocks(nv, kGrain, [&](int b, int begin, int end) {
    // Every spring is written at the block's next place and only an owned one advances it (no
    // branch to mispredict on the half that is not owned); the block's last place belongs to
    // the next block, so writes there go to a dummy.
    int* __restrict order = s.eorder.data();
    const int last = s.count[std::size_t(b) + 1];
    int at = s.count[std::size_t(b)], dummy = 0;
    for (int v = begin; v < end; ++v) {
      const ListHead h = V.spring_list[v];
      const std::int32_t* spring = &V.springs[std::size_t(h.at)];
      const std::int32_t* nbr = &V.nbrs[std::size_t(h.at)];
      for (int w = 0; w < h.count; ++w) {
        *(at < last ? &order[at] : &dummy) = spring[w] >> 1;
        at += nbr[w] > v;
      }
    }
  });
  int at = live;
  for (int id : m.E.free_ids) s.eorder[at++] = m.E.phys[std::size_t(id)];
  inverse(par, s.eorder, s.enew);
}

/// One pool's entries of every vertex's list renamed where they are, a vertex's block at a time
/// (phase one packed the blocks in vertex order; only the blocks in use are read: the garbage
/// a later move left behind holds nothing to rename).
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

// Phase two: the triangles permuted (the areas are not moved: they are per-step values that
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

// Phase three: the edges permuted (the edge pass's output is per step and is not kept), then
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
  vertex_order(par, m.V, s);
  inverse(par, s.vorder, s.vnew);
  const Rename v{s.vnew};
  move_vertices(m.V, par, s, v);
  rename_vertices(m, par, v);
  inverse(par, m.V.lid, m.V.phys);  // free lists hold logical ids and do not change
  m.V.created = 0;
}

void relayout_triangles(Topology& m, const Parallel& par, LayoutScratch& s) {
  triangle_order(m, par, s);
  move_triangles(m, par, s, Rename{s.tnew});
  inverse(par, m.T.lid, m.T.phys);
}

void relayout_edges(Topology& m, const Parallel& par, LayoutScratch& s) {
  edge_order(m, par, s);
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
    case 1: relayout_triangles(m, par, s); break;
    default: relayout_edges(m, par, s); break;
  }
}

}  // namespace crumple::fast
