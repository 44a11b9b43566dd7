// The fracture and restoration test of every edge (kernels.h: adapt_test). [Eq 6] breaks a mesh
// edge with P = 1/4 c (1 - phi n_ij)(1 + phi n_rl), c = 1 - lt/l0, made per step by P_step =
// 1 - (1 - P)^(h/h_ref) (MODEL.md §4), against the edge's counter-based random number; [Eq 10]
// restores an auxiliary edge whose crease (wings l, r of its split) is bent across enough,
// (1 - n_rl)/2 >= epsilon. `exact_step`: h = h_ref, so P_step = P (no pow).
//
// With AVX2 the test runs eight edges at a time in lanes (lanes8.h: the records and the rows
// transposed, the hash in 64-bit lanes); elsewhere one edge at a time. Both apply the same
// operations in the same order to each edge, so both make the same decisions (as far as the
// compiler contracts the same products into FMAs, which a build's target decides: D33).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "fast/kernels.h"
#include "fast/lanes8.h"
#include "model/random.h"

namespace crumple::fast {

namespace {
/// The fixed mixes of uniform(seed, step, id, Fracture) (model/random.h), hoisted out of a range.
std::uint64_t seed_and_step(const AdaptConstants& c) { return mix64(mix64(c.seed ^ 0x9e3779b97f4a7c15ULL) ^ c.step); }

/// P_step's pow form for one edge (the budget's factor included), the same expression in both
/// forms of the test. P is clamped to [0, 1] only for the pow: with P_step = P the test (P > 0)
/// & (u < P), u in [0, 1), decides the same for P and its clamp (NaN too). The budget's factor
/// (D22, in [0, 1]) keeps that true: P <= 1 up to round-off (c <= 1, each bracket <= 2), and a
/// factor of exactly 1 changes no bit.
float stepped(float P, float budget, float exponent) {
  return budget * (1.0f - std::pow(1.0f - std::fmin(std::fmax(P, 0.0f), 1.0f), exponent));
}

#if CRUMPLE_LANES8
/// The low 64 bits of a * b in each of four 64-bit lanes.
inline __m256i mullo64(__m256i a, __m256i b) {
#if defined(__AVX512DQ__) && defined(__AVX512VL__)
  return _mm256_mullo_epi64(a, b);
#else
  const __m256i cross = _mm256_add_epi64(_mm256_mul_epu32(_mm256_srli_epi64(a, 32), b),
                                         _mm256_mul_epu32(a, _mm256_srli_epi64(b, 32)));
  return _mm256_add_epi64(_mm256_mul_epu32(a, b), _mm256_slli_epi64(cross, 32));
#endif
}

/// model/random.h's mix64 in four 64-bit lanes.
inline __m256i mix64_lanes(__m256i z) {
  z = mullo64(_mm256_xor_si256(z, _mm256_srli_epi64(z, 30)), _mm256_set1_epi64x(std::int64_t(0xbf58476d1ce4e5b9ULL)));
  z = mullo64(_mm256_xor_si256(z, _mm256_srli_epi64(z, 27)), _mm256_set1_epi64x(std::int64_t(0x94d049bb133111ebULL)));
  return _mm256_xor_si256(z, _mm256_srli_epi64(z, 31));
}

/// uniform(seed, step, id[k], Fracture) for eight logical ids (keyed by the id: the same stream
/// whatever the slot order, layout.h), `seed_step` its first two mixes: 24 bits, exact in float.
inline __m256 fracture_draws(std::uint64_t seed_step, const std::int32_t id[8]) {
  const __m256i ids = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(id));
  const __m256i key = _mm256_set1_epi64x(std::int64_t(seed_step));
  const __m256i draw = _mm256_set1_epi64x(std::int64_t(Draw::Fracture));
  auto four = [&](__m128i ids4) {  // h >> 40 < 2^24: each 64-bit lane's low word holds it
    const __m256i x = _mm256_or_si256(_mm256_slli_epi64(_mm256_cvtepu32_epi64(ids4), 2), draw);
    return _mm256_srli_epi64(mix64_lanes(_mm256_xor_si256(key, x)), 40);
  };
  const __m256i low_words = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
  const __m256i lo = _mm256_permutevar8x32_epi32(four(_mm256_castsi256_si128(ids)), low_words);
  const __m256i hi = _mm256_permutevar8x32_epi32(four(_mm256_extracti128_si256(ids, 1)), low_words);
  return _mm256_cvtepi32_ps(_mm256_permute2x128_si256(lo, hi, 0x20)) * _mm256_set1_ps(1.0f / 16777216.0f);
}

/// Lanes of 32-bit 0 / 1 / 2 -> their low bytes at out, the first n of eight (a range's last
/// block stores only its own).
inline void store_decisions(__m256i d, std::uint8_t* out, int n) {
  const __m128i words = _mm_packus_epi32(_mm256_castsi256_si128(d), _mm256_extracti128_si256(d, 1));
  const __m128i bytes = _mm_packus_epi16(words, words);
  if (n == 8) {
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out), bytes);
  } else {
    alignas(16) std::uint8_t all[16];
    _mm_store_si128(reinterpret_cast<__m128i*>(all), bytes);
    std::memcpy(out, all, std::size_t(n));
  }
}

