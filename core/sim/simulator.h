// The backend interface. Every backend (the scalar reference, the fast SoA core) implements the
// same model of ../shared/paper/MODEL.md behind this class, so the command, the tests and the
// benchmarks iterate one registry of backends (see backends.h) and run the same cases on each.
//
// A backend owns the mesh topology (vertices, edges, triangles, split records) and the
// per-step state (positions, velocities, masses). Element ids follow one policy in every backend
// so that the random stream, keyed by edge id, gives the same decisions everywhere:
//   * the input mesh's vertices keep their ids; its edges are numbered in order of first
//     appearance walking triangles t = 0, 1, ... and their edges (v0,v1), (v1,v2), (v2,v0);
//   * a removed vertex, edge or triangle id goes on a free list of its kind (last in, first
//     out); a new element takes the free list's last id, else the next new id;
//   * a split allocates, in order: vertex n; edges e_in, e_nj, e_ln, e_nr (those that exist);
//     triangle (n,j,l) then (n,i,r); triangles (i,j,l) and (j,i,r) keep their ids as (i,n,l)
//     and (j,n,r). A restore frees, in order: edges e_in, e_nj, e_ln, e_nr, triangles (n,j,l),
//     (n,i,r), vertex n.
#pragma once

#include <array>
#include <cstdio>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mesh/input_mesh.h"
#include "model/params.h"
#include "sim/manipulators.h"

namespace crumple {

using Vec3d = std::array<double, 3>;

/// Totals over the current state (one row of stats.csv, less the frame bookkeeping).
struct Totals {
  int vertices = 0;          ///< live vertices
  int edges = 0;             ///< live mesh edges (in triangles; auxiliary springs not counted)
  int auxiliary = 0;         ///< live auxiliary springs (broken edges holding a crease)
  int triangles = 0;         ///< live triangles
  double mass = 0;           ///< sum of m_k
  Vec3d momentum{};          ///< sum of m_k v_k
  double kinetic = 0;        ///< sum of m_k |v_k|^2 / 2
  double max_strain = 0;     ///< max over mesh edges of |lt/l0 - 1|
  double rms_strain = 0;     ///< root mean square over mesh edges of lt/l0 - 1
  double max_distance = 0;   ///< max over vertices of |x_k - c| (c: the scene's centre)
  double max_speed = 0;      ///< max over vertices of |v_k|
};

/// Topology events of one step.
struct StepEvents {
  int splits = 0;    ///< edges broken and split                 [Eq 6, Eq 2-4, 7]
  int restores = 0;  ///< auxiliary edges restored               [Eq 10-12]
  std::vector<int> split_edges;     ///< ids of the split edges (now auxiliary), ascending
  std::vector<int> restored_edges;  ///< ids of the restored edges (mesh edges again), ascending
};

/// The adaptive-mesh tests of one edge on the current state (MODEL.md §4, §7), before applying.
struct Decision {
  std::uint8_t kind = 0;  ///< 0 none, 1 breaks [Eq 6], 2 restoration angle test passes [Eq 10]
  double margin = 0;      ///< kind 1 candidates: P_step - u (how far from the other outcome)
};

/// One spring as a test sees it.
struct EdgeView {
  int a = -1, b = -1;          ///< endpoint vertex ids
  int wing_l = -1, wing_r = -1;  ///< third vertex of the triangle traversing a->b, b->a (-1 none)
  double rest = 0;             ///< current rest length l0
  bool auxiliary = false;      ///< a broken edge kept as a spring
  bool breakable = false;      ///< may break [Eq 6] (mesh edges) ; [Eq 10] uses it
};

/// A copy of the whole state, ids as the backend has them (dead slots marked), for tests/output.
struct Snapshot {
  std::vector<Vec3d> rest, position, velocity;  ///< per vertex id (dead: zeros)
  std::vector<double> mass;                     ///< per vertex id (dead: 0)
  std::vector<bool> vertex_alive;               ///< per vertex id
  std::vector<EdgeView> edges;                  ///< per edge id (dead: a = -1)
  std::vector<std::array<int, 3>> triangles;    ///< per triangle id (dead: {-1,-1,-1})
};

/// Writes the live vertices (renumbered densely) and triangles of a snapshot as an OBJ, with
/// every auxiliary spring (a crease held by a broken edge) as an `l a b` line.
/// Write errors are left in std::ferror(file) for the caller, who checks it before closing.
void write_snapshot_obj(std::FILE* file, const Snapshot& s);

/// What a renderer reads, packed by Simulator::render in the layout a GPU takes.
struct RenderBuffers {
  std::vector<float> positions;         ///< x, y, z per vertex id (dead ids: zeros, never indexed)
  std::vector<float> normals;           ///< unit vertex normal per vertex id (MODEL.md §1)
  std::vector<std::uint32_t> triangles; ///< the live triangles' vertex ids, three each, by id
};

/// When a backend runs its fracture/restoration pass (Params::adapt_per_frame): after every
/// step, or after the step that completes Params::adapt_interval() of simulated time (a frame,
/// or adapt_every). Both backends keep one, so they pass at the same steps.
class AdaptClock {
 public:
  /// Counts a step of h; true if the pass runs after it.
  bool tick(const Params& p) {
    if (!p.adapt_per_frame) return true;
    elapsed_ += p.h();
    if (elapsed_ < p.adapt_interval() * (1 - 1e-6)) return false;  // S steps of interval / S, rounded
    elapsed_ = 0;
    return true;
  }

