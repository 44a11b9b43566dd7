// The fast backend's state as the rest of the program sees it: totals, snapshots, test hooks.
// Everything here is in logical ids (topology.h): element k of every list is logical id k,
// whatever slot layout.h has put it in, and sums run in logical order, but for the edges' part
// of the totals (edge_totals).
#include <algorithm>
#include <bit>
#include <cmath>

#include "fast/fast_sim.h"
#include "fast/lanes8.h"

namespace crumple::fast {

namespace {
/// One block of vertex ids' share of the totals: sums in double, maxima, and whether any state
/// was not finite.
struct VertexPart {
  double mass = 0, momentum[3] = {0, 0, 0}, kinetic = 0, max_speed = 0, max_distance = 0;
  bool finite = true;
};
/// One block of edge slots' share: the largest strain, the squared strains' sum, the counts.
struct EdgePart {
  double max_strain = 0, strain2 = 0;
  int mesh_edges = 0, auxiliary = 0;
};
/// The vertex sums run in logical order, so each id's slot is a random read: the rows of the id
/// this far ahead are prefetched, so that the reads overlap instead of waiting one after the
/// other.
constexpr int kTotalsAhead = 64;

void vertex_totals(const Vertices& V, const double c[3], int begin, int end, VertexPart& out) {
  VertexPart t;  // a local, whose sums stay in registers (through `out` each add would store)
  for (int id = begin; id < end; ++id) {
    if (id + kTotalsAhead < end) {
      const int ahead = V.phys[id + kTotalsAhead];
      __builtin_prefetch(&V.xm[ahead]), __builtin_prefetch(&V.vm[ahead]);
    }
    const int v = V.phys[id];
    if (!(V.mass(v) > 0)) continue;
    const double m = V.mass(v), vx = V.vm[v].x, vy = V.vm[v].y, vz = V.vm[v].z;
    t.mass += m;
    t.momentum[0] += m * vx;
    t.momentum[1] += m * vy;
    t.momentum[2] += m * vz;
    const double v2 = vx * vx + vy * vy + vz * vz;
    t.kinetic += 0.5 * m * v2;
    t.max_speed = std::max(t.max_speed, v2);  // squared until the block's end: see below
    const double dx = V.xm[v].x - c[0], dy = V.xm[v].y - c[1], dz = V.xm[v].z - c[2];
    t.max_distance = std::max(t.max_distance, dx * dx + dy * dy + dz * dz);
    t.finite &= bool(std::isfinite(V.xm[v].x + V.xm[v].y + V.xm[v].z + v2));
  }
  // The largest root is the root of the largest square (a correctly rounded square root is
  // monotone, and std::max skips a NaN second argument either way): one root a block, not two
  // a vertex.
  t.max_speed = std::sqrt(t.max_speed);
  t.max_distance = std::sqrt(t.max_distance);
  out = t;
}

/// One edge's strain |x_a - x_b| / l0 - 1, from its endpoints' rows, in double.
inline double strain_of(const EdgeRecord& r, const Float4& pa, const Float4& pb) {
  const double dx = double(pa.x) - pb.x, dy = double(pa.y) - pb.y, dz = double(pa.z) - pb.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz) / r.l0 - 1.0;
}

// The edges' part runs over slots, where the records stream and the layout keeps each edge's
// endpoints near it (in logical order every record and both endpoints are random reads). The
// counts and the largest strain do not depend on the order; the squared strains' sum, which only
// the instability check reads (rms_strain), may differ in its last bits with the layout
// (docs/DECISIONS.md D12). One slot at a time: the pass without AVX2, and a block's tail.
void edge_totals_scalar(const Edges& E, const Vertices& V, int begin, int end, EdgePart& t) {
  for (int e = begin; e < end; ++e) {
    const EdgeRecord& r = E[e];
    if (!(r.flags & kAlive)) continue;
    if (!(r.flags & kMesh)) {
      ++t.auxiliary;
      continue;
    }
    ++t.mesh_edges;
    const double strain = strain_of(r, V.xm[r.a], V.xm[r.b]);
    t.max_strain = std::max(t.max_strain, std::abs(strain));
    t.strain2 += strain * strain;
  }
}

#if CRUMPLE_LANES8 && defined(__FMA__)
/// The strain of eight mesh edges in lanes, as strain_of computes it (its products fused as GCC
/// fuses them on an FMA target), 0 in the lanes of other slots, whose endpoints are read as
/// vertex 0's (a dead slot's ids may be stale).
void strains8(const EdgeRecord* const edge[8], const Vertices& V, __m256d& lo, __m256d& hi, int& mesh_bits,
              int& auxiliary_bits) {
  using namespace lanes8;
  __m256 fa, fb, unused, l0, flags;
  load_at(edge, kStencilRow, fa, fb, unused, unused);
  load_at(edge, kRestRow, unused, l0, unused, flags);
  const __m256i kind = _mm256_and_si256(_mm256_castps_si256(flags), _mm256_set1_epi32(kAlive | kMesh));
  const __m256i mesh = _mm256_cmpeq_epi32(kind, _mm256_set1_epi32(kAlive | kMesh));
  const __m256i auxiliary = _mm256_cmpeq_epi32(kind, _mm256_set1_epi32(kAlive));
  mesh_bits = _mm256_movemask_ps(_mm256_castsi256_ps(mesh));
  auxiliary_bits = _mm256_movemask_ps(_mm256_castsi256_ps(auxiliary));
  alignas(32) int a[8], b[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(a), _mm256_and_si256(_mm256_castps_si256(fa), mesh));
  _mm256_store_si256(reinterpret_cast<__m256i*>(b), _mm256_and_si256(_mm256_castps_si256(fb), mesh));
  __m256 xa, ya, za, xb, yb, zb;
  load_rows(V.xm.data(), a, xa, ya, za, unused);
  load_rows(V.xm.data(), b, xb, yb, zb, unused);
  auto half = [&](auto part, __m128i lanes) {  // part: the low or the high four lanes as double
    const __m256d dx = part(xa) - part(xb), dy = part(ya) - part(yb), dz = part(za) - part(zb);
    const __m256d d2 = _mm256_fmadd_pd(dz, dz, _mm256_fmadd_pd(dx, dx, dy * dy));
    const __m256d strain = _mm256_sqrt_pd(d2) / part(l0) - _mm256_set1_pd(1.0);
    return _mm256_and_pd(strain, _mm256_castsi256_pd(_mm256_cvtepi32_epi64(lanes)));
  };
  lo = half([](__m256 x) { return _mm256_cvtps_pd(_mm256_castps256_ps128(x)); }, _mm256_castsi256_si128(mesh));
  hi = half([](__m256 x) { return _mm256_cvtps_pd(_mm256_extractf128_ps(x, 1)); }, _mm256_extracti128_si256(mesh, 1));
}

/// Slots ahead whose endpoints' rows edge_totals prefetches, so that the misses of the rows
/// scattered since the last relayout overlap.
constexpr int kStrainAhead = 32;

// Eight slots at a time, branch-free (mesh, auxiliary and dead slots interleave at random, so
// per-slot branches mispredict), the squares summed per lane and the lanes added in a fixed
// order at the end; a block's last slots past a multiple of eight run edge_totals_scalar. The
// blocks are fixed, so the sums are the same on any thread count.
void edge_totals(const Edges& E, const Vertices& V, int begin, int end, EdgePart& out) {
  EdgePart t;  // a local, as in vertex_totals
  __m256d max_lo = _mm256_setzero_pd(), max_hi = max_lo, sum_lo = max_lo, sum_hi = max_lo;
  const __m256d magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffff));
  int e0 = begin;
  for (; e0 + 8 <= end; e0 += 8) {
    if (e0 + kStrainAhead + 8 <= end)
      for (int k = e0 + kStrainAhead; k < e0 + kStrainAhead + 8; ++k)
        __builtin_prefetch(&V.xm[E[k].a]), __builtin_prefetch(&V.xm[E[k].b]);
    const EdgeRecord* edge[8];
    for (int k = 0; k < 8; ++k) edge[k] = &E[e0 + k];
    __m256d lo, hi;
    int mesh, auxiliary;
    strains8(edge, V, lo, hi, mesh, auxiliary);
    t.mesh_edges += std::popcount(unsigned(mesh));
    t.auxiliary += std::popcount(unsigned(auxiliary));
    // max_pd returns its second operand where either is NaN: a NaN strain leaves the maximum as
    // std::max(max, NaN) does.
    max_lo = _mm256_max_pd(_mm256_and_pd(lo, magnitude), max_lo);
    max_hi = _mm256_max_pd(_mm256_and_pd(hi, magnitude), max_hi);
    sum_lo = _mm256_fmadd_pd(lo, lo, sum_lo);
    sum_hi = _mm256_fmadd_pd(hi, hi, sum_hi);
  }
  alignas(32) double m[8], s[8];
  _mm256_store_pd(m, max_lo), _mm256_store_pd(m + 4, max_hi);
  _mm256_store_pd(s, sum_lo), _mm256_store_pd(s + 4, sum_hi);
  for (int k = 0; k < 8; ++k) t.max_strain = std::max(t.max_strain, m[k]), t.strain2 += s[k];
  edge_totals_scalar(E, V, e0, end, t);
  out = t;
}
#else
void edge_totals(const Edges& E, const Vertices& V, int begin, int end, EdgePart& out) {
  EdgePart t;  // a local, as in vertex_totals
  edge_totals_scalar(E, V, begin, end, t);
  out = t;
}
#endif
}  // namespace