/// What the test reads of eight edges, as lanes.
struct TestLanes {
  __m256 lt, rest, l0;  ///< current and rest length (both scaled by the unit), rest length as stored
  __m256 nij, nrl;      ///< n_i . n_j, and n_r . n_l (1 without two wings)
  __m256i flags, record;
};

/// Reads edges[e0 .. e0 + 7] (a range's last block repeats edge end - 1 past it) and their
/// vertices' rows into lanes; their logical ids into id.
inline TestLanes load_lanes(const AdaptConstants& c, const EdgeRecord* edges, const std::int32_t* lid,
                            const Float4* xm, const Float4* nr, int e0, int end, std::int32_t id[8]) {
  using namespace lanes8;
  const EdgeRecord* edge[8];
  alignas(32) std::int32_t a[8], b[8], l[8], r[8];
  for (int k = 0; k < 8; ++k) {
    const int e = std::min(e0 + k, end - 1);
    edge[k] = &edges[e], id[k] = lid[e];
  }
  TestLanes t;
  __m256 fa, fb, fwl, fwr, unused, frecord, fflags;
  load_at(edge, kStencilRow, fa, fb, fwl, fwr);
  load_at(edge, kRestRow, unused, t.l0, frecord, fflags);
  // A missing wing (-1) reads vertex 0's row, masked by two_wings: no branch on the wings.
  const __m256i wl = _mm256_castps_si256(fwl), wr = _mm256_castps_si256(fwr);
  const __m256i two_wings = _mm256_cmpgt_epi32(_mm256_or_si256(wl, wr), _mm256_set1_epi32(-1));
  _mm256_store_si256(reinterpret_cast<__m256i*>(a), _mm256_castps_si256(fa));
  _mm256_store_si256(reinterpret_cast<__m256i*>(b), _mm256_castps_si256(fb));
  _mm256_store_si256(reinterpret_cast<__m256i*>(l), _mm256_andnot_si256(_mm256_srai_epi32(wl, 31), wl));
  _mm256_store_si256(reinterpret_cast<__m256i*>(r), _mm256_andnot_si256(_mm256_srai_epi32(wr, 31), wr));
  __m256 xa, ya, za, xb, yb, zb, nxa, nya, nza, nxb, nyb, nzb, nxl, nyl, nzl, nxr, nyr, nzr;
  load_rows(xm, a, xa, ya, za, unused);
  load_rows(xm, b, xb, yb, zb, unused);
  load_rows(nr, a, nxa, nya, nza, unused);
  load_rows(nr, b, nxb, nyb, nzb, unused);
  load_rows(nr, l, nxl, nyl, nzl, unused);
  load_rows(nr, r, nxr, nyr, nzr, unused);
  // Lengths in units of 1/unit, as in the scalar form.
  const __m256 unit = _mm256_set1_ps(c.unit);
  const __m256 dx = (xa - xb) * unit, dy = (ya - yb) * unit, dz = (za - zb) * unit;
  t.lt = _mm256_sqrt_ps(dx * dx + dy * dy + dz * dz), t.rest = t.l0 * unit;
  t.nij = nxa * nxb + nya * nyb + nza * nzb;
  const __m256 dot_rl = nxr * nxl + nyr * nyl + nzr * nzl;
  t.nrl = _mm256_blendv_ps(_mm256_set1_ps(1.0f), dot_rl, _mm256_castsi256_ps(two_wings));
  t.flags = _mm256_and_si256(_mm256_castps_si256(fflags), _mm256_set1_epi32(0xff));  // the rest is padding
  t.record = _mm256_castps_si256(frecord);
  return t;
}

