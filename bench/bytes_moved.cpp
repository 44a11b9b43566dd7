#include "bytes_moved.h"

#include <cmath>

#include "fast/fast_sim.h"

namespace crumple::bench {

namespace {
// Element sizes of the layout (topology.h). The asserts make a layout change fail here, where
// the formulas below must then be revisited, rather than silently miscount.
constexpr double kF = 4, kI = 4, kU8 = 1;   // float, int32 id, flag byte
constexpr double kF4 = 16, kOut = 32;       // Float4 (vertex rows, g, area), EdgeOut record
constexpr double kEdge = 36, kHead = 8;     // EdgeRecord (the edge's topology and l0), ListHead
constexpr double kFace = 24;                // a triangle slot's corners and sides
static_assert(sizeof(fast::Float4) == kF4 && sizeof(fast::EdgeOut) == kOut && sizeof(fast::EdgeRecord) == kEdge &&
              sizeof(fast::ListHead) == kHead && sizeof(fast::Face) == kFace);
constexpr double kLine = 64;

/// One vertex's list: its head (block start, count, room) and its share of the pool.
double list_row(double room) { return kHead + kI * room; }
double block_lines(double room) { return std::ceil(kI * room / kLine); }

// triangle_areas: per triangle slot its record (corners and sides: read whole) and alive in, its
// area vector out; the
// corners' position rows once per vertex.
// vertex_normals: per vertex its triangle list, the normal row out; each area once.
double normals(const LayoutSizes& s) {
  const double areas = s.triangles * (kFace + kU8 + kF4) + s.vertices * kF4;
  const double sums = s.vertices * (list_row(s.room_t) + kF4) + s.triangles * kF4;
  return areas + sums;
}

// Per edge slot its record in (a, b, wl, wr, l0, flags read; the record is read whole) and the
// 32-byte EdgeOut out; per vertex (endpoints and wings, each once) its position and normal rows
// (and its velocity row where springs are damped, which no benchmark's configuration does).
double edge_forces(const LayoutSizes& s) { return s.edges * (kEdge + kOut) + s.vertices * 2 * kF4; }

// Per vertex its spring, neighbour and wing lists (the neighbours' block shares the springs'
// head), its velocity and normal rows
// in, f, ksum and g out; every EdgeOut record once, every neighbour's velocity row once (the
// vertex's own among them).
double gather(const LayoutSizes& s) {
  const double lists = list_row(s.room_e) + kI * s.room_e + list_row(s.room_t);
  const double per_vertex = lists + kF4 + kF4 + 4 * kF + kF4;
  return s.vertices * per_vertex + s.edges * kOut;
}

// Per sweep and vertex: its neighbour list, ksum, f and its velocity row in, each
// neighbour's guess g once (the vertex's own g among them), g_next out. Then momentum_drift with
// the total mass (velocity row, g, f in) and advance (position row and g in; both rows out).
double integrate(const LayoutSizes& s, int sweeps) {
  const double sweep = s.vertices * (list_row(s.room_e) + kF + kF4 + 3 * kF + kF4 + kF4);
  const double drift = s.vertices * (kF4 + kF4 + 3 * kF);
  const double advance = s.vertices * (kF4 + kF4 + 2 * kF4);
  return sweeps * sweep + drift + advance;
}

// The normals on the new positions, then per edge slot its record and lid in and one decision
// byte out; per vertex its position and normal rows once.
double adapt_test(const LayoutSizes& s) {
  return normals(s) + s.edges * (kEdge + kI + kU8) + s.vertices * 2 * kF4;
}

// Lines of one element's row, each array's entry on its own line (random access in SoA): a
// vertex's four rows (position, velocity, normal, rest position), lid, phys, its two list heads
// and its four adjacency blocks; an edge's record (at most two lines: 36
// bytes straddle a line boundary for half the slots), lid and phys; a triangle's record (24
// bytes, at most two lines), alive, area, lid and phys. The
// step's scratch (step_scratch.h) is no part of a row: no event reads or writes it.
double vertex_lines(const LayoutSizes& s) { return 4 + 2 + 2 + 2 * block_lines(s.room_e) + 2 * block_lines(s.room_t); }
constexpr double kEdgeLines = 2 + 2, kTriangleLines = 2 + 4;
constexpr double kRecordLines = double((sizeof(fast::SplitRecord) + 63) / 64);

// One split or restore touches the five vertices n, i, j, l, r, the five edges e, e_in, e_nj,
// e_ln, e_nr, the four triangles of the split record, and the record: every line of their rows.
// (An estimate of the lines an event brings in, not a floor: an edit reads only part of a row.)
double event(const LayoutSizes& s) {
  return kLine * (5 * vertex_lines(s) + 5 * kEdgeLines + 4 * kTriangleLines + kRecordLines);
}

// adapt_test, then the two scans of one byte per edge that collect the events in id order
// (decisions, then the per-id copy), then the events themselves.
double topology_apply(const LayoutSizes& s, double events) {
  return adapt_test(s) + s.edges * 2 * kU8 + events * event(s);
}

// A relayout's phases (layout.h) read every array of every element and write it permuted (the
// pools repacked), not the step's scratch, which the next step rewrites (no EdgeOut, no areas),
// and rename the entries that name a moved kind in place: the edge records in the vertex and
// triangle phases, the faces in the vertex and edge phases, the four pools (the neighbours in
// the vertex phase, the triangles in the triangle phase, the springs and wings in the edge
// phase). Split records and the edge order's read of the lists are left out.
double layout(const LayoutSizes& s) {
  const double pools = 2 * kI * (s.room_e + s.room_t);  // a vertex's share of the four pools
  const double vertex = 4 * kF4 + 2 * kI + 2 * kHead + pools /* repacked */ + pools /* renamed */;
  const double edge = 3 * kEdge + 2 * kI;
  const double triangle = 3 * kFace + kU8 + 2 * kI;
  return 2 * (s.vertices * vertex + s.edges * edge + s.triangles * triangle);
}
}  // namespace

LayoutSizes layout_sizes(const fast::Topology& m) {
  LayoutSizes s;
  s.vertices = m.V.size();
  s.edges = m.E.size();
  s.triangles = m.T.size();
  if (s.vertices > 0) {
    s.room_e = double(m.V.springs.size()) / s.vertices;
    s.room_t = double(m.V.tris.size()) / s.vertices;
  }
  return s;
}

std::optional<LayoutSizes> layout_sizes(const Simulator& sim) {
  const auto* fast = dynamic_cast<const fast::FastSimulator*>(&sim);
  if (!fast) return std::nullopt;
  return layout_sizes(fast->topology());
}

double pass_bytes(const std::string& pass, const LayoutSizes& s, int sweeps, double events) {
  if (pass == "normals") return normals(s);
  if (pass == "edge_forces") return edge_forces(s);
  if (pass == "gather") return gather(s);
  if (pass == "integrate") return integrate(s, sweeps);
  if (pass == "adapt_test") return adapt_test(s);
  if (pass == "topology_apply") return topology_apply(s, events);
  if (pass == "layout") return layout(s);
  return 0;
}

double frozen_step_bytes(const LayoutSizes& s, int sweeps) {
  return normals(s) + edge_forces(s) + gather(s) + integrate(s, sweeps);
}

}  // namespace crumple::bench
