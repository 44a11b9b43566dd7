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
// correction of DECISIONS.md D2). Vertices go along a Morton (Z-order) curve of their rest
// positions: the sheet's material coordinates, where neighbours are near each other however the
// sheet is crumpled, and where an inserted vertex lies between its parents [Eq 7]. Edges then
// follow their lower endpoint and triangles their lowest corner (counting sorts), dead elements
// last. The cost is a few passes over the state, so it runs only when enough elements were
// created since the last one (FastSimulator's layout fraction).
#pragma once

#include "fast/parallel.h"
#include "fast/topology.h"

namespace crumple::fast {

/// The memory relayout reuses from one call to the next (index maps, sort keys, one spare
/// buffer per element type that each permuted array is gathered into and swapped with, and a
/// second one for the adjacency pools, which are repacked in pairs), so that a relayout
/// allocates nothing, and takes no page fault, once warm.
struct LayoutScratch {
  LayoutScratch() = default;
  /// A copy (a clone of the simulator) gets spare buffers of the same room, already touched,
  /// so that its first relayout takes no page faults either.
  LayoutScratch(const LayoutScratch& o);
  LayoutScratch& operator=(const LayoutScratch& o);

  std::vector<int> vorder, vnew, eorder, enew, torder, tnew, key, idx, count;
  std::vector<std::int32_t> at_old;  ///< each vertex's old block start, by new slot (repacking)
  std::vector<std::uint64_t> code, code2;
  Array<ListHead> spare_heads;
  Array<std::int32_t> spare_i, spare_i2;
  Array<std::uint8_t> spare_u8;
  Array<Float4> spare_f4;
  Array<EdgeRecord> spare_edges;
  Array<Face> spare_faces;
};

/// Reorders the slots of m as described above and resets the vertices' `created` counter.
void relayout(Topology& m, const Parallel& par, LayoutScratch& scratch);

/// True when the vertices created since the last relayout are at least `fraction` of the slots
/// (fraction 0: always; negative: never).
bool layout_stale(const Topology& m, double fraction);

}  // namespace crumple::fast