/// P_step of eight edges: the pow form lane by lane through stepped() (pow has no lanes form
/// with std::pow's bits).
template <bool exact_step>
inline __m256 step_probability(__m256 P, const AdaptConstants& c) {
  if (exact_step) return _mm256_set1_ps(c.budget) * P;
  alignas(32) float p[8];
  _mm256_store_ps(p, P);
  for (float& x : p) x = stepped(x, c.budget, c.step_exponent);
  return _mm256_load_ps(p);
}

// The test eight edges at a time: every lane the scalar form's operations in its order.
template <bool exact_step>
void adapt_test_body(const AdaptConstants& c, const EdgeRecord* __restrict edges,
                     const std::int32_t* __restrict lid, const Float4* __restrict xm, const Float4* __restrict nr,
                     std::uint8_t* __restrict out, int begin, int end) {
  const std::uint64_t seed_step = seed_and_step(c);
  const __m256 phi = _mm256_set1_ps(c.phi), epsilon = _mm256_set1_ps(c.epsilon);
  const __m256 floor_length = _mm256_set1_ps(c.floor_length), zero = _mm256_setzero_ps();
  const __m256 one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f), quarter = _mm256_set1_ps(0.25f);
  const __m256i breakable = _mm256_set1_epi32(kAlive | kMesh | kBreakable), auxiliary = _mm256_set1_epi32(kAlive);
  const __m256i fracture = _mm256_set1_epi32(c.fracture ? -1 : 0), restoration = _mm256_set1_epi32(c.restoration ? -1 : 0);
  auto mask = [](__m256 m) { return _mm256_castps_si256(m); };
  for (int e0 = begin; e0 < end; e0 += 8) {
    alignas(32) std::int32_t id[8];
    const TestLanes t = load_lanes(c, edges, lid, xm, nr, e0, end, id);
    const __m256 comp = one - t.lt / t.rest;
    const __m256 P = quarter * comp * (one - phi * t.nij) * (one + phi * t.nrl);
    const __m256 Pstep = step_probability<exact_step>(P, c);
    const __m256 u = fracture_draws(seed_step, id);
    const __m256i can = _mm256_and_si256(_mm256_and_si256(fracture, _mm256_cmpeq_epi32(t.flags, breakable)),
                                         mask(_mm256_and_ps(_mm256_cmp_ps(t.l0, floor_length, _CMP_GE_OQ),
                                                            _mm256_cmp_ps(t.lt, t.rest, _CMP_LT_OQ))));
    const __m256i breaks = _mm256_and_si256(
        can, mask(_mm256_and_ps(_mm256_cmp_ps(Pstep, zero, _CMP_GT_OQ), _mm256_cmp_ps(u, Pstep, _CMP_LT_OQ))));
    const __m256i bent = mask(_mm256_cmp_ps((one - t.nrl) * half, epsilon, _CMP_GE_OQ));
    const __m256i has_record = _mm256_cmpgt_epi32(t.record, _mm256_set1_epi32(-1));
    const __m256i restores = _mm256_and_si256(_mm256_and_si256(restoration, _mm256_cmpeq_epi32(t.flags, auxiliary)),
                                              _mm256_and_si256(has_record, bent));
    const __m256i decision = _mm256_or_si256(_mm256_and_si256(breaks, _mm256_set1_epi32(1)),
                                             _mm256_andnot_si256(breaks, _mm256_and_si256(restores, _mm256_set1_epi32(2))));
    store_decisions(decision, out + e0, std::min(8, end - e0));
  }
}
#else
// The scalar kernels prefetch the rows of the edge a fixed distance ahead: an edge is tens of
// instructions (the hash, a square root and a division), so the core's reorder window spans
// only a few edges and few of their misses overlap.
constexpr int kTestAhead = 32;  ///< six row loads an edge

