// The fast kernels' one wide-float type (the idea of Box2D v3's b2FloatW): a row of N floats
// with element-wise arithmetic, for kernels that sum whole records (an EdgeOut is one row of
// 8, a Float4 one row of 4) instead of one field at a time. The SIMD build maps it onto GCC's
// vector extensions (a row of 8 is one AVX register, a row of 16 one AVX-512 register on this machine; GCC splits it on
// narrower targets); CRUMPLE_DISABLE_SIMD maps it onto a plain array with scalar loops, so the
// same kernel source measures the SIMD gain. Element-wise: lane k of a sum adds in the order
// the kernel adds, so a row sum rounds exactly as the per-field scalar sums it replaces.
#pragma once

#include <cstring>

namespace crumple::fast {

#if CRUMPLE_DISABLE_SIMD
template <int N>
struct Wide {
  float v[N];  ///< the lanes

  static Wide load(const void* p) {
    Wide w;
    std::memcpy(w.v, p, sizeof w.v);
    return w;
  }
  static Wide zero() { return Wide{}; }
  float operator[](int k) const { return v[k]; }
  Wide& operator+=(const Wide& b) {
    for (int k = 0; k < N; ++k) v[k] += b.v[k];
    return *this;
  }
  friend Wide operator-(Wide a, const Wide& b) {
    for (int k = 0; k < N; ++k) a.v[k] -= b.v[k];
    return a;
  }
  friend Wide operator*(Wide a, const Wide& b) {
    for (int k = 0; k < N; ++k) a.v[k] *= b.v[k];
    return a;
  }
  friend Wide operator*(float s, Wide a) {
    for (int k = 0; k < N; ++k) a.v[k] *= s;
    return a;
  }
};
#else
template <int N> struct VectorOf;  // GCC's vector type of N floats (a dependent size is ignored)
template <> struct VectorOf<4> { typedef float type __attribute__((vector_size(16))); };
template <> struct VectorOf<8> { typedef float type __attribute__((vector_size(32))); };
template <> struct VectorOf<16> { typedef float type __attribute__((vector_size(64))); };

template <int N>
struct Wide {
  using Lanes = typename VectorOf<N>::type;
  Lanes v;  ///< the lanes, one vector register where the target has one this wide

  static Wide load(const void* p) {
    Wide w;
    std::memcpy(&w.v, p, sizeof w.v);  // compiles to one unaligned vector load
    return w;
  }
  static Wide zero() { return Wide{Lanes{}}; }
  float operator[](int k) const { return v[k]; }
  Wide& operator+=(const Wide& b) {
    v += b.v;
    return *this;
  }
  friend Wide operator-(Wide a, const Wide& b) { return Wide{a.v - b.v}; }
  friend Wide operator*(Wide a, const Wide& b) { return Wide{a.v * b.v}; }
  friend Wide operator*(float s, Wide a) { return Wide{a.v * s}; }
};
#endif

}  // namespace crumple::fast
