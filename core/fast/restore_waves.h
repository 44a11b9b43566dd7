// The restores of one topology pass, in parallel waves with the serial result
// (docs/DECISIONS.md D14). A restore reads and writes only its own vertices {n, i, j, l, r} with
// their lists, edges and triangles. Each candidate is tested once, in parallel, on the state
// after the pass's splits, and that answer holds through the pass: no restore of the pass makes
// a restorable candidate unrestorable or the other way round (D14 proves it; the serial
// oracle, which tests each candidate at its turn, checks it in the tests). So exactly the
// restorable candidates are applied, and the waves only keep their event order where they share
// a vertex: a wave scans the pending restorable candidates in event order; one sharing a vertex
// with an earlier one of the scan waits for the next wave (and claims its vertices, so that
// later ones at them wait too); the others, vertex-disjoint, apply in parallel. Every vertex
// sees its restores in event order, and the freed ids reach the free lists in event order after
// the waves: the serial result, bit for bit.
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
  void claim_whole(ColdClaims& claims) { claims.whole(claim_); }
  /// Applies the restore events (edge slots, in event order) to sim's mesh, after the pass's
  /// splits, marking the triangles each accepted restore changes in `stamps`. Returns the
  /// restores applied. Their ids stay taken until free_ids().
  int apply(FastSimulator& sim, const std::vector<int>& restores, TriangleStamps& stamps);
  /// Puts what the last apply() freed on m's free lists, in event order (Topology::free_ids).
  void free_ids(Topology& m) const;
  /// Appends the live vertices (i, j, l, r) of each restore the last apply() applied.
  void touched(std::vector<int>& out) const;
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
    int wave;                  ///< the wave that applied it (set when applied)
  };
  /// Every candidate's vertices and answer, on the state after the pass's splits.
  void pretest(FastSimulator& sim, const std::vector<int>& restores, const TriangleStamps& stamps);
  /// One wave's serial scan of pending_ (restorable candidates): fills wave_ and next_, claims
  /// and stamps.
  void scan(const std::vector<int>& restores, const Topology& m, TriangleStamps& stamps, int wave);

  Array<int> claim_;  ///< per vertex slot: 1 + the candidate claiming it in a wave (0 between waves)
  // Per pass, kept so that a pass allocates (and faults in) no memory.
  std::vector<Candidate> candidates_;                 ///< per restore event
  std::vector<int> pending_, next_, wave_, claimed_;  ///< candidates by wave; vertices claimed
  std::vector<std::pair<int, Freed>> freed_;          ///< per accepted restore: what it freed
  std::uint64_t large_waves_ = 0;
};

}  // namespace crumple::fast
