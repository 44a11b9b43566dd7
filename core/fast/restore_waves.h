// The restores of one topology pass, in parallel waves with the serial result
// (docs/DECISIONS.md D14). A restore reads and writes only its own vertices {n, i, j, l, r} with
// their lists, edges and triangles. Each candidate is tested once, in parallel, on the state
// after the pass's splits, and that answer holds through the pass: no restore of the pass makes
// a restorable candidate unrestorable or the other way round (D14 proves it; the serial
// oracle, which tests each candidate at its turn, checks it in the tests). So exactly the
// restorable candidates are applied, and the waves only keep their event order where they share
// a vertex: one serial scan in event order gives each restorable candidate the wave after the
// last wave of an earlier one sharing a vertex (the split rounds' rule), so the restores of a
// wave are vertex-disjoint and apply in parallel. Every vertex sees its restores in event order,
// and the freed ids reach the free lists in event order after the waves: the serial result, bit
// for bit. (The restores' triangles are not stamped: the answers are known, and no later event
// of the pass reads the stamps.)
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "fast/aligned.h"
#include "fast/pass_events.h"
#include "fast/topology.h"

namespace crumple::fast {

class FastSimulator;

class RestoreWaves {
 public:
  /// Room for the per-vertex scratch of a mesh of this many vertex slots.
  void reserve(std::size_t vertices);
  /// Claims the whole room for the caller to touch (FastSimulator::make_resident).
  void claim_whole(ColdClaims& claims) { claims.whole(wave_last_); }
  /// Applies the restore events (edge slots in event order, with their split records) to sim's
  /// mesh, after the pass's splits, whose changed triangles `stamps` holds, and renews the
  /// normals of the vertices whose triangles changed. Returns the restores applied. Their ids
  /// stay taken until free_ids().
  int apply(FastSimulator& sim, const std::vector<int>& restores, const std::vector<int>& records,
            const PassStamps& stamps);
  /// Puts what the last apply() freed on m's free lists, in event order (Topology::free_ids).
  void free_ids(Topology& m) const;
  /// Appends the edge slot of each restore the last apply() applied (`restores` is what it
  /// was given), in event order.
  void applied_edges(const std::vector<int>& restores, std::vector<int>& out) const;
  /// Waves so far large enough to run as a parallel loop (tests check they happened).
  std::uint64_t large_waves() const { return large_waves_; }
  /// One restore the last apply() applied: its place in the pass's restore events, its wave
  /// (0 first) and its record's vertices n, i, j, l, r (-1: none), for tests of the waves.
  struct Applied {
    int event, wave;
    std::array<int, 5> verts;
  };
  std::vector<Applied> applied() const;

 private:
  struct Candidate {
    std::array<int, 5> verts;  ///< n, i, j, l, r of its split record (-1: none)
    bool restorable;           ///< on the state after the pass's splits, and so through the pass
    int wave;                  ///< its wave, 0 first (restorable candidates)
    int record;                ///< its split record (for the waves' prefetch: no read of the edge)
  };
  /// Every candidate's vertices and answer, on the state after the pass's splits.
  void pretest(FastSimulator& sim, const std::vector<int>& records, const PassStamps& stamps);
  /// Each restorable candidate's wave, serially in event order (the class comment); fills
  /// restorable_ and by_wave_. Returns the number of waves.
  int assign_waves();
  static void renew_normals(FastSimulator& sim, const std::array<int, 5>& verts);

  Array<int> wave_last_;  ///< per vertex slot: 1 + the last wave assigned at it (0 between passes)
  // Per pass, kept so that a pass allocates (and faults in) no memory.
  std::vector<Candidate> candidates_;  ///< per restore event
  std::vector<int> restorable_;        ///< the restorable candidates, in event order
  std::vector<int> by_wave_, start_;   ///< places in restorable_ by wave; each wave's first
  std::vector<int> claimed_;           ///< the vertices of the pass's restores
  std::vector<std::pair<int, Freed>> freed_;  ///< per restorable candidate (event order): what it freed
  std::uint64_t large_waves_ = 0;
};

}  // namespace crumple::fast
