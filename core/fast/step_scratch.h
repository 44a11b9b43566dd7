// The physics step's per-slot scratch, apart from the mesh (topology.h): what one step's passes
// write for the next pass of the same step and nothing after it reads. Every pass that reads an
// array runs after the pass that rebuilt it in the same step, so topology edits and relayout
// neither keep nor permute any of it; it only follows the slot counts (fit).
#pragma once

#include <cstddef>

#include "fast/aligned.h"
#include "fast/topology.h"

namespace crumple::fast {

/// What the edge pass leaves for the vertex gather: what the gather cannot compute from the two
/// endpoints' vertex rows (their velocities and masses give the implicit block W_e and
/// W_e (v_b - v_a), so those are not stored). 32 bytes, two records to a cache line: the edge pass writes them in
/// order with whole 16-byte stores, the gather reads them at random.
struct alignas(32) EdgeOut {
  float fx = 0, fy = 0, fz = 0;  ///< spring force on a (b gets the opposite)
  float kb = 0;                  ///< bending magnitude s C_beta B [Eq 8-9] (0: none)
  float bx = 0, by = 0, bz = 0;  ///< balanced form: mean of the stencil's four forces
  float pad = 0;                 ///< to 32 bytes
};

/// What the gather sums per vertex slot (gather_forces) and the integrators read.
struct VertexForces {
  Array<float> fx, fy, fz;  ///< total force f_k of this step
  Array<float> ksum;        ///< sum of W_e over the vertex's springs (the implicit row's diagonal)
};

/// The symmetric 3 x 3 sum W = sum_e W_e of a vertex's implicit blocks under the axial Jacobian
/// (axial_blocks), 32 bytes so that a row is one aligned load.
struct alignas(32) Block3 {
  float xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;
  float pad0 = 0, pad1 = 0;
};

struct StepScratch {
  Array<EdgeOut> edge_out;  ///< per edge slot: the edge pass's record for the gather
  VertexForces forces;
  Array<Float4> g;          ///< Jacobi guess of v_k' (MODEL.md §3) in x, y, z and m_k in w:
                            ///< what a sweep gathers from each neighbour, in one load
  Array<Float4> g_next;     ///< the next sweep's guess (double buffer)
  Array<Block3> wsum;       ///< the axial Jacobian's row blocks (sized by fit_blocks only: the
                            ///< isotropic step keeps its diagonal in forces.ksum)

  /// Room for this many slots without reallocating (growth past it is geometric).
  void reserve(std::size_t vertices, std::size_t edges) {
    for (Array<Float4>* a : {&g, &g_next}) a->reserve_warm(vertices);
    for (Array<float>* a : {&forces.fx, &forces.fy, &forces.fz, &forces.ksum}) a->reserve_warm(vertices);
    edge_out.reserve_warm(edges);
  }
  /// Sizes every array to the mesh's slots (values are rebuilt by the passes before any read).
  void fit(const Topology& m) {
    const std::size_t nv = std::size_t(m.V.size()), ne = std::size_t(m.E.size());
    if (g.size() != nv) {
      for (Array<Float4>* a : {&g, &g_next}) a->resize(nv), a->keep_warm();
      for (Array<float>* a : {&forces.fx, &forces.fy, &forces.fz, &forces.ksum}) a->resize(nv), a->keep_warm();
    }
    if (edge_out.size() != ne) edge_out.resize(ne), edge_out.keep_warm();
  }
  /// Calls f(array) for each array (see Topology::for_each_array).
  template <class F>
  void for_each_array(F&& f) {
    f(edge_out), f(forces.fx), f(forces.fy), f(forces.fz), f(forces.ksum), f(g), f(g_next), f(wsum);
  }
  /// fit, and wsum sized to the vertex slots (the axial Jacobian's step).
  void fit_blocks(const Topology& m) {
    fit(m);
    if (wsum.size() != std::size_t(m.V.size())) wsum.resize(std::size_t(m.V.size())), wsum.keep_warm();
  }
};

}  // namespace crumple::fast
