#include "fast/layout_order.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "fast/radix.h"

namespace crumple::fast::layout_order {

namespace {

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

}  // namespace

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

// A counting sort by the lowest corner's slot; a dead triangle's key is past every slot.
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

namespace {

/// The springs in v's list whose other end has a higher slot: each live edge is listed once at
/// each end (Topology::check), so once at its lower end.
int owned_springs(const Vertices& V, int v) {
  const ListHead h = V.spring_list[v];
  const std::int32_t* nbr = &V.nbrs[std::size_t(h.at)];
  int owned = 0;
  for (int w = 0; w < h.count; ++w) owned += nbr[w] > v;
  return owned;
}

}  // namespace

// Read from the spring lists that phase two packed in vertex order (the events of a step since
// may have moved a few blocks: locality, not correctness; two streaming passes over them, a
// fixed block of vertices at a time) rather than sorted by a key over every edge record:
// the passes gather an edge's endpoints, not its neighbours in slot order, so any order within
// one lower endpoint serves locality, and none changes a bit of what a step computes.
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
}

}  // namespace crumple::fast::layout_order
