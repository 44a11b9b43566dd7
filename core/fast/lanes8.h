// Eight edges in the eight lanes of an AVX register: the edge pass reads each edge's vertices as
// 16-byte rows (topology.h's per-step rows) and transposes them into one register per component,
// so that its square roots, divisions and products serve eight edges per instruction without
// the vector gathers that Zen 4 executes slower than the scalar loads they replace
// (docs/PERFORMANCE.md). Every lane runs the same instructions, so an edge's result does not
// depend on which lane or which chunk of the range it fell in: the pass gives the same bits on
// any thread count.
#pragma once

#if defined(__AVX2__) && !CRUMPLE_DISABLE_SIMD
#define CRUMPLE_LANES8 1
#include <immintrin.h>

#include <cstddef>

#include "fast/topology.h"

namespace crumple::fast::lanes8 {

// The fields of an EdgeRecord that the edge kernels read, as two 16-byte rows that load_at
// transposes: (a, b, wl, wr) at the record's start and (tri1, l0, record, flags) ending at its
// last byte (the flags' word holds the record's padding, which a reader masks away).
constexpr std::size_t kStencilRow = 0, kRestRow = offsetof(EdgeRecord, tri1);
static_assert(offsetof(EdgeRecord, a) == kStencilRow && offsetof(EdgeRecord, b) == kStencilRow + 4 &&
              offsetof(EdgeRecord, wl) == kStencilRow + 8 && offsetof(EdgeRecord, wr) == kStencilRow + 12);
static_assert(offsetof(EdgeRecord, l0) == kRestRow + 4 && offsetof(EdgeRecord, flags) == kRestRow + 12 &&
              sizeof(EdgeRecord) == kRestRow + 16);

/// Four registers, each holding row k in its low half and row k + 4 in its high half (k = 0..3)
/// -> one register per component: x, y, z, w of the eight rows.
inline void transpose(__m256 r04, __m256 r15, __m256 r26, __m256 r37, __m256& x, __m256& y, __m256& z, __m256& w) {
  const __m256 t0 = _mm256_unpacklo_ps(r04, r15), t1 = _mm256_unpackhi_ps(r04, r15);
  const __m256 t2 = _mm256_unpacklo_ps(r26, r37), t3 = _mm256_unpackhi_ps(r26, r37);
  x = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  y = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  z = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  w = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/// The 16 bytes at byte `offset` of *at[0..7] (any alignment) -> their four 4-byte fields as one
/// register each.
template <class Row>
inline void load_at(const Row* const at[8], std::size_t offset, __m256& x, __m256& y, __m256& z, __m256& w) {
  auto row = [&](int k) { return reinterpret_cast<const float*>(reinterpret_cast<const char*>(at[k]) + offset); };
  auto pair = [&](int lo, int hi) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(row(lo))), _mm_loadu_ps(row(hi)), 1);
  };
  transpose(pair(0, 4), pair(1, 5), pair(2, 6), pair(3, 7), x, y, z, w);
}

/// Rows rows[id[0..7]] -> one register per component: x, y, z, w of the eight rows.
inline void load_rows(const Float4* rows, const int id[8], __m256& x, __m256& y, __m256& z, __m256& w) {
  const Float4* const at[8] = {&rows[id[0]], &rows[id[1]], &rows[id[2]], &rows[id[3]],
                               &rows[id[4]], &rows[id[5]], &rows[id[6]], &rows[id[7]]};
  load_at(at, 0, x, y, z, w);
}

/// The inverse: lane k of (a, b, c, d) -> the four floats at dst[k] (16-byte aligned).
inline void store_rows(float* const dst[8], __m256 a, __m256 b, __m256 c, __m256 d) {
  __m256 r[4];  // r[k] holds lanes k and k + 4: the transposition is its own inverse
  transpose(a, b, c, d, r[0], r[1], r[2], r[3]);
  for (int k = 0; k < 4; ++k) {
    _mm_store_ps(dst[k], _mm256_castps256_ps128(r[k]));
    _mm_store_ps(dst[k + 4], _mm256_extractf128_ps(r[k], 1));
  }
}

/// 1 where a > 0, -1 where a < 0, else 0 (NaN: 0), as the scalar pass's sign.
inline __m256 sign(__m256 a) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  return _mm256_and_ps(_mm256_cmp_ps(a, zero, _CMP_GT_OQ), one) - _mm256_and_ps(_mm256_cmp_ps(a, zero, _CMP_LT_OQ), one);
}

}  // namespace crumple::fast::lanes8
#endif
