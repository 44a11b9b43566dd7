#include "fast/kernels.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "fast/lanes8.h"
#include "fast/wide.h"

#if CRUMPLE_DISABLE_SIMD
#define CRUMPLE_SIMD_LOOP  // the no-SIMD build: no vectorization hints (and no unknown-pragma warnings)
#else
#define CRUMPLE_SIMD_LOOP _Pragma("omp simd")
#endif
#define CRUMPLE_SCALAR_KERNEL [[gnu::optimize("no-tree-vectorize")]]

namespace crumple::fast {

// GCC honours __restrict on parameters, not on local pointers: each vectorized kernel is a
// body taking raw arrays, wrapped by the public range function. CRUMPLE_SIMD_LOOP marks a loop
// whose iterations are independent (`omp simd`, compiled with -fopenmp-simd: no OpenMP runtime).
// CRUMPLE_SCALAR_KERNEL keeps the vectorizer off a kernel whose loads are random gathers (of
// positions: the triangle pass and the edge pass's fallback): scalar, because Zen 4 executes
// vector gathers slower than the scalar loads they replace (docs/PERFORMANCE.md). The edge pass
// itself runs eight edges in AVX lanes from 16-byte rows instead (lanes8.h), as the adapt test
// does (kernels_adapt.cpp).
namespace {
// The scalar kernels prefetch the rows read by the element a fixed distance ahead: an element is
// tens of instructions, so the core's reorder window spans only a few elements and few of their
// misses overlap. The eight-lane edge pass issues its 64 row loads (80 with damping) before any
// arithmetic and gains nothing from a prefetch (docs/PERFORMANCE.md).
constexpr int kTriangleAhead = 64;  ///< triangle_areas: three row loads a triangle

// One triangle's area vector: the loop body of triangle_areas and the whole of triangle_area,
// so that an event's areas and the pass's are the same bits. Both callers are scalar kernels:
// vectorized in one and not the other, the products could contract into FMAs differently.
[[gnu::always_inline]] inline Float4 area_of(const Face& f, std::uint8_t alive, const Float4* xm, float unit) {
  const Float4 pa = xm[f.v[0]], pb = xm[f.v[1]], pc = xm[f.v[2]];
  const float ux = (pb.x - pa.x) * unit, uy = (pb.y - pa.y) * unit, uz = (pb.z - pa.z) * unit;
  const float wx = (pc.x - pa.x) * unit, wy = (pc.y - pa.y) * unit, wz = (pc.z - pa.z) * unit;
  const float on = alive ? 1.0f : 0.0f;
  return Float4{on * (uy * wz - uz * wy), on * (uz * wx - ux * wz), on * (ux * wy - uy * wx), 0.0f};
}

CRUMPLE_SCALAR_KERNEL void triangle_areas_body(const Face* __restrict faces, const std::uint8_t* __restrict alive,
                                               const Float4* __restrict xm, float unit, Float4* __restrict area,
                                               int begin, int end) {
  for (int t = begin; t < end; ++t) {
    if (t + kTriangleAhead < end) {
      const Face& next = faces[t + kTriangleAhead];
      for (int k = 0; k < 3; ++k) __builtin_prefetch(&xm[next.v[k]]);
    }
    area[t] = area_of(faces[t], alive[t], xm, unit);
  }
}
}  // namespace

void triangle_areas(const Topology& m, float unit, Float4* area, int begin, int end) {
  triangle_areas_body(m.T.slots.data(), m.T.alive.data(), m.V.xm.data(), unit, area, begin, end);
}

CRUMPLE_SCALAR_KERNEL void triangle_area(const Topology& m, float unit, Float4* area, int t) {
  area[t] = area_of(m.T[t], m.T.alive[std::size_t(t)], m.V.xm.data(), unit);
}

namespace {
// Sums over adjacency lists. The first kFixed entries of a list are summed in a loop of fixed
// length, entries past the list's count selecting a zero record (adding an exact 0 changes no
// sum: a sum that starts at +0 never becomes -0), the rest in a loop to the count. GCC unrolls
// the fixed loop and, knowing the zero record's value, turns the selects into exits at the
// count: one compare an entry, no loop counter, no record loaded past the count, which costs
// less than loading all kFixed entries without a branch (docs/PERFORMANCE.md). Every list's
// block has room for at least kFixed entries (kMinRoom, topology.h), so reading them needs no
// bounds test.
constexpr int kFixed = 8;
static_assert(kFixed <= kMinRoom);
alignas(64) const EdgeOut kZeroRow{};
const Float4 kZero4{};
using Row4 = Wide<4>;

/// Calls f(entry, in_list) for the first kFixed slots of a list of n entries (in_list false past
/// n: f reads its zero record then), and f(entry, true) for the rest: the loop every list sum uses.
template <class F>
void for_list(const std::int32_t* list, int n, F f) {
  for (int k = 0; k < kFixed; ++k) f(list[k], k < n);
  for (int k = kFixed; k < n; ++k) f(list[k], true);
}

// The 32-byte records the gather reads are scattered, and a vertex's loads are few, so the
// gather fetches the first kFixed records of the vertex kAhead places on while it sums this one
// (entries past a list's count fetch the zero record), and that vertex's first kFixed
// neighbours' velocity rows, which the vertices created since the last relayout (at the
// arrays' end) scatter. The Jacobi sweep and the normals do not: their 16-byte records mostly
// hit the cache, and prefetching them made those passes slower (docs/PERFORMANCE.md).
constexpr int kAhead = 6;  ///< far enough for the records to arrive, near enough to stay in L1
void prefetch_list(const EdgeOut* records, const std::int32_t* list, int count, int shift) {
  for (int k = 0; k < kFixed; ++k) __builtin_prefetch(k < count ? &records[list[k] >> shift] : &kZeroRow);
}
/// Entries past the count fetch the row of `self`, which the gather reads anyway.
void prefetch_rows(const Float4* rows, const std::int32_t* list, int count, int self) {
  for (int k = 0; k < kFixed; ++k) __builtin_prefetch(&rows[k < count ? list[k] : self]);
}
}  // namespace

namespace {
// One vertex's normal: the loop body of vertex_normals and the whole of vertex_normal, so that
// an event's normals and the pass's are the same bits (inlined in both: check_simd.sh reads the
// row sum's packed adds in vertex_normals itself).
[[gnu::always_inline]] inline Float4 normal_of(const ListHead& head, const std::int32_t* tris, const Float4* area) {
  Row4 sum = Row4::zero();
  for_list(tris + head.at, head.count, [&](int x, bool in) { sum += Row4::load(in ? &area[x >> 2] : &kZero4); });
  const float sx = sum[0], sy = sum[1], sz = sum[2];
  const float len = std::sqrt(sx * sx + sy * sy + sz * sz);
  const float inv = len > 0 ? 1.0f / len : 0.0f;
  return Float4{sx * inv, sy * inv, sz * inv, 0.0f};
}
}  // namespace

void vertex_normals(const Topology& m, Float4* normals, int begin, int end) {
  const ListHead* __restrict heads = m.V.tri_list.data();
  const std::int32_t* __restrict tris = m.V.tris.data();
  const Float4* __restrict area = m.T.area.data();
  Float4* __restrict n_out = normals;
  for (int v = begin; v < end; ++v) n_out[v] = normal_of(heads[v], tris, area);
}

void vertex_normal(const Topology& m, Float4* normals, int v) {
  normals[v] = normal_of(m.V.tri_list[std::size_t(v)], m.V.tris.data(), m.T.area.data());
}

namespace {
/// An edge's four vertices as the edge pass reads them: the endpoints a, b and, for a hinge (a
/// mesh edge with two wings), the wings l, r; elsewhere l = r = a and `hinge` is 0.
struct Stencil {
  int a, b, l, r;
  float hinge;
};
inline Stencil stencil(const Edges& E, int e) {
  const bool hinge = (E[e].flags & kMesh) && E[e].wl >= 0 && E[e].wr >= 0;
  return {E[e].a, E[e].b, hinge ? E[e].wl : E[e].a, hinge ? E[e].wr : E[e].a, hinge ? 1.0f : 0.0f};
}

#if CRUMPLE_LANES8
/// stencil() of eight edges in lanes: their rows' ids into a, b, l, r, the hinge (1 or 0) and
/// the rest lengths as registers. Selects in lanes rather than stencil()'s per-edge tests, which
/// compile to branches that mispredict wherever hinges and other edges alternate.
inline void stencils8(const EdgeRecord* const edge[8], int a[8], int b[8], int l[8], int r[8], __m256& hinge,
                      __m256& rest) {
  using namespace lanes8;
  __m256 fa, fb, fwl, fwr, unused, flags;
  load_at(edge, kStencilRow, fa, fb, fwl, fwr);
  load_at(edge, kRestRow, unused, rest, unused, flags);
  const __m256i ia = _mm256_castps_si256(fa), wl = _mm256_castps_si256(fwl), wr = _mm256_castps_si256(fwr);
  const __m256i mesh_bit = _mm256_set1_epi32(kMesh);
  const __m256i mesh = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_castps_si256(flags), mesh_bit), mesh_bit);
  const __m256i wings = _mm256_cmpgt_epi32(_mm256_setzero_si256(), _mm256_or_si256(wl, wr));  // -1: a wing < 0
  const __m256i is_hinge = _mm256_andnot_si256(wings, mesh);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(a), ia);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(b), _mm256_castps_si256(fb));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(l), _mm256_blendv_epi8(ia, wl, is_hinge));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(r), _mm256_blendv_epi8(ia, wr, is_hinge));
  hinge = _mm256_and_ps(_mm256_castsi256_ps(is_hinge), _mm256_set1_ps(1.0f));
}

