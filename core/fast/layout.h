// Spatial layout of the fast backend's slots, for cache locality.
//
// Every force pass gathers neighbour data at random: a vertex reads its springs' and triangles'
// outputs, an edge reads its endpoints and wings. On the input mesh neighbours sit in nearby
// slots; refinement appends each new vertex, edge and triangle at the end of the arrays (or in
// a recycled slot), so after a few hundred frames of crumpling most neighbour reads miss every
// cache, and the force and integration passes slow down to what they cost on a grid whose
// vertex order was shuffled at random (docs/PERFORMANCE.md).
//
// relayout() reorders every slot, keeping every logical id (topology.h), every adjacency list's
// order and every value, so a step after it computes bit for bit what it would have without it,
// except for the sums over all vertices whose block order follows the slots (the momentum
// correction of DECISIONS.md D2), and totals() adds the squared strains in slot order too
// (rms_strain, D12). Vertices go along a Morton (Z-order) curve of their rest
// positions (over the axes the sheet spans): the sheet's material coordinates, where neighbours
// are near each other however the sheet is crumpled, and where an inserted vertex lies between
// its parents [Eq 7]. Edges then follow their lower endpoint (read from the spring lists) and
// triangles their lowest corner (a counting sort), dead elements last. The cost is a few passes
// over the state, so it runs only when enough elements were created since the last one
// (FastSimulator's layout fraction).
//
// It runs in five phases, each leaving a valid topology, so that a simulator can run them in
// consecutive steps and no step carries the whole cost: a real-time loop must fit its longest
// frame. Phase one moves the vertices (their lists stay where they are, renamed); phase two
// repacks the adjacency pools in the new vertex order; phase three sorts the triangles by the
// vertex slots they find; phase four orders the edges by their lower endpoints, and phase five
// moves them so, with the edges created in between last. Each move is a complete permutation of
// one kind of element that renames every reference to it. Until their phase the lists, triangles
// and edges keep their old order, which costs the passes of a step or a few some locality, not
// correctness (every pass computes a dead slot as a live one, so a dead slot may sit anywhere).
#pragma once

#include "fast/parallel.h"
#include "fast/topology.h"

namespace crumple::fast {

/// The memory relayout reuses from one call to the next (index maps, sort keys, and the spare
/// buffers that each permuted array is gathered into and swapped with), so that a warm relayout
/// allocates nothing and takes page faults only where the state has grown past what earlier
/// relayouts used. All of it is in Arrays, so that the large ones are on huge pages (aligned.h):
/// a first touch of memory costs less per byte there. Arrays of one element type and one length
/// share a spare; arrays of one type but different lengths (the three kinds' ids, the two
/// adjacency pools) each have their own, since a spare that comes back from a shorter array
/// must be grown, and value-initialized, before a longer one can be gathered into it.
///
/// A copy (a clone of the simulator) keeps the original's room with its first part faulted in
/// (Array's copy), so that the clone's relayouts fault about where the original's would.
struct LayoutScratch {
  /// Room for a state of up to nv vertex, ne edge and nt triangle slots on `threads` threads,
  /// so that the scratch grows without reallocating (the spares take their arrays' room at the
  /// first relayout).
  void reserve(std::size_t nv, std::size_t ne, std::size_t nt, int threads);

  /// Faults in, ahead of the next relayout, the memory it will write: each spare as far as its
  /// array will reach when they swap (the array's elements and the room it keeps warm ahead,
  /// Array::keep_warm), each order's scratch as far as its kind's slots then. A first touch of
  /// memory can cost far more than streaming the same bytes (on a VM whose host backs the
  /// guest's memory lazily: docs/PERFORMANCE.md), and the spares and the orders' scratch are
  /// used only by relayouts, which would otherwise fault in all the growth since the last one in
  /// one step. Touches `budget` bytes or a little more (a claim on huge pages runs on to its
  /// huge page's end: Array::huge_page_end), on all of par's threads, and returns how many it
  /// touched. Only between relayouts: it may drop the scratch's contents.
  std::size_t warm(const Topology& m, const Parallel& par, std::size_t budget);
  /// warm()'s bookkeeping without the touch: appends the ranges to `cold` (counted as faulted
  /// in from now on; the caller touches them, with other arrays' in one loop:
  /// FastSimulator::warm_ahead) and returns their bytes.
  std::size_t claim_cold(const Topology& m, int threads, std::size_t budget, std::vector<ColdRange>& cold);
  /// The bytes short of the targets that warm() touches towards.
  std::size_t cold_bytes(const Topology& m, int threads) const;
  /// Gives every array all of its room (each spare its array's capacity, each order's scratch
  /// what reserve() gave it) and adds the ranges to `claims`, for FastSimulator::make_resident
  /// to touch with the state's in one loop. Keeps the contents: callable within a relayout.
  void claim_whole(const Topology& m, int threads, ColdClaims& claims);
  /// Whether all the room claim_whole() claims is faulted in.
  bool resident(const Topology& m, int threads) const;

  Array<int> vorder, vnew, eorder, enew, torder, tnew, key, idx, count;
  Array<std::uint64_t> code, code2;
  Array<ListHead> spare_heads;  ///< the vertices' list heads
  Array<Float4> spare_rows;     ///< the vertices' rows
  Array<std::int32_t> spare_vid, spare_eid, spare_tid;  ///< each kind's logical ids
  Array<std::int32_t> spare_springs, spare_nbrs, spare_tris, spare_wings;  ///< the pools
  Array<EdgeRecord> spare_edges;
  Array<Face> spare_faces;
  Array<std::uint8_t> spare_alive;  ///< the triangles' alive bytes
};

/// The phases of a relayout (above): vertices, lists, triangles, edge order, edges.
inline constexpr int kLayoutPhases = 5;

/// A step between relayouts faults in this part (1 / kWarmParts) of the memory the next
/// relayout will write that is not faulted in yet, and of the arrays' growth room
/// (LayoutScratch::warm; FastSimulator::warm_ahead).
inline constexpr std::size_t kWarmParts = 4;

/// Runs phase `phase` (0 to kLayoutPhases - 1) of a relayout; phase 0 resets the vertices'
/// `created` counter. Each phase sorts by the slots of the kinds before it as they are.
void relayout_phase(int phase, Topology& m, const Parallel& par, LayoutScratch& scratch);

/// Every phase, one after the other.
void relayout(Topology& m, const Parallel& par, LayoutScratch& scratch);

/// True when the vertices created since the last relayout are at least `fraction` of the slots
/// (fraction 0: always; negative: never).
bool layout_stale(const Topology& m, double fraction);

}  // namespace crumple::fast
