// The test oracle of the topology pass: its events one after the other, in event order, each
// skipped when an earlier accepted event of the pass changed one of its triangles (MODEL.md §4).
// This is the definition that SplitRounds and RestoreWaves reproduce bit for bit in parallel;
// FastSimulator::set_serial_edits swaps it in for them (tests compare the two).
#pragma once

#include <vector>

#include "fast/pass_events.h"

namespace crumple::fast {

class FastSimulator;

struct SerialEvents {
  /// Splits (edge slots, in event order) one after the other, appending each applied split's
  /// live vertices (i, j, l, r, n) to `touched`; returns the splits applied.
  static int splits(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps, std::vector<int>& touched);
  /// Restores (edge slots, in event order) one after the other, appending each applied
  /// restore's live vertices (i, j, l, r) to `touched`; returns the restores applied.
  static int restores(FastSimulator& sim, const std::vector<int>& restores, PassStamps& stamps,
                      std::vector<int>& touched);
};

}  // namespace crumple::fast
