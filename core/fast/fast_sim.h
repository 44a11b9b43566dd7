// The fast backend: the model of MODEL.md in float, structure-of-arrays, with every pass a
// range kernel (kernels.h) run on the backend's TBB arena.
//
// Design note (the whole pipeline of one step; cf. Box2D's solver.h):
//   forces     triangle_areas -> vertex_normals -> edge_forces -> gather_forces
//              Springs, bending and predictor are computed per element and gathered per
//              vertex over its adjacency lists: no scatter, no atomics, one summation order.
//              The vertex state lives in 16-byte rows (position with mass, velocity with mass,
//              normal: topology.h), and the edge pass reads each of an edge's four vertices as
//              rows, eight edges in AVX lanes (lanes8.h). It stores per edge only what the
//              gather cannot compute from the endpoints' rows (force and bending, 32 bytes);
//              the gather sums those records as wide rows (wide.h), the first 8 entries of a
//              list in a loop of fixed length (kernels.cpp says what GCC makes of it), and the
//              implicit blocks W_e, kappa_e = kappa (m_a + m_b) (D15), from the neighbours'
//              velocity rows. Springs are evaluated once per edge, not once from each side: a
//              second set of square roots would cost more than the per-edge output does. What
//              was measured and not kept for this pass is in docs/PERFORMANCE.md.
//   integrate  K x jacobi_sweep (double-buffered guesses, each neighbour's mass in w, so a
//              sweep reads one 16-byte value per neighbour and nothing per edge) ->
//              momentum_drift (fixed-block reduction) -> advance (new v and x, sphere
//              constraint). Explicit Euler replaces the sweeps by explicit_velocity;
//              the axial Jacobian replaces them by axial_blocks and axial_sweep (3 x 3 rows);
//              XPBD (fast_xpbd.cpp) projects the springs as constraints, one colour of
//              vertex-disjoint springs at a time (constraint_colors.h);
//              Baraff-Witkin runs on the reference path.
//   adapt      triangle_areas -> vertex_normals on the new positions -> adapt_test (fracture
//              [Eq 6] and restoration [Eq 10] decisions per edge, all on that one state) ->
//              splits in ascending edge id, then restores in ascending id, each skipped when
//              an earlier event of the pass changed one of its triangles (MODEL.md §4). Splits
//              apply in parallel rounds of vertex-disjoint events and restores in parallel
//              waves, both with the serial result (docs/DECISIONS.md D13, D14).
//   layout     when enough elements were created since the last time, relayout() (layout.h)
//              reorders every slot along a space-filling curve of the rest positions, keeping
//              logical ids, so that neighbours stay in nearby cache lines (D12): the vertices
//              in that step, then their lists, the triangles, the edges' order and the edges
//              in the next four, so that no step carries it whole.
//   data       the mesh (topology.h: hot vertex state, cold topology, adjacency) outlives the
//              step; what the forces and integrate passes hand on to each other (rows, edge
//              records, forces, guesses) is per-step scratch (step_scratch.h), which edits and
//              relayout neither keep nor permute. Each kernel's signature shows what it writes.
//   Threads only ever split a pass's range, a round or a wave; the edits touch O(events) elements and
//   keep every helper structure (adjacency, wings) up to date incrementally, so a frame
//   with a few hundred splits costs about what one without does.
#pragma once

#include <array>
#include <vector>

#include "fast/constraint_colors.h"
#include "fast/kernels.h"
#include "fast/layout.h"
#include "fast/parallel.h"
#include "fast/pass_events.h"
#include "fast/restore_waves.h"
#include "fast/split_rounds.h"
#include "fast/topology.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace crumple::fast {

/// The passes of a step, for per-pass timing and benchmarks.
enum class Pass { Normals, EdgeForces, Gather, Integrate, AdaptTest, TopologyApply, Layout, kCount };
const char* to_string(Pass);

class FastSimulator final : public Simulator {
 public:
  FastSimulator(const InputMesh& mesh, const Params& params, int threads);
  /// A copy keeps the reserved room of the original (aligned.h's Array), so a benchmark timing
  /// frames of a clone does not time reallocations.
  FastSimulator(const FastSimulator& o) = default;