// The edge pass eight edges at a time (lanes8.h); a last block of fewer than eight repeats the
// range's last edge in the lanes past it and stores only its own lanes.
template <bool damped>
void edge_forces_body(const Edges& E, const Vertices& V, const StepConstants& c, EdgeOut* __restrict out,
                      int begin, int end) {
  using namespace lanes8;
  const __m256 kappa = _mm256_set1_ps(c.kappa), damping = _mm256_set1_ps(c.damping), bend = _mm256_set1_ps(c.bend);
  const __m256 quarter = _mm256_set1_ps(c.balanced ? 0.25f : 0.0f), half = _mm256_set1_ps(0.5f);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  // Where lanes past the range store (never read). Per thread and off the stack: a stack array
  // would be zeroed on every call, and ThreadSanitizer, which cannot see oneTBB's
  // uninstrumented wait, then reports that write against a worker's atomic write to an earlier
  // loop's wait node that lived at the same stack address (a false race, tests/tsan.supp).
  alignas(32) static thread_local EdgeOut spare[8];
  for (int e0 = begin; e0 < end; e0 += 8) {
    int a[8], b[8], l[8], r[8];
    const EdgeRecord* edge[8];
    float* dst[8];
    for (int k = 0; k < 8; ++k) {
      edge[k] = &E[std::min(e0 + k, end - 1)];
      dst[k] = e0 + k < end ? &out[e0 + k].fx : &spare[k].fx;
    }
    __m256 hinge, rest;
    stencils8(edge, a, b, l, r, hinge, rest);
    __m256 xa, ya, za, ma, xb, yb, zb, mb, unused;
    load_rows(V.xm.data(), a, xa, ya, za, ma);
    load_rows(V.xm.data(), b, xb, yb, zb, mb);
    // Hookean spring with kappa_e = kappa (m_a + m_b) [Eq 5], damping along the axis (§2).
    const __m256 dx = xa - xb, dy = ya - yb, dz = za - zb;
    const __m256 lt = _mm256_sqrt_ps(dx * dx + dy * dy + dz * dz);
    const __m256 inv = _mm256_and_ps(_mm256_cmp_ps(lt, zero, _CMP_GT_OQ), one / lt);
    const __m256 msum = ma + mb;
    __m256 axial = -kappa * (lt - rest);
    if constexpr (damped) {
      __m256 vxa, vya, vza, vxb, vyb, vzb;
      load_rows(V.vm.data(), a, vxa, vya, vza, unused);
      load_rows(V.vm.data(), b, vxb, vyb, vzb, unused);
      const __m256 rel = -((vxb - vxa) * dx + (vyb - vya) * dy + (vzb - vza) * dz) * inv;
      axial = axial - damping * rel;
    }
    const __m256 s = axial * msum * inv;
    // Bending [Eq 8-9]: k = s C_beta B, B = (1 - n_rl)|e|/2, the sign from the wings' normals.
    __m256 nxa, nya, nza, nxb, nyb, nzb, nxl, nyl, nzl, nxr, nyr, nzr, xl, yl, zl, xr, yr, zr;
    load_rows(V.nr.data(), a, nxa, nya, nza, unused);
    load_rows(V.nr.data(), b, nxb, nyb, nzb, unused);
    load_rows(V.nr.data(), l, nxl, nyl, nzl, unused);
    load_rows(V.nr.data(), r, nxr, nyr, nzr, unused);
    load_rows(V.xm.data(), l, xl, yl, zl, unused);
    load_rows(V.xm.data(), r, xr, yr, zr, unused);
    const __m256 nrl = nxr * nxl + nyr * nyl + nzr * nzl;
    const __m256 Bmag = (one - nrl) * lt * half;
    const __m256 gx = (xr + nxr) - (xl + nxl), gy = (yr + nyr) - (yl + nyl), gz = (zr + nzr) - (zl + nzl);
    const __m256 ox = xr - xl, oy = yr - yl, oz = zr - zl;
    const __m256 gap = _mm256_sqrt_ps(gx * gx + gy * gy + gz * gz) - _mm256_sqrt_ps(ox * ox + oy * oy + oz * oz);
    const __m256 k = hinge * (sign(gap) * bend * msum * Bmag);
    const __m256 qk = quarter * k;  // mean of f_i = -k n_i, f_j = -k n_j, f_r = k n_r, f_l = k n_l
    store_rows(dst, s * dx, s * dy, s * dz, k);
    float* const mean[8] = {dst[0] + 4, dst[1] + 4, dst[2] + 4, dst[3] + 4, dst[4] + 4, dst[5] + 4, dst[6] + 4, dst[7] + 4};
    store_rows(mean, qk * (nxr + nxl - nxa - nxb), qk * (nyr + nyl - nya - nyb), qk * (nzr + nzl - nza - nzb), zero);
  }
}
#else
// The same pass one edge at a time (a target without AVX2, or the no-SIMD build).
template <bool damped>
CRUMPLE_SCALAR_KERNEL void edge_forces_body(const Edges& E, const Vertices& V, const StepConstants& c,
                                            EdgeOut* __restrict out, int begin, int end) {
  const float quarter = c.balanced ? 0.25f : 0.0f;
  for (int e = begin; e < end; ++e) {
    const Stencil q = stencil(E, e);
    const Float4 pa = V.xm[q.a], pb = V.xm[q.b];
    const Float4 na = V.nr[q.a], nb = V.nr[q.b], nl = V.nr[q.l], nr = V.nr[q.r], pl = V.xm[q.l], pr = V.xm[q.r];
    // Hookean spring with kappa_e = kappa (m_a + m_b) [Eq 5], damping along the axis (§2).
    const float dx = pa.x - pb.x, dy = pa.y - pb.y, dz = pa.z - pb.z;
    const float lt = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float inv = lt > 0 ? 1.0f / lt : 0.0f;
    const float msum = pa.w + pb.w;
    float axial = -c.kappa * (lt - E[e].l0);
    if constexpr (damped) {
      const Float4 va = V.vm[q.a], vb = V.vm[q.b];
      const float rel = -((vb.x - va.x) * dx + (vb.y - va.y) * dy + (vb.z - va.z) * dz) * inv;
      axial = axial - c.damping * rel;
    }
    const float s = axial * msum * inv;
    // Bending [Eq 8-9]: k = s C_beta B, B = (1 - n_rl)|e|/2, the sign from the wings' normals.
    const float nrl = nr.x * nl.x + nr.y * nl.y + nr.z * nl.z;
    const float Bmag = (1.0f - nrl) * lt * 0.5f;
    const float gx = (pr.x + nr.x) - (pl.x + nl.x), gy = (pr.y + nr.y) - (pl.y + nl.y), gz = (pr.z + nr.z) - (pl.z + nl.z);
    const float ox = pr.x - pl.x, oy = pr.y - pl.y, oz = pr.z - pl.z;
    const float gap = std::sqrt(gx * gx + gy * gy + gz * gz) - std::sqrt(ox * ox + oy * oy + oz * oz);
    const float sign = gap > 0 ? 1.0f : (gap < 0 ? -1.0f : 0.0f);
    const float k = q.hinge * (sign * c.bend * msum * Bmag);
    const float qk = quarter * k;  // mean of f_i = -k n_i, f_j = -k n_j, f_r = k n_r, f_l = k n_l
    out[e] = EdgeOut{s * dx, s * dy, s * dz, k, qk * (nr.x + nl.x - na.x - nb.x), qk * (nr.y + nl.y - na.y - nb.y),
                     qk * (nr.z + nl.z - na.z - nb.z), 0.0f};
  }
}
#endif
}  // namespace