// The test one edge at a time (a target without AVX2, or the no-SIMD build). No such target has
// vector gathers, so unlike the triangle pass it needs no attribute to keep the vectorizer off.
template <bool exact_step>
void adapt_test_body(const AdaptConstants& c, const EdgeRecord* __restrict edges,
                     const std::int32_t* __restrict lid, const Float4* __restrict xm, const Float4* __restrict nr,
                     std::uint8_t* __restrict out, int begin, int end) {
  const std::uint64_t seed_step = seed_and_step(c);
  const float phi = c.phi, epsilon = c.epsilon, floor_length = c.floor_length, unit = c.unit;
  const bool fracture = c.fracture, restoration = c.restoration;
  // A missing wing (-1) reads vertex 0's row instead, masked below: no branch on the wings.
  auto wing = [](int w) { return w & ~(w >> 31); };
  for (int e = begin; e < end; ++e) {
    if (e + kTestAhead < end) {
      const EdgeRecord& next = edges[e + kTestAhead];
      for (int v : {next.a, next.b}) __builtin_prefetch(&xm[v]), __builtin_prefetch(&nr[v]);
      __builtin_prefetch(&nr[wing(next.wl)]), __builtin_prefetch(&nr[wing(next.wr)]);
    }
    const EdgeRecord& edge = edges[e];
    const int a = edge.a, b = edge.b;
    const int l = wing(edge.wl), r = wing(edge.wr);
    const bool two_wings = (edge.wl >= 0) & (edge.wr >= 0);
    // Lengths in units of 1/unit (a power of two: the same bits of comp), so that a tiny mesh's
    // squared lengths stay normal floats (issue 14 defect 2: at 1e-25 they were 0, c = 1, and
    // every compressed edge broke at once).
    const Float4 pa = xm[a], pb = xm[b], na = nr[a], nb = nr[b], nl = nr[l], nrr = nr[r];
    const float dx = (pa.x - pb.x) * unit, dy = (pa.y - pb.y) * unit, dz = (pa.z - pb.z) * unit;
    const float lt = std::sqrt(dx * dx + dy * dy + dz * dz), rest = edge.l0 * unit;
    const float comp = 1.0f - lt / rest;
    const float nij = na.x * nb.x + na.y * nb.y + na.z * nb.z;
    const float dot_rl = nrr.x * nl.x + nrr.y * nl.y + nrr.z * nl.z;  // l, r are 0 without wings
    const float nrl = two_wings ? dot_rl : 1.0f;
    const float P = 0.25f * comp * (1 - phi * nij) * (1 + phi * nrl);
    const float Pstep = exact_step ? c.budget * P : stepped(P, c.budget, c.step_exponent);
    const std::uint64_t h = mix64(seed_step ^ (std::uint64_t(std::uint32_t(lid[e])) << 2 | std::uint64_t(Draw::Fracture)));
    const float u = float(h >> 40) * (1.0f / 16777216.0f);  // 24 bits: exact in float
    const bool can = fracture & (edge.flags == (kAlive | kMesh | kBreakable)) & (edge.l0 >= floor_length) & (lt < rest);
    const bool breaks = can & (Pstep > 0) & (u < Pstep);
    const bool restores = restoration & (edge.flags == kAlive) & (edge.record >= 0) & ((1.0f - nrl) * 0.5f >= epsilon);
    out[e] = std::uint8_t(breaks) | std::uint8_t(std::uint8_t(restores & !breaks) << 1);  // 1, 2 or 0
  }
}
#endif
}  // namespace

void adapt_test(const Topology& m, const AdaptConstants& c, std::uint8_t* out, int begin, int end) {
  const Vertices& V = m.V;
  const Edges& E = m.E;
  auto run = [&](auto body) { body(c, E.slots.data(), E.lid.data(), V.xm.data(), V.nr.data(), out, begin, end); };
  if (c.step_exponent == 1.0f) run(adapt_test_body<true>);
  else run(adapt_test_body<false>);
}

}  // namespace crumple::fast