// Sums in fixed blocks (of ids; of slots for the edges) whose partial sums are added in block
// order: the same bits on any thread count.
Totals FastSimulator::totals() const {
  const Vertices& V = topo_.V;
  const Edges& E = topo_.E;
  const double c[3] = {scene_.center[0], scene_.center[1], scene_.center[2]};
  const int nv = V.size(), ne = E.size();
  std::vector<VertexPart> vertex_parts(std::size_t(Parallel::blocks_of(nv, kReduceBlock)));
  std::vector<EdgePart> edge_parts(std::size_t(Parallel::blocks_of(ne, kReduceBlock)));
  par_.run_blocks(nv, kReduceBlock, [&](int b, int begin, int end) { vertex_totals(V, c, begin, end, vertex_parts[b]); });
  par_.run_blocks(ne, kReduceBlock, [&](int b, int begin, int end) { edge_totals(E, V, begin, end, edge_parts[b]); });
  Totals T;
  T.vertices = topo_.live_vertices();
  T.triangles = topo_.live_triangles();
  bool finite = true;
  for (const VertexPart& t : vertex_parts) {
    T.mass += t.mass;
    for (int d = 0; d < 3; ++d) T.momentum[d] += t.momentum[d];
    T.kinetic += t.kinetic;
    T.max_speed = std::max(T.max_speed, t.max_speed);
    T.max_distance = std::max(T.max_distance, t.max_distance);
    finite &= t.finite;
  }
  for (const EdgePart& t : edge_parts) {
    T.max_strain = std::max(T.max_strain, t.max_strain);
    T.rms_strain += t.strain2;
    T.edges += t.mesh_edges;
    T.auxiliary += t.auxiliary;
  }
  if (!finite) T.max_distance = NAN;
  T.rms_strain = std::sqrt(T.rms_strain / std::max(1, T.edges));
  return T;
}

