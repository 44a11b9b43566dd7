// The splits of one topology pass, in parallel rounds with the serial result (docs/DECISIONS.md
// D13). Acceptance is decided first, serially in event order: a split is skipped when an
// earlier accepted split of the pass changed one of its edge's two triangles, and those are
// still the triangles it had at the start of the pass (a split changes only its own two, and any
// later split sharing one is skipped). Counting what each accepted split takes then gives each
// its new ids, looked up in parallel. Accepted splits then apply in rounds: a split's round
// is one more than the last round of an earlier split sharing one of its vertices, so the
// splits of a round have disjoint vertex sets (hence disjoint edges, triangles and adjacency
// lists) and run in parallel, while every vertex still receives its edits in event order.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "fast/aligned.h"
#include "fast/pass_events.h"

namespace crumple::fast {

class FastSimulator;

class SplitRounds {
 public:
  /// Room for the per-vertex scratch of a mesh of this many vertex slots.
  void reserve(std::size_t vertices);
  /// Claims the whole room for the caller to touch (FastSimulator::make_resident).
  void claim_whole(ColdClaims& claims) { claims.whole(tally_); }
  /// Applies the split events (edge slots, in event order) to sim's mesh, marking the triangles
  /// each accepted split changes in `stamps`, and renews the normals of the vertices whose
  /// triangles changed (renew_normals). Returns the splits applied.
  int apply(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps);
  /// Appends the edge slot of each split the last apply() applied, in event order.
  void applied_edges(std::vector<int>& out) const;
  /// Rounds so far large enough to run as a parallel loop (tests check they happened).
  std::uint64_t large_rounds() const { return large_rounds_; }
  /// One split the last apply() applied: its place in the pass's split events, its round (1
  /// first) and its vertices i, j, l, r, n (-1: none), for tests of the rounds.
  struct Applied {
    int event, round;
    std::array<int, 5> verts;
  };
  std::vector<Applied> applied() const;

 private:
  int plan(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps);
  int accept(PassStamps& stamps);
  void take_ids(FastSimulator& sim, PassStamps& stamps);
  void make_room(FastSimulator& sim);
  int run_rounds(FastSimulator& sim, int rounds);
  void renew_normals(FastSimulator& sim, const SplitPlan& plan, int round);

  /// What this pass's accepted splits do at one vertex: one record, so that the serial plan
  /// misses one line a vertex, not one per array.
  struct Tally {
    int round_last = 0;   ///< round of the vertex's last split in this pass (0: none)
    int spring_adds = 0;  ///< springs the splits of this pass add at the vertex
    int tri_adds = 0;     ///< triangles the splits of this pass add at the vertex
    int unused = 0;       ///< pads the record to 16 bytes: four a line, none across two
  };
  // Per vertex slot, all zero between passes (reset for the vertices used: the adds by
  // make_room, the rest at the vertex's last split, renew_normals): no pass clears or allocates
  // an array the size of the mesh.
  Array<Tally> tally_;
  // Per pass, kept so that a pass allocates (and faults in) no memory.
  std::vector<SplitCandidate> candidates_;   ///< per split event
  /// An accepted split: its candidate, and where its new edges and triangles fall among the
  /// pass's takes of each kind (its vertex and record are its own index among the accepted).
  struct Accepted {
    int candidate, edge_at, tri_at;
  };
  std::vector<Accepted> accepted_;           ///< in event order
  int edges_taken_ = 0, tris_taken_ = 0;     ///< by all of accepted_
  std::vector<SplitPlan> plans_;             ///< accepted splits, in event order
  std::vector<int> round_of_;                ///< per plan
  std::vector<int> involved_;                ///< vertices of accepted splits (i, j, l, r), once each
  std::vector<int> by_round_, start_;        ///< plans sorted by round, each round's first
  std::uint64_t large_rounds_ = 0;
};

}  // namespace crumple::fast