 private:
  double elapsed_ = 0;  ///< simulated time since the last pass
};

class Simulator {
 public:
  virtual ~Simulator() = default;

  /// The backend's registry name ("reference", "fast").
  virtual const char* name() const = 0;

  /// An independent copy of the whole simulation (topology, state, time, random stream
  /// position): benchmarks restore a prepared state with it, tests compare branches.
  virtual std::unique_ptr<Simulator> clone() const = 0;

  /// Advances one time step h = params.h(): forces, integration, sphere, fracture, restoration.
  virtual StepEvents step() = 0;

  /// Turns fracture [Eq 6] and restoration [Eq 10] on or off from the next step on. Off, the
  /// topology is frozen and a step is the physics alone: the benchmarks time the same prepared
  /// frames both ways to price the events (BM_Frozen in bench/bench_frame.cpp).
  virtual void set_adaptivity(bool fracture, bool restoration) = 0;

  /// Steps per frame from now on (h = frame_dt / substeps): run_frame's automatic choice.
  virtual void set_substeps(int substeps) = 0;

  /// A bound on the stiffest mode of the current mesh per unit kappa: the largest Gershgorin row
  /// sum of M^-1/2 L M^-1/2 (same eigenvalues as M^-1 L), L the Laplacian weighted by
  /// m_i + m_j ([Eq 5]): mu = max_i sum_{e=(i,j)} (m_i + m_j) (1 / m_i + 1 / sqrt(m_i m_j)).
  /// omega_max^2 <= kappa mu for the springs (each spring's 3 x 3 block has norm kappa_e while
  /// it is longer than half its rest length) and gamma_max <= c mu for the viscosity (D17).
  /// A split's light new vertex raises it.
  virtual double stiffness_bound() const = 0;

  /// Simulated time and number of steps taken.
  virtual double time() const = 0;
  virtual std::uint64_t steps() const = 0;

  virtual Totals totals() const = 0;
  virtual Snapshot snapshot() const = 0;

  /// Empty when the topology is a valid oriented manifold with consistent helper structures;
  /// otherwise a description of the first inconsistency.
  virtual std::string check_topology() const = 0;

  /// Manipulators applied from the next step on (sim/manipulators.h says how); ids must be
  /// checked by the caller (the embedding API does).
  virtual void set_manipulators(const Manipulators& m) = 0;
  /// Writes positions and normals of the current state into out; the triangles too if
  /// `triangles` (a renderer needs them only when the topology changed). Not const: a backend
  /// may bring cached normals up to date (the same values its next step would compute).
  virtual void render(RenderBuffers& out, bool triangles) = 0;
  /// Faults in all the memory reserved for the mesh's growth, so that no step page-faults until
  /// the mesh outgrows its reserve (a real-time loop's choice: more resident memory and a longer
  /// load for no first touch inside a frame, docs/DECISIONS.md D16). A copy of a resident
  /// simulator is resident. A backend that reserves nothing ahead does nothing.
  virtual void make_resident() {}

  // --- passes, for per-pass benchmarks ---
  /// The passes of a step that run_pass() can run alone, in step order.
  virtual std::vector<std::string> pass_names() const = 0;
  /// Runs one pass on the current state (it may change the state, as in a step).
  virtual void run_pass(const std::string& name) = 0;

  // --- hooks for tests: each runs one part of the model on the current state ---
  /// Vertex normals (area-weighted, normalized), per vertex id.
  virtual std::vector<Vec3d> normals() const = 0;
  /// Total force on each vertex (springs, bending, gravity, damping), per vertex id.
  virtual std::vector<Vec3d> forces() const = 0;
  /// The fracture and restoration decisions the next step's adapt pass would take on the
  /// current positions (per edge id; before the in-pass skipping of touched triangles).
  virtual std::vector<Decision> decide() const = 0;
  /// Splits edge e now (as if it broke), if it is a live breakable mesh edge. Returns success.
  virtual bool split(int e) = 0;
  /// Restores auxiliary edge e now, if the mesh allows it (MODEL.md §7), ignoring the angle test.
  virtual bool restore(int e) = 0;
  /// Overwrites positions and velocities (per vertex id; dead ids ignored).
  virtual void set_state(const std::vector<Vec3d>& x, const std::vector<Vec3d>& v) = 0;
  /// Overwrites masses (per vertex id) and updates every kappa_e [Eq 5].
  virtual void set_masses(const std::vector<double>& m) = 0;
};

}  // namespace crumple
