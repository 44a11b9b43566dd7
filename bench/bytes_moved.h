// Bytes each pass of the fast backend must move, counted from its layout (core/fast/topology.h),
// so that a pass's time becomes an achieved bandwidth to set against the machine's measured
// streaming bandwidth (BM_Stream): the roofline of scripts/bench_report.py.
//
// The count is a floor of the traffic given the data layout, not a model of the caches: every
// array a pass reads or writes counts its element size once per element it covers, and data
// read at random through indices (a neighbour's position, an edge's output record) counts once
// per distinct element, as if every reuse hit the cache. Adjacency lists live in per-vertex
// blocks of two pools, packed in vertex order, and a pass that walks a vertex's lists counts its
// block start and the mean block (pool entries per vertex slot x 4 bytes, garbage included),
// since that is the memory the layout makes it touch. Element
// counts are slots (live and dead): every kernel runs over all slots. bytes_moved.cpp gives
// each pass's formula.
#pragma once

#include <optional>
#include <string>

namespace crumple {
class Simulator;
namespace fast {
class Topology;
}
}  // namespace crumple

namespace crumple::bench {

/// What the counts depend on: the topology's slot counts and adjacency pool sizes.
struct LayoutSizes {
  double vertices = 0, edges = 0, triangles = 0;  ///< slots
  double room_e = 8, room_t = 8;                  ///< springs / tris pool entries per vertex slot
};

LayoutSizes layout_sizes(const fast::Topology& m);
/// The sizes of a fast backend's current topology; nullopt for other backends (not counted).
std::optional<LayoutSizes> layout_sizes(const Simulator& sim);

/// Bytes one run of `pass` (a fast::Pass name) moves: `sweeps` Jacobi sweeps in integrate
/// (Params::sweeps, the approximate implicit integrator); `events` splits + restores applied by
/// topology_apply. Unknown pass: 0.
double pass_bytes(const std::string& pass, const LayoutSizes& s, int sweeps, double events);

/// A frozen step (BM_Frozen: fracture and restoration off): normals, edge_forces, gather and
/// integrate, nothing of the adapt or layout passes.
double frozen_step_bytes(const LayoutSizes& s, int sweeps);

}  // namespace crumple::bench
