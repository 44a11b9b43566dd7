// The restores of one topology pass, in parallel waves with the serial result
// (docs/DECISIONS.md D14). A restore reads and writes only its own vertices {n, i, j, l, r} with
// their lists, edges and triangles, so a candidate's answer can change only through an earlier
// candidate sharing one of its vertices. A wave scans the pending candidates in event order: one
// sharing a vertex with an earlier candidate of the scan that is accepted or waiting waits for
// the next wave (and claims its vertices, so that later candidates at them wait too); the others
// are decided on the current state and the accepted ones, vertex-disjoint, apply in parallel.
// Every vertex sees its restores in event order, and the freed ids reach the free lists in event
// order after the waves: the serial result, bit for bit. Each wave's answers are tested in
// parallel before its scan, so the serial scan reads only a compact array and the claims: a
// scan changes no state and marks only the triangles of the candidates it accepts, whose corners
// it claims, so a candidate that does not wait gets the answer the scan would have computed.
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
  /// Applies the restore events (edge slots, in event order) to sim's mesh, after the pass's
  /// splits, marking the triangles each accepted restore changes in `stamps`. Returns the
  /// restores applied.
  int apply(FastSimulator& sim, const std::vector<int>& restores, TriangleStamps& stamps);
  /// Appends the live vertices (i, j, l, r) of each restore the last apply() applied.
  void touched(std::vector<int>& out) const;
  /// Waves so far large enough to run as a parallel loop (tests check they happened).
  std::uint64_t large_waves() const { return large_waves_; }

 private:
  /// A candidate's answer on the current state: never (in this pass) once an accepted event of
  /// the pass changed a triangle of its record, else whether it can restore now.
  enum Answer : std::uint8_t { kNever, kNotNow, kRestorable };
  struct Candidate {
    std::array<int, 5> verts;  ///< n, i, j, l, r of its split record (-1: none)
    Answer answer;             ///< as of the start of the candidate's current wave
  };
  static Answer test(const FastSimulator& sim, int edge, const TriangleStamps& stamps);
  /// Every candidate's vertices and first answer, on the state after the pass's splits.
  void pretest(FastSimulator& sim, const std::vector<int>& restores, const TriangleStamps& stamps);
  /// The answers of the candidates pending for a later wave, on the state after the last wave.
  void retest(FastSimulator& sim, const std::vector<int>& restores, const TriangleStamps& stamps);
  /// One wave's serial scan of pending_: fills wave_ and next_, claims and stamps.
  void scan(const std::vector<int>& restores, const Topology& m, TriangleStamps& stamps);

  Array<int> claim_;  ///< per vertex slot: 1 + the candidate claiming it in a wave (0 between waves)
  // Per pass, kept so that a pass allocates (and faults in) no memory.
  std::vector<Candidate> candidates_;                 ///< per restore event
  std::vector<int> pending_, next_, wave_, claimed_;  ///< candidates by wave; vertices claimed
  std::vector<std::pair<int, Freed>> freed_;          ///< per accepted restore: what it freed
  std::uint64_t large_waves_ = 0;
};

}  // namespace crumple::fast
