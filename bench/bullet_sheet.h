// The Bullet peer of the crumple benchmark: a btSoftBody cloth patch over the same N x N grid of
// the unit square, hanging from two corners under gravity in a btSoftRigidDynamicsWorld.
//
// It is a different method (position-based constraint projection, fixed topology, no fracture,
// no sphere), so its timings say what a widely used soft-body library costs per frame on a
// sheet of the same size, not how it compares on the same physics.
#pragma once

#include <memory>

class btSoftBody;
class btSoftRigidDynamicsWorld;

namespace crumple::bench {

class BulletSheet {
 public:
  /// An n x n patch (btSoftBodyHelpers::CreatePatch, gendiags = true) in the z = 0 plane,
  /// total mass 1, corners (0,0) and (1,0) pinned (setMass(node, 0)), gravity -9.81 along z,
  /// m_cfg.piterations = piterations.
  BulletSheet(int n, int piterations);
  ~BulletSheet();
  BulletSheet(const BulletSheet&) = delete;
  BulletSheet& operator=(const BulletSheet&) = delete;

  /// One 1/60 s frame: stepSimulation(1/60., 1, 1/60.).
  void frame();
  /// Largest |coordinate| over all nodes; infinity if any coordinate is not finite.
  double max_abs_coordinate() const;
  /// max_abs_coordinate() <= limit (default 1e3: the sheet is 1 unit wide and hangs ~1 unit).
  bool bounded(double limit = 1e3) const { return max_abs_coordinate() <= limit; }

  int nodes() const;
  int links() const;
  int faces() const;
  int piterations() const;

 private:
  struct Parts;
  std::unique_ptr<Parts> p_;
  btSoftBody* body_ = nullptr;  // owned here; registered with the world
};

}  // namespace crumple::bench
