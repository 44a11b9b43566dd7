// Stable counting passes for the fast backend's least-significant-digit radix sorts (the
// relayout's Morton order, the step's event order): the same ranks on any thread count.
#pragma once

#include <algorithm>
#include <utility>
#include <vector>

#include "fast/aligned.h"
#include "fast/parallel.h"

namespace crumple::fast {

/// Most bits a radix pass sorts: its histograms (4096 counts a block) stay in L1.
constexpr int kMaxDigit = 12;
/// Fewest items a counting pass gives a block of its own: counting an item is a load and an
/// increment, and every block adds a histogram of up to 4096 counts to the serial sum and a
/// parallel loop's start to each pass, so smaller blocks do not repay them (a step's event keys,
/// some thousands, sort faster in one block).
constexpr int kRadixBlock = 16384;
/// Most blocks a counting pass cuts its items into: the histograms (blocks x buckets) are summed
/// serially, so their count is bounded whatever the thread count.
constexpr int kMaxRadixBlocks = 8;

/// How an LSD radix sort covers `bits` key bits: as few passes of at most kMaxDigit bits as
/// cover them, each of `bits` digit bits (the last may reach past the key's top bit).
struct RadixDigits {
  int passes = 1;
  int bits = 0;
};
inline RadixDigits radix_digits(int bits) {
  const int passes = std::max(1, (bits + kMaxDigit - 1) / kMaxDigit);
  return {passes, (bits + passes - 1) / passes};
}

/// One stable counting pass over the items 0..n-1 with keys in [0, buckets): place(k, to) is
/// told each item's rank among the items of smaller key, then of equal key and smaller index.
/// The items are cut into one block per thread, each counted into its own histogram, the
/// histograms summed in bucket-major order (serial, buckets x blocks), then each block places
/// its items in index order: the ranks do not depend on the number of blocks, so the result is
/// the serial pass's on any thread count. hist (a vector of int) holds the histograms.
template <class Hist, class Key, class Place>
void stable_pass(const Parallel& par, Hist& hist, int n, int buckets, Key key, Place place) {
  const int wanted = std::clamp(n / kRadixBlock, 1, std::min(par.threads(), kMaxRadixBlocks));
  const int per = std::max(1, (n + wanted - 1) / wanted);  // >= 1: no block of zero items
  const int blocks = Parallel::blocks_of(n, per);          // the blocks run_blocks runs
  resize_scratch(hist, std::size_t(blocks) * buckets);
  std::fill(hist.begin(), hist.end(), 0);
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

}  // namespace crumple::fast