double FastSimulator::stiffness_bound() const {
  // Over each vertex's spring list (no scatter); the max does not depend on the order.
  const Vertices& V = topo_.V;
  double mu = 0;
  for (int v = 0; v < V.size(); ++v) {
    if (!(V.mass(v) > 0)) continue;
    double row = 0;
    for (int k = 0; k < V.spring_list[v].count; ++k) {
      const double mi = V.mass(v), mj = V.mass(topo_.nbrs_of(v)[k]);
      row += (mi + mj) * (1 / mi + 1 / std::sqrt(mi * mj));
    }
    mu = std::max(mu, row);
  }
  return mu;
}

Snapshot FastSimulator::snapshot() const {
  const Vertices& V = topo_.V;
  Snapshot s;
  for (int id = 0; id < V.size(); ++id) {
    const int v = V.phys[id];
    const bool alive = V.mass(v) > 0;
    s.vertex_alive.push_back(alive);
    s.rest.push_back(alive ? Vec3d{V.rest[v].x, V.rest[v].y, V.rest[v].z} : Vec3d{});
    s.position.push_back(alive ? Vec3d{V.xm[v].x, V.xm[v].y, V.xm[v].z} : Vec3d{});
    s.velocity.push_back(alive ? Vec3d{V.vm[v].x, V.vm[v].y, V.vm[v].z} : Vec3d{});
    s.mass.push_back(alive ? V.mass(v) : 0.0);
  }
  auto vid = [&](int v) { return v >= 0 ? int(V.lid[v]) : v; };
  for (int id = 0; id < topo_.E.size(); ++id) {
    const int e = topo_.E.phys[id];
    EdgeView ev;
    const std::uint8_t f = topo_.E[e].flags;
    if (f & kAlive) {
      ev.a = vid(topo_.E[e].a);
      ev.b = vid(topo_.E[e].b);
      ev.wing_l = (f & kMesh) ? vid(topo_.E[e].wl) : -1;  // an auxiliary edge keeps its crease's
      ev.wing_r = (f & kMesh) ? vid(topo_.E[e].wr) : -1;  // wings there (topology.h), not a triangle's
      ev.rest = topo_.E[e].l0;
      ev.auxiliary = !(f & kMesh);
      ev.breakable = f & kBreakable;
    }
    s.edges.push_back(ev);
  }
  for (int id = 0; id < topo_.T.size(); ++id) {
    const int t = topo_.T.phys[id];
    s.triangles.push_back(topo_.T.alive[t] ? std::array<int, 3>{vid(topo_.T[t].v[0]), vid(topo_.T[t].v[1]), vid(topo_.T[t].v[2])}
                                           : std::array<int, 3>{-1, -1, -1});
  }
  return s;
}

