#include "fast/layout.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace crumple::fast {

namespace {

/// Minimum items per parallel chunk (and per sort block) of relayout's loops: an item is a load
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

/// One stable counting pass over the items 0..n-1 with keys in [0, buckets): place(k, to) is
/// told each item's rank among the items of smaller key, then of equal key and smaller index.
/// The items are cut into one block per thread, each counted into its own histogram, the
/// histograms summed in bucket-major order (serial, buckets x blocks), then each block places
/// its items in index order: the ranks do not depend on the number of blocks, so the result is
/// the serial pass's on any thread count.
template <class Key, class Place>
void stable_pass(const Parallel& par, std::vector<int>& hist, int n, int buckets, Key key, Place place) {
  // At most 8 blocks: the histograms (blocks x buckets, summed serially) grow with the count.
  const int wanted = std::clamp(n / kGrain, 1, std::min(par.threads(), 8));
  const int per = std::max(1, (n + wanted - 1) / wanted);  // >= 1: no block of zero items
  const int blocks = Parallel::blocks_of(n, per);          // the blocks run_blocks runs
  hist.assign(std::size_t(blocks) * buckets, 0);
  par.run_blocks(n, per, [&](int b, int begin, int end) {
    int* h = &hist[std::size_t(b) * buckets];
    for (int k = begin; k < end; ++k) ++h[key(k)];
  });
  int sum = 0;
  for (int c = 0; c < buckets; ++c)
    for (int b = 0; b < blocks; ++b) sum += std::exchange(hist[std::size_t(b) * buckets + c], sum);
  par.run_blocks(n, per, [&](int b, int begin, int end) {
    int* h = &hist[std::size_t(b) * buckets];
    for (int k = begin; k < end; ++k) place(k, h[key(k)]++);
  });
}

/// Stable LSD radix sort of the slots 0..n-1 by code (11-bit digits over `bits`) into `order`.
void radix_order(const Parallel& par, LayoutScratch& s, int bits, std::vector<int>& order) {
  const int n = int(s.code.size());
  order.resize(n);
  s.idx.resize(n);
  s.code2.resize(n);
  for (int k = 0; k < n; ++k) order[k] = k;
  constexpr int kDigit = 11;
  constexpr std::uint64_t kMask = (std::uint64_t(1) << kDigit) - 1;
  for (int shift = 0; shift < bits; shift += kDigit) {
    const std::uint64_t* code = s.code.data();
    auto digit = [&](int k) { return int((code[k] >> shift) & kMask); };
    stable_pass(par, s.count, n, 1 << kDigit, digit, [&](int k, int to) {
      s.code2[to] = code[k];
      s.idx[to] = order[k];
    });
    s.code.swap(s.code2);
    order.swap(s.idx);
  }
}

/// Stable counting sort of the slots by s.key (values in [0, buckets)) into `order`.
void counting_order(const Parallel& par, LayoutScratch& s, int buckets, std::vector<int>& order) {
  order.resize(s.key.size());
  const int* key = s.key.data();
  stable_pass(par, s.count, int(s.key.size()), buckets, [&](int k) { return key[k]; },
              [&](int k, int to) { order[to] = k; });
}

/// of[old] = new from order[new] = old (each entry written once: no race).
template <class From, class To>
void inverse(const Parallel& par, const From& order, To& of) {
  of.resize(order.size());
  par.run(int(order.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) of[order[k]] = k;
  });
}

/// The spare buffer of element type T.
template <class T> Array<T>& spare(LayoutScratch& s);
template <> Array<ListHead>& spare(LayoutScratch& s) { return s.spare_heads; }
template <> Array<std::int32_t>& spare(LayoutScratch& s) { return s.spare_i; }
template <> Array<std::uint8_t>& spare(LayoutScratch& s) { return s.spare_u8; }
template <> Array<Float4>& spare(LayoutScratch& s) { return s.spare_f4; }
template <> Array<EdgeRecord>& spare(LayoutScratch& s) { return s.spare_edges; }
template <> Array<Face>& spare(LayoutScratch& s) { return s.spare_faces; }

/// a[new] = f(a[order[new]]): gathered into the spare buffer, which then swaps with a (keeping
/// a's reserved room).
template <class T, class F>
void permute(const Parallel& par, LayoutScratch& s, Array<T>& a, const std::vector<int>& order, F f) {
  Array<T>& out = spare<T>(s);
  if (out.capacity() < a.capacity()) out.reserve(a.capacity());
  out.resize(a.size());
  const T* src = a.data();
  T* dst = out.data();
  par.run(int(order.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      // The sources are scattered (new elements sit at the end until a relayout): fetch them
      // ahead. Not the renaming tables' entries: prefetching those too made it slower
      // (docs/PERFORMANCE.md).
      if (k + kAhead < e) __builtin_prefetch(&src[order[k + kAhead]]);
      dst[k] = f(src[order[k]]);
    }
  });
  a.swap(out);
}
template <class T>
void permute(const Parallel& par, LayoutScratch& s, Array<T>& a, const std::vector<int>& order) {
  permute(par, s, a, order, [](const T& v) { return v; });
}