  const char* name() const override { return "fast"; }
  std::unique_ptr<Simulator> clone() const override { return std::make_unique<FastSimulator>(*this); }
  StepEvents step() override;
  void set_adaptivity(bool fracture, bool restoration) override {
    params_.fracture = fracture;
    params_.restoration = restoration;
  }
  void set_substeps(int substeps) override { params_.substeps = substeps; }
  double stiffness_bound() const override;
  double time() const override { return time_; }
  std::uint64_t steps() const override { return steps_; }
  Totals totals() const override;
  Snapshot snapshot() const override;
  std::string check_topology() const override { return topo_.check(); }
  std::vector<Vec3d> normals() const override;
  std::vector<Vec3d> forces() const override;
  std::vector<Decision> decide() const override;
  bool split(int e) override;
  bool restore(int e) override;
  void set_state(const std::vector<Vec3d>& x, const std::vector<Vec3d>& v) override;
  void set_masses(const std::vector<double>& m) override;
  void set_manipulators(const Manipulators& m) override;
  void render(RenderBuffers& out, bool triangles) override;
  void make_resident() override;

  /// Runs one pass of a step on the current state (benchmarks time passes one by one).
  void run_pass(Pass p);
  std::vector<std::string> pass_names() const override;
  void run_pass(const std::string& name) override;
  /// Seconds spent in each pass since construction (steps only).
  const std::array<double, int(Pass::kCount)>& pass_seconds() const { return pass_seconds_; }
  const Topology& topology() const { return topo_; }
  const LayoutScratch& layout_scratch() const { return layout_scratch_; }
  /// When to relayout: once the vertices created since the last one reach this fraction of the
  /// slots (0: after every step's topology pass; negative: never). Results do not depend on it
  /// but for the last bits of the momentum correction and of totals().rms_strain (layout.h). A
  /// relayout's later phases run in the steps after its first, whatever the fraction.
  void set_layout_fraction(double f) { layout_fraction_ = f; }
  /// Relayout phases run since construction.
  std::uint64_t relayout_phases() const { return relayout_phases_; }
  /// Test hook: apply a pass's splits and restores one after the other instead of in parallel
  /// rounds and waves (which must give the same result, bit for bit).
  void set_serial_edits(bool on) { serial_edits_ = on; }
  /// Split rounds so far large enough to run as a parallel loop (tests check they happened).
  std::uint64_t large_rounds() const { return rounds_.large_rounds(); }
  /// Restore waves so far large enough to run as a parallel loop (tests check they happened).
  std::uint64_t large_waves() const { return waves_.large_waves(); }
  /// The restores the last step's topology pass applied in waves, for tests of the waves.
  std::vector<RestoreWaves::Applied> restore_waves_applied() const { return waves_.applied(); }
  /// The splits the last step's topology pass applied in rounds, for tests of the rounds.
  std::vector<SplitRounds::Applied> split_rounds_applied() const { return rounds_.applied(); }

 private:
  StepConstants step_constants() const;
  /// The approximate implicit step with the axial Jacobian (kernels_axial.cpp).
  bool axial() const { return params_.integrator == Integrator::Approx && params_.jacobian == Jacobian::Axial; }
  void compute_normals();
  void compute_forces();
  void edge_pass(const StepConstants& c);  ///< edge_forces over every edge slot
  void gather_pass(const StepConstants& c);
  void integrate();
  void pin_guesses();  ///< pinned vertices (hang scene) are fixed neighbours: guess 0
  /// K Jacobi sweeps of the implicit velocity step from the guesses in g (isotropic, or the
  /// axial rows), then the momentum correction of D2 into corr.
  void sweep_rows(const StepConstants& c, float corr[3]);
  /// advance (new v and x, the sphere) from the guesses less the momentum correction, then the pins.
  void advance_state(const StepConstants& c, const float corr[3]);
  // XPBD (fast_xpbd.cpp, D19).
  void integrate_xpbd();
  void viscous_step(const StepConstants& c);  ///< the viscosity's implicit step, no force
  StepEvents adapt();
  void update_layout();    ///< a relayout's phase when one is due (layout.h)
  void warm_ahead();       ///< the arrays' growth room and part of the next relayout's memory faulted in
  void adapt_decide();     ///< normals on the current state, adapt_test into decisions_, the events listed
  StepEvents adapt_apply();  ///< the splits and restores of decisions_, in event order
  // The caller's manipulators (fast_manipulators.cpp).
  int live_slot(int id) const;  ///< slot of live vertex id, else -1
  void add_grab_forces();       ///< after compute_forces: into f and the first guess
  void apply_manipulators();    ///< spheres, planes, then pins
  // The topology pass (fast_adapt.cpp): the events in order, the splits in rounds (D13,
  // split_rounds.h), the restores in waves (D14, restore_waves.h); each event computes its
  // triangles' areas, and the rounds and waves renew the normals event by event.
  friend class SplitRounds;
  friend class RestoreWaves;
  friend struct SerialEvents;
  void list_events(int block, int begin, int end);
  void collect_events();
  void list_event_ids(StepEvents& ev) const;
  void list_event_ids_by_flags(StepEvents& ev) const;
  void renew_normals_of_touched();  ///< the serial edits' renewal, after all events
  float length_unit() const { return length_unit_; }  ///< a power of two near 1 / sheet size (unit_of_length)
  double margin(int e, double budget) const; ///< Decision::margin of slot e on the current normals (decide())
  // One event's edits (fast_edits.cpp).
  SplitCandidate split_candidate(int e) const;
  SplitPlan plan_split(const SplitCandidate& c);  ///< takes the new ids (serial, in event order)
  /// The same for the split-th split of a batch whose new ids are taken at once (split_rounds.h):
  /// its vertex and record are the batch's split-th takes of their kinds, its edges and triangles
  /// the takes from edge_at and tri_at on (Topology::peek_X). Takes nothing: safe in parallel.
  SplitPlan plan_split_at(const SplitCandidate& c, int split, int edge_at, int tri_at) const;
  void apply_split(const SplitPlan& p);  ///< a plan of a candidate that passed (p.e >= 0)
  bool split_edge(int e);                     ///< plan and apply: one split alone
  bool can_restore(int e) const;
  /// can_restore from the split record alone, for the record of an edge that adapt_test
  /// marked for a restore (an alive auxiliary edge with a record) in this pass: the restore
  /// waves' pre-test, whose candidates stay such edges through the pass (RestoreWaves::pretest).
  bool can_restore_record(const SplitRecord& s) const;
  void restore_edge(int e);                 ///< one restore alone, free lists included
  /// All of a restore but the free lists (safe in parallel for restores of disjoint
  /// vertices): returns what it freed, for Topology::free_ids.
  Freed restore_edge_local(int e);
  void render_triangles(std::vector<std::uint32_t>& out);  ///< the live triangles' corner ids, by id