// Without damping (the default) the pass reads no velocity: two of its ten rows an edge.
void edge_forces(const Edges& E, const Vertices& V, const StepConstants& c, EdgeOut* out, int begin, int end) {
  if (c.damping != 0.0f) edge_forces_body<true>(E, V, c, out, begin, end);
  else edge_forces_body<false>(E, V, c, out, begin, end);
}

namespace {
// The gather sums whole EdgeOut records as rows of 8 floats, each scaled lane by lane by the
// role the vertex plays: (f, -kb, mean) for endpoint a, the force negated for endpoint b (b
// receives the opposite of a), and only (kb, mean) as a wing. Scaling by 1, -1 or 0 is exact,
// so each lane sums exactly what per-field sums would.
using Row = Wide<8>;
static_assert(sizeof(EdgeOut) == sizeof(Row));
const Row kAsEndpoint[2] = {
    Row{{1, 1, 1, -1, 1, 1, 1, 0}},     // v is a
    Row{{-1, -1, -1, -1, 1, 1, 1, 0}},  // v is b
};
const Row kAsWing{{0, 0, 0, 1, 1, 1, 1, 0}};
}  // namespace

void gather_forces(const Topology& m, const EdgeOut* records, const StepConstants& c, VertexForces& f, Float4* g,
                   int begin, int end) {
  const Vertices& V = m.V;
  const EdgeOut* __restrict out = records;
  const Float4* __restrict vm = V.vm.data();
  for (int v = begin; v < end; ++v) {
    if (v + kAhead < end) {
      const int a = v + kAhead;
      const ListHead sa = V.spring_list[a], ta = V.tri_list[a];
      prefetch_list(out, &V.springs[sa.at], sa.count, 1);
      prefetch_list(out, &V.wings[ta.at], ta.count, 0);
      prefetch_rows(vm, &V.nbrs[sa.at], sa.count, a);
    }
    // Per spring, its record and the implicit block W_e = w (m_v + m_o) I [Eq 5, D17] with
    // W_e (v_o - v) from the rows of v and of the neighbour o (nothing per edge to store for
    // them): the springs list and its parallel neighbours list in one loop, in list order.
    const Row4 self = Row4::load(&vm[v]);
    const float mass = self[3];
    Row sum = Row::zero();
    Row4 j = Row4::zero();
    float ks = 0;
    const ListHead sl = V.spring_list[v], tl = V.tri_list[v];
    const std::int32_t* springs = &V.springs[sl.at];
    const std::int32_t* nbrs = &V.nbrs[sl.at];
    const int ns = sl.count, nt = tl.count;
    auto spring = [&](int k, bool in) {
      const int x = springs[k];
      sum += Row::load(in ? &out[x >> 1] : &kZeroRow) * kAsEndpoint[x & 1];
      const Row4 other = Row4::load(in ? &vm[nbrs[k]] : &vm[v]);
      const float w = in ? c.implicit * (mass + other[3]) : 0.0f;
      ks += w;
      j += w * (other - self);
    };
    for (int k = 0; k < kFixed; ++k) spring(k, k < ns);
    for (int k = kFixed; k < ns; ++k) spring(k, true);
    const std::int32_t* wings = &V.wings[tl.at];  // v is a wing of the edge opposite it
    for_list(wings, nt, [&](int x, bool in) { sum += Row::load(in ? &out[x] : &kZeroRow) * kAsWing; });
    float fx = sum[0], fy = sum[1], fz = sum[2];
    const float kn = sum[3], mx = sum[4], my = sum[5], mz = sum[6];  // f = -k n_v (hinge), +k n_v (wing), - mean
    const float jx = j[0], jy = j[1], jz = j[2];                     // sum of W_e (v_other - v_v)
    const Float4 n = V.nr[v];
    fx += kn * n.x - mx;
    fy += kn * n.y - my;
    fz += kn * n.z - mz - mass * c.gravity;
    f.fx[v] = fx;
    f.fy[v] = fy;
    f.fz[v] = fz;
    f.ksum[v] = ks;
    const float dead = mass > 0 ? 0.0f : 1.0f;
    if (c.bounded) {
      // Bounded predictor (DECISIONS.md D1): the row with its Gershgorin diagonal, g exact.
      const float inv = 1.0f / (mass + 2.0f * ks + dead);
      g[v] = Float4{self[0] + (c.h * fx + jx) * inv, self[1] + (c.h * fy + jy) * inv,
                    self[2] - c.h * c.gravity + (c.h * (fz + mass * c.gravity) + jz) * inv, mass};
    } else {
      const float inv = c.h / (mass + dead);
      g[v] = Float4{self[0] + fx * inv, self[1] + fy * inv, self[2] + fz * inv, mass};
    }
  }
}