/// Repacks one adjacency pool (list) and its parallel pool in the new vertex order: the vertex
/// now in slot k (heads already permuted) gets a block of room_for(count) entries, the blocks
/// packed in slot order, so neighbouring vertices' lists share cache lines and no garbage is
/// left. f and g rename the entries of list and parallel.
template <class F, class G>
void repack(const Parallel& par, LayoutScratch& s, Array<std::int32_t>& list, Array<std::int32_t>& parallel,
            Array<ListHead>& heads, F f, G g) {
  const int n = int(heads.size());
  s.at_old.resize(n);
  std::int64_t total = 0;  // a serial prefix sum: a few ns per vertex, and relayout is rare
  for (int k = 0; k < n; ++k) {
    ListHead& h = heads[k];
    s.at_old[k] = h.at;
    h.room = std::uint16_t(room_for(h.count));
    h.at = std::int32_t(total);
    total += h.room;
  }
  auto copy = [&](Array<std::int32_t>& pool, auto rename) {
    Array<std::int32_t>& out = spare<std::int32_t>(s);
    if (out.capacity() < pool.capacity()) out.reserve(pool.capacity());
    out.resize(std::size_t(total));
    const std::int32_t* src = pool.data();
    std::int32_t* dst = out.data();
    par.run(n, kGrain, [&](int b, int e) {
      for (int k = b; k < e; ++k) {
        if (k + kAhead < e) __builtin_prefetch(&src[s.at_old[k + kAhead]]);
        for (int w = 0; w < heads[k].count; ++w) dst[heads[k].at + w] = rename(src[s.at_old[k] + w]);
      }
    });
    pool.swap(out);
  };
  copy(list, f);
  copy(parallel, g);
}

/// Morton order of the vertex slots by rest position, dead slots last, into s.vorder.
void vertex_order(const Parallel& par, const Vertices& V, LayoutScratch& s) {
  const int n = V.size();
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int v = 0; v < n; ++v) {
    if (!(V.mass(v) > 0)) continue;
    const Float4 X = V.rest[v];
    const float r[3] = {X.x, X.y, X.z};
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], r[d]), hi[d] = std::max(hi[d], r[d]);
  }
  // Resolution: a sheet of n vertices has about sqrt(n) per axis; four times that per axis.
  const int bits = std::clamp(int(std::ceil(std::log2(std::max(n, 2)) / 2)) + 2, 4, 21);
  const double extent = std::max({double(hi[0]) - lo[0], double(hi[1]) - lo[1], double(hi[2]) - lo[2], 1e-30});
  const double scale = double((1 << bits) - 1) / extent;
  s.code.resize(n);
  par.run(n, kGrain, [&](int b, int e) {
    for (int v = b; v < e; ++v) {
      if (!(V.mass(v) > 0)) {
        s.code[v] = std::uint64_t(1) << (3 * bits);  // after every live vertex
        continue;
      }
      const Float4 X = V.rest[v];
      const float r[3] = {X.x, X.y, X.z};
      std::uint64_t code = 0;
      for (int d = 0; d < 3; ++d) {
        const double q = std::clamp((double(r[d]) - lo[d]) * scale, 0.0, double((1 << bits) - 1));
        code |= spread3(std::uint64_t(q)) << d;
      }
      s.code[v] = code;
    }
  });
  radix_order(par, s, 3 * bits + 1, s.vorder);
}

}  // namespace

namespace {
template <class T>
void copy_warm(Array<T>& to, const Array<T>& from) {
  to.clear();
  to.reserve(from.capacity());
  to.resize(from.size());  // touches what relayout writes, and then the room ahead
  to.keep_warm();
}
}  // namespace

LayoutScratch::LayoutScratch(const LayoutScratch& o) { *this = o; }

LayoutScratch& LayoutScratch::operator=(const LayoutScratch& o) {
  if (this == &o) return *this;
  vorder = o.vorder, vnew = o.vnew, eorder = o.eorder, enew = o.enew, torder = o.torder, tnew = o.tnew;
  key = o.key, idx = o.idx, count = o.count, code = o.code, code2 = o.code2, at_old = o.at_old;
  copy_warm(spare_heads, o.spare_heads);
  copy_warm(spare_i, o.spare_i);
  copy_warm(spare_u8, o.spare_u8);
  copy_warm(spare_f4, o.spare_f4);
  copy_warm(spare_edges, o.spare_edges);
  copy_warm(spare_faces, o.spare_faces);
  return *this;
}

