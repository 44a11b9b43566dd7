// The counter-based random stream (MODEL.md §4): a pure function of (seed, step, edge, purpose),
// so every backend, thread count and evaluation order draws the same numbers.
#pragma once

#include <cstdint>

namespace crumple {

/// What a random number is drawn for; one independent stream each.
enum class Draw : std::uint32_t {
  Fracture = 0,   ///< u < P_step breaks the edge                 [Eq 6]
  FlatSign = 1,   ///< sign of the new vertex's offset on a flat edge [Eq 7]
};

/// SplitMix64's finalizer: a bijective 64-bit mix with full avalanche.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// Uniform number in [0, 1) with 24 significant bits, so that it is exactly representable in
/// float and double and every backend compares the same value.
constexpr double uniform(std::uint64_t seed, std::uint64_t step, std::uint32_t edge, Draw d) {
  std::uint64_t h = mix64(seed ^ 0x9e3779b97f4a7c15ULL);
  h = mix64(h ^ step);
  h = mix64(h ^ ((std::uint64_t(edge) << 2) | std::uint64_t(d)));
  return double(h >> 40) * (1.0 / 16777216.0);
}

}  // namespace crumple
