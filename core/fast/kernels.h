// The fast backend's kernels. Each one computes a range [begin, end) of one pass and writes
// only the outputs of its own elements. What it reads comes as const; what it writes is in the
// arguments that are not (an output array, or the part of the step scratch it fills:
// step_scratch.h). So the same body runs in a plain loop, inside tbb::parallel_for, and in a
// test; no kernel scatters, so there is nothing to race on and every sum has one order on any
// thread count (sums over a vertex's adjacency list in list order). The loops are written for
// the auto-vectorizer (SoA arrays, no early exits, selects instead of branches);
// CRUMPLE_DISABLE_SIMD builds the same source with vectorization off.
#pragma once

#include <cstdint>

#include "fast/step_scratch.h"
#include "fast/topology.h"

namespace crumple::fast {

/// Per-step constants the kernels need (float, the backend's precision).
struct StepConstants {
  float h = 0, h2 = 0;       ///< time step and its square
  float kappa = 0;           ///< stiffness per unit mass [Eq 5]
  float implicit = 0;        ///< w per unit mass: W_e = w (m_a + m_b) I is a spring's block of the
                             ///< implicit velocity step, w = h^2 kappa (approx) + h c (viscosity, D17)
  float axial = 0;           ///< the axial Jacobian (else 0): h^2 kappa, and a spring's block is
                             ///< W_e = (m_a + m_b)(axial u u^T + viscous I) in axial_blocks/axial_sweep
  float viscous = 0;         ///< h c, the viscosity's part of W_e (D17)
  float bend = 0;            ///< bending coefficient per unit mass [Eq 9]
  float damping = 0;         ///< spring-axis damping per unit mass
  float gravity = 0;         ///< acceleration along -z
  bool balanced = true;      ///< balanced bending form (MODEL.md §6)
  bool bounded = true;       ///< bounded predictor (docs/DECISIONS.md D1), else explicit
};

/// Area vector (x1 - x0) x (x2 - x0) of each triangle (zero for dead ones), in units of 1/unit,
/// into area[t]: the edges are scaled by `unit` (a power of two, FastSimulator::length_unit)
/// before the product, which changes no normal's bits and keeps a tiny mesh's products out of
/// float's subnormals.                                                                 §1
void triangle_areas(const Topology& m, float unit, Float4* area, int begin, int end);
/// The same for one triangle t: an event's, without the pass's loop and prefetches.     §1
void triangle_area(const Topology& m, float unit, Float4* area, int t);
/// n_v = normalized sum of the area vectors (m.T.area) of v's triangles, into normals[v] (the
/// mesh's own V.nr: the normals outlive the step).                                      §1
void vertex_normals(const Topology& m, Float4* normals, int begin, int end);
/// The same for one vertex v: an event's renewal, without the pass's loop.               §1
void vertex_normal(const Topology& m, Float4* normals, int v);
/// Per edge, from the vertex rows, into out[e]: the spring force on endpoint a (Hookean with
/// kappa_e [Eq 5], damping), and the bending magnitude s C_beta B and balanced mean of its
/// stencil [Eq 8-9].
void edge_forces(const Edges& E, const Vertices& V, const StepConstants& c, EdgeOut* out, int begin, int end);
/// Per vertex: gathers f_v, sum W_e and sum W_e (v_o - v_v) over its springs (the edge records
/// and the neighbours' rows) into f, and writes the first Jacobi guess g (the predictor, §3)
/// with m_v in w.
void gather_forces(const Topology& m, const EdgeOut* records, const StepConstants& c, VertexForces& f, Float4* g,
                   int begin, int end);
/// One Jacobi sweep of the implicit velocity step (approx, viscosity): reads g, writes g_next. §3
void jacobi_sweep(const Topology& m, const VertexForces& f, const StepConstants& c, const Float4* g,
                  Float4* g_next, int begin, int end);
/// The axial Jacobian (MODEL.md §3): per vertex, W = sum_e W_e over its springs, u along each
/// spring from the positions, into wsum; then the first guess into g as gather_forces
/// writes it for the isotropic step, with the 3 x 3 rows (reads the forces gather_forces summed).
void axial_blocks(const Topology& m, const VertexForces& f, const StepConstants& c, Block3* wsum, Float4* g,
                  int begin, int end);
/// One Jacobi sweep with the axial blocks: (m I + W) g_next = m v + h f + sum_e W_e g_o.     §3
void axial_sweep(const Topology& m, const VertexForces& f, const Block3* wsum, const StepConstants& c,
                 const Float4* g, Float4* g_next, int begin, int end);
/// Symplectic Euler's new velocity into g: v + h f / m.                               §3
void explicit_velocity(const Vertices& V, const VertexForces& f, const StepConstants& c, Float4* g, int begin,
                       int end);
/// Sums over [begin, end) of m (g - v) - h f (the momentum a finite sweep count adds) into
/// out[0..2] and of m into out[3], in double.
void momentum_drift(const Vertices& V, const VertexForces& f, const Float4* g, const StepConstants& c, int begin,
                    int end, double out[4]);
/// The new velocity v = g - correction into V's velocities and x += h v into its positions,
/// then the sphere constraint (radius <= 0: none).                                     §3, §8
void advance(const Float4* g, const StepConstants& c, const float correction[3], const float center[3],
             float radius, Vertices& V, int begin, int end);

// XPBD with small steps (kernels_xpbd.cpp, D19). Its guess rows hold the displacement of the
// step (x, y, z) and the inverse mass (w; 0 for a pinned vertex).
struct XpbdConstants {
  float kappa = 0;  ///< stiffness per unit mass: the compliance is 1 / (kappa (m_a + m_b)) [Eq 5]
  float h2 = 0;     ///< h^2
  float unit = 1;   ///< lengths scaled by it (a power of two, as in triangle_areas)
};
/// The viscosity's step alone (D19's operator splitting): the first guess of the implicit
/// velocity step with W_e = h c_e I and no force but gravity's acceleration in the predictor.
void viscous_guess(const Topology& m, const StepConstants& c, Float4* g, int begin, int end);
/// v = g - correction into V's velocities (live slots; dead ones get 0).
void take_velocity(const Float4* g, const float correction[3], Vertices& V, int begin, int end);
/// d = h (v + h f / m) and w = 1 / m (0 for a dead slot) into disp.
void xpbd_predict(const Vertices& V, const VertexForces& f, const StepConstants& c, Float4* disp, int begin,
                  int end);
/// Projects the distance constraints of the edge slots slots[begin, end), which share no vertex
/// (one colour of ConstraintColors): dlambda = -C / (w_a + w_b + alpha~), d_a += w_a dlambda u,
/// d_b -= w_b dlambda u.
void xpbd_project(const Edges& E, const Vertices& V, const XpbdConstants& c, const std::int32_t* slots,
                  Float4* disp, int begin, int end);
/// g = d / h: the step's velocity, which advance() then turns back into x + h v.
void displacement_to_velocity(float h, Float4* g, int begin, int end);

/// Constants of the fracture and restoration tests.
struct AdaptConstants {
  float phi = 0;             ///< [Eq 6]
  float epsilon = 0;         ///< [Eq 10]
  float floor_length = 0;    ///< rest lengths below it never break (MODEL.md §4)
  float step_exponent = 1;   ///< h / h_ref of P_step = 1 - (1 - P)^(h/h_ref)
  float budget = 1;          ///< the vertex budget's factor on P_step (D22; epsilon comes scaled)
  float unit = 1;            ///< lengths are compared scaled by it (a power of two; see triangle_areas)
  std::uint64_t seed = 0;    ///< random stream
  std::uint64_t step = 0;    ///< step counter of the stream
  bool fracture = true, restoration = true;
};

/// Per edge: 1 if it breaks this step [Eq 6], 2 if it is an alive auxiliary edge with a split
/// record whose crease is bent enough to restore [Eq 10] (the other topology conditions are
/// checked when applied), else 0.
void adapt_test(const Topology& m, const AdaptConstants& c, std::uint8_t* out, int begin, int end);

}  // namespace crumple::fast