bool layout_stale(const Topology& m, double fraction) {
  if (fraction < 0) return false;
  return double(m.V.created) >= fraction * m.V.size();
}

void relayout(Topology& m, const Parallel& par, LayoutScratch& s) {
  Vertices& V = m.V;
  Edges& E = m.E;
  Triangles& T = m.T;
  const int nv = V.size(), ne = E.size(), nt = T.size();

  vertex_order(par, V, s);
  inverse(par, s.vorder, s.vnew);
  const std::vector<int>& vnew = s.vnew;
  s.key.resize(ne);
  par.run(ne, kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) s.key[k] = (E[k].flags & kAlive) ? std::min(vnew[E[k].a], vnew[E[k].b]) : nv;
  });
  counting_order(par, s, nv + 1, s.eorder);
  inverse(par, s.eorder, s.enew);
  s.key.resize(nt);
  par.run(nt, kGrain, [&](int b, int e) {
    for (int t = b; t < e; ++t)
      s.key[t] = T.alive[t] ? std::min({vnew[T[t].v[0]], vnew[T[t].v[1]], vnew[T[t].v[2]]}) : nv;
  });
  counting_order(par, s, nv + 1, s.torder);
  inverse(par, s.torder, s.tnew);
  const std::vector<int>&vorder = s.vorder, &eorder = s.eorder, &torder = s.torder, &enew = s.enew, &tnew = s.tnew;

  auto vmap = [&](std::int32_t v) { return v >= 0 ? std::int32_t(vnew[v]) : v; };
  auto emap = [&](std::int32_t e) { return e >= 0 ? std::int32_t(enew[e]) : e; };
  auto tmap = [&](std::int32_t t) { return t >= 0 ? std::int32_t(tnew[t]) : t; };

  // Vertices: the state that lives across steps (forces, sums and guesses are rewritten by the
  // next step before anything reads them), then the adjacency lists with their entries renamed.
  for (Array<Float4>* a : {&V.xm, &V.vm, &V.nr, &V.rest}) permute(par, s, *a, vorder);
  for (Array<ListHead>* a : {&V.spring_list, &V.tri_list}) permute(par, s, *a, vorder);
  permute(par, s, V.lid, vorder);
  repack(par, s, V.springs, V.nbrs, V.spring_list, [&](std::int32_t x) { return (enew[x >> 1] << 1) | (x & 1); },
         vmap);
  repack(par, s, V.tris, V.wings, V.tri_list, [&](std::int32_t x) { return (tnew[x >> 2] << 2) | (x & 3); }, emap);
  V.garbage_e = V.garbage_t = 0;

  // Edges (the edge pass's output is per step and is not kept). A dead edge joins slot 0 to
  // itself, as the topology's convention says.
  permute(par, s, E.slots, eorder, [&](EdgeRecord r) {
    if (r.flags & kAlive) r.a = vmap(r.a), r.b = vmap(r.b);
    else r.a = r.b = 0;
    r.wl = vmap(r.wl), r.wr = vmap(r.wr), r.tri0 = tmap(r.tri0), r.tri1 = tmap(r.tri1);
    return r;
  });
  permute(par, s, E.lid, eorder);

  // Triangles (dead ones keep corners 0 and no edges).
  const std::uint8_t* old_alive = T.alive.data();
  permute(par, s, T.slots, torder, [&](Face f) {
    for (int k = 0; k < 3; ++k) f.v[k] = std::int32_t(vnew[f.v[k]]), f.e[k] = emap(f.e[k]);
    return f;
  });
  par.run(nt, kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k)
      if (!old_alive[torder[k]]) T[k].v = kNoFace.v;
  });
  permute(par, s, T.area, torder);
  permute(par, s, T.lid, torder);
  permute(par, s, T.alive, torder);  // last: read above

  // Split records (free ones too: their stale ids stay in range and are overwritten on reuse).
  par.run(int(m.records.size()), kGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      SplitRecord& r = m.records[k];
      r.n = vmap(r.n);
      for (int q = 0; q < 4; ++q) r.k[q] = vmap(r.k[q]), r.e[q] = emap(r.e[q]), r.t[q] = tmap(r.t[q]);
    }
  });

  // The inverse maps; free lists hold logical ids and do not change.
  inverse(par, V.lid, V.phys);
  inverse(par, E.lid, E.phys);
  inverse(par, T.lid, T.phys);
  V.created = 0;
}

}  // namespace crumple::fast
