// The scalar reference backend: the whole model of MODEL.md in plain double-precision loops.
// Speed is not its purpose; being obviously right is. Every later backend is tested against it.
//
// One step (MODEL.md §3-§7):
//   forces      springs [Eq 5], bending [Eq 8-9] on vertex normals, gravity, damping
//   integrate   approximate implicit (K Jacobi sweeps) | symplectic Euler | Baraff-Witkin + CG
//   constrain   the manipulation sphere (sphere scene)
//   adapt       normals on the new state; fracture test [Eq 6] and restoration test [Eq 10] on
//               that one state; splits [Eq 2-4, 7] in ascending edge id, then restores
//               [Eq 11-12 or exact] in ascending id, each skipped if an earlier event of the
//               same pass changed one of its triangles.
#pragma once

#include "reference/ref_mesh.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace crumple::ref {

class ReferenceSimulator final : public Simulator {
 public:
  ReferenceSimulator(const InputMesh& mesh, const Params& params);

  const char* name() const override { return "reference"; }
  std::unique_ptr<Simulator> clone() const override { return std::make_unique<ReferenceSimulator>(*this); }
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
  std::string check_topology() const override { return mesh_.check(); }
  std::vector<Vec3d> normals() const override;
  std::vector<Vec3d> forces() const override;
  std::vector<Decision> decide() const override;
  bool split(int e) override;
  std::vector<std::string> pass_names() const override;
  void run_pass(const std::string& name) override;
  bool restore(int e) override;
  void set_state(const std::vector<Vec3d>& x, const std::vector<Vec3d>& v) override;
  void set_masses(const std::vector<double>& m) override;
  void set_manipulators(const Manipulators& m) override;
  void render(RenderBuffers& out, bool triangles) override;

  const Mesh& mesh() const { return mesh_; }

 private:
  // ref_forces.cpp
  std::vector<V3> vertex_normals() const;
  void add_spring_forces(std::vector<V3>& f) const;
  void add_bending_forces(const std::vector<V3>& n, std::vector<V3>& f) const;
  std::vector<V3> external_forces() const;  ///< all but the springs: bending, gravity
  std::vector<V3> total_forces() const;
  void add_gravity(std::vector<V3>& f) const;
  void advance_step(std::vector<V3> f);  ///< the step after its forces, up to the adapt pass
  // ref_integrate.cpp, ref_xpbd.cpp
  void integrate(double h, const std::vector<V3>& f);
  template <class Block>
  Block implicit_block(const Edge& E, double h) const;
  template <class Block>
  std::vector<V3> solve_rows(double h, const std::vector<V3>& f) const;
  void correct_momentum(double h, const std::vector<V3>& f, std::vector<V3>& vnew) const;
  void advance(double h, const std::vector<V3>& vnew);
  void integrate_xpbd(double h);
  void integrate_explicit(double h, const std::vector<V3>& f);
  void integrate_implicit(double h, const std::vector<V3>& f);
  void apply_sphere();
  // ref_manipulators.cpp
  void add_grab_forces(std::vector<V3>& f) const;
  void apply_manipulators();
  // ref_adapt.cpp
  double break_probability(int e, const std::vector<V3>& n) const;
  double restoration_angle(int e, const std::vector<V3>& n) const;
  bool can_restore(int e) const;
  bool split_edge(int e, const std::vector<V3>& n, double flat_draw);
  void restore_edge(int e);
  void update_kappa(int v);
  StepEvents adapt();

  Params params_;
  AdaptClock adapt_clock_;  ///< which steps run the fracture/restoration pass
  SceneSetup scene_;
  Mesh mesh_;
  double time_ = 0;
  std::uint64_t steps_ = 0;
  std::vector<std::uint64_t> tri_stamp_;  ///< pass number that last changed each triangle
  std::uint64_t pass_ = 0;                ///< topology passes so far
  Manipulators manip_;                    ///< the caller's, applied every step
  std::vector<V3> pass_normals_, pass_forces_;  ///< run_pass() state between passes
};

}  // namespace crumple::ref