void jacobi_sweep(const Topology& m, const VertexForces& f, const StepConstants& c, const Float4* g_in,
                  Float4* g_next, int begin, int end) {
  const Vertices& V = m.V;
  const Float4* __restrict g = g_in;
  for (int v = begin; v < end; ++v) {
    Row4 sum = Row4::zero();
    const Float4 vel = V.vm[v];
    const float mass = vel.w;
    const ListHead sl = V.spring_list[v];
    const std::int32_t* nbrs = &V.nbrs[sl.at];
    const int n = sl.count;
    auto add = [&](const Float4* p) {
      const Row4 o = Row4::load(p);
      sum += (c.implicit * (mass + o[3])) * o;  // W_e (the neighbour's mass in w) times its guess
    };
    // for_list's loops, written out: through for_list GCC contracts this multiply-add into FMAs
    // differently, which changes the rounding of every run (the state hashes would change).
    for (int k = 0; k < kFixed; ++k) add(k < n ? &g[nbrs[k]] : &kZero4);
    for (int k = kFixed; k < n; ++k) add(&g[nbrs[k]]);
    const float sx = sum[0], sy = sum[1], sz = sum[2];
    const float inv = 1.0f / (mass + f.ksum[v] + (mass > 0 ? 0.0f : 1.0f));
    g_next[v] = Float4{(mass * vel.x + c.h * f.fx[v] + sx) * inv,
                       (mass * vel.y + c.h * f.fy[v] + sy) * inv,
                       (mass * vel.z + c.h * f.fz[v] + sz) * inv, mass};
  }
}