  Params params_;
  AdaptClock adapt_clock_;  ///< which steps run the fracture/restoration pass
  SceneSetup scene_;
  float length_unit_ = 1;  ///< length_unit(): fixed by the scene, read by every event
  Parallel par_;
  Topology topo_;
  double time_ = 0;
  std::uint64_t steps_ = 0;
  // Per-element scratch of the topology pass, in Arrays like the topology's (a copy keeps their
  // room, growth is faulted in ahead: D16), reserved with it in the constructor.
  Array<std::uint8_t> decisions_;         ///< adapt_test output per edge
  std::vector<int> touched_;              ///< the serial edits' vertices, in event order (repeats)
  /// The events of a pass, kept from pass to pass so that a pass allocates (and faults in) no
  /// memory. An event's key is its edge's logical id above its slot (a restore's, while the keys
  /// sort, above its place in `carried`): keys sort in event order.
  struct EventLists {
    std::vector<std::vector<std::uint64_t>> found;  ///< keys per block of adapt_test and kind, in slot order
    std::vector<std::vector<int>> found_records;    ///< per block b, the split record of each key of found[2b + 1]
    std::vector<std::uint64_t> keys;                ///< one kind's keys, sorted
    std::vector<std::uint64_t> spare;               ///< the keys' other buffer while they are sorted
    std::vector<int> count;                         ///< the sort's digit counts
    std::vector<int> splits, restores;              ///< event slots in event order
    std::vector<int> restore_records;               ///< each restore's split record, in event order
    std::vector<std::array<int, 2>> carried;        ///< a restore key's slot and record while the keys sort
  };
  EventLists events_;
  PassStamps stamps_;                     ///< the triangles this pass's events changed
  SplitRounds rounds_;                    ///< the splits' unit, with its scratch
  RestoreWaves waves_;                    ///< the restores' unit, with its scratch
  StepScratch step_;                      ///< the physics step's rows, records, forces and guesses
  ConstraintColors colors_;               ///< XPBD's projection order (stale after any edit)
  Manipulators manip_;                    ///< the caller's, applied every step
  double layout_fraction_ = 0.25;         ///< see set_layout_fraction
  int layout_phase_ = 0;                  ///< the relayout phase this step runs (0: when stale)
  std::uint64_t relayout_phases_ = 0;     ///< see relayout_phases
  bool serial_edits_ = false;             ///< see set_serial_edits
  LayoutScratch layout_scratch_;          ///< relayout's reused memory (copied warm by clones)
  std::vector<std::size_t> render_scratch_;  ///< render_triangles' block starts
  bool normals_valid_ = false;            ///< normals and areas match the current state
  std::array<double, int(Pass::kCount)> pass_seconds_{};
};

}  // namespace crumple::fast