std::vector<Vec3d> FastSimulator::normals() const {
  FastSimulator tmp(*this);
  tmp.compute_normals();
  std::vector<Vec3d> out;
  for (int id = 0; id < tmp.topo_.V.size(); ++id) {
    const int v = tmp.topo_.V.phys[id];
    out.push_back({tmp.topo_.V.nr[v].x, tmp.topo_.V.nr[v].y, tmp.topo_.V.nr[v].z});
  }
  return out;
}

std::vector<Vec3d> FastSimulator::forces() const {
  FastSimulator tmp(*this);
  tmp.compute_normals();
  tmp.compute_forces();
  tmp.add_grab_forces();
  std::vector<Vec3d> out;
  for (int id = 0; id < tmp.topo_.V.size(); ++id) {
    const int v = tmp.topo_.V.phys[id];
    const VertexForces& f = tmp.step_.forces;
    out.push_back({f.fx[v], f.fy[v], f.fz[v]});
  }
  return out;
}

void FastSimulator::set_state(const std::vector<Vec3d>& x, const std::vector<Vec3d>& v) {
  Vertices& V = topo_.V;
  for (int k = 0; k < V.size() && k < int(x.size()) && k < int(v.size()); ++k) {
    const int s = V.phys[k];
    if (!(V.mass(s) > 0)) continue;
    V.xm[s].x = float(x[k][0]), V.xm[s].y = float(x[k][1]), V.xm[s].z = float(x[k][2]);
    V.vm[s].x = float(v[k][0]), V.vm[s].y = float(v[k][1]), V.vm[s].z = float(v[k][2]);
  }
  normals_valid_ = false;
}

void FastSimulator::set_masses(const std::vector<double>& m) {
  Vertices& V = topo_.V;
  for (int k = 0; k < V.size() && k < int(m.size()); ++k)
    if (V.mass(V.phys[k]) > 0) V.set_mass(V.phys[k], float(m[k]));
}

}  // namespace crumple::fast