void explicit_velocity(const Vertices& V, const VertexForces& f, const StepConstants& c, Float4* g, int begin,
                       int end) {
  for (int v = begin; v < end; ++v) {
    const Float4 vel = V.vm[v];
    const float inv = vel.w > 0 ? c.h / vel.w : 0.0f;
    g[v] = Float4{vel.x + f.fx[v] * inv, vel.y + f.fy[v] * inv, vel.z + f.fz[v] * inv, vel.w};
  }
}

void momentum_drift(const Vertices& V, const VertexForces& f, const Float4* g, const StepConstants& c, int begin,
                    int end, double out[4]) {
  double sx = 0, sy = 0, sz = 0, mass = 0;
  for (int v = begin; v < end; ++v) {
    const Float4 vel = V.vm[v];
    sx += double(vel.w) * (double(g[v].x) - vel.x) - double(c.h) * f.fx[v];
    sy += double(vel.w) * (double(g[v].y) - vel.y) - double(c.h) * f.fy[v];
    sz += double(vel.w) * (double(g[v].z) - vel.z) - double(c.h) * f.fz[v];
    mass += vel.w;
  }
  out[0] = sx;
  out[1] = sy;
  out[2] = sz;
  out[3] = mass;
}

namespace {
// `sphere` a template parameter: a branch on it inside the loop is control flow that the
// vectorizer of an AVX2 target cannot turn into selects (its float operations could trap, and
// AVX2 has no masked ones), so each case gets its own branch-free loop.
template <bool sphere>
void advance_body(const StepConstants& c, const float corr[3], const float center[3], float radius,
                  Float4* __restrict xm, Float4* __restrict vm, const Float4* __restrict g, int begin,
                  int end) {
  // The constants as locals: read through pointers inside the loop they stop it from vectorizing.
  const float h = c.h, c0 = corr[0], c1 = corr[1], c2 = corr[2], s0 = center[0], s1 = center[1], s2 = center[2];
  CRUMPLE_SIMD_LOOP
  for (int v = begin; v < end; ++v) {
    const Float4 p = xm[v];
    const float on = p.w > 0 ? 1.0f : 0.0f;
    float ux = on * (g[v].x - c0), uy = on * (g[v].y - c1), uz = on * (g[v].z - c2);
    float px = p.x + h * ux, py = p.y + h * uy, pz = p.z + h * uz;
    if constexpr (sphere) {
      // The manipulation sphere (§8): onto the sphere, outward velocity removed.
      const float dx = px - s0, dy = py - s1, dz = pz - s2;
      const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
      const bool out = r > radius;
      // 1/r where r > 0, else 0, with the division unconditional (a conditional one could trap).
      const float inv = (r > 0 ? 1.0f : 0.0f) * (1.0f / (r > 0 ? r : 1.0f));
      const float nx = dx * inv, ny = dy * inv, nz = dz * inv;
      px = out ? s0 + radius * nx : px;
      py = out ? s1 + radius * ny : py;
      pz = out ? s2 + radius * nz : pz;
      const float radial = ux * nx + uy * ny + uz * nz;
      const float cut = (out && radial > 0) ? radial : 0.0f;
      ux -= cut * nx;
      uy -= cut * ny;
      uz -= cut * nz;
    }
    xm[v] = Float4{px, py, pz, p.w};
    vm[v] = Float4{ux, uy, uz, p.w};
  }
}
}  // namespace

void advance(const Float4* g, const StepConstants& c, const float corr[3], const float center[3], float radius,
             Vertices& V, int begin, int end) {
  auto run = [&](auto body) {
    body(c, corr, center, radius, V.xm.data(), V.vm.data(), g, begin, end);
  };
  if (radius > 0) run(advance_body<true>);
  else run(advance_body<false>);
}

}  // namespace crumple::fast
