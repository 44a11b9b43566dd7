// Small meshes with hand-known geometry, and helpers shared by the test suites.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <string>

#include "mesh/input_mesh.h"
#include "sim/backends.h"

namespace crumple::test {

using V3 = Eigen::Vector3d;
inline V3 v3(const Vec3d& a) { return V3(a[0], a[1], a[2]); }
inline Vec3d arr(const V3& a) { return {a.x(), a.y(), a.z()}; }

/// The unit square split by the diagonal 0-2: triangles (0,1,2), (0,2,3), normals +z.
/// Edge ids by the policy of simulator.h: e0 = (0,1), e1 = (1,2), e2 = (2,0) the diagonal,
/// e3 = (2,3), e4 = (3,0).
inline InputMesh unit_square() {
  InputMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}
constexpr int kDiagonal = 2;

/// The unit square folded about its diagonal 0-2 so that the two face normals make the angle
/// `alpha`, then scaled by `scale` about vertex 0 (all five edges compressed by 1 - scale).
/// Vertex 0 stays at the origin, the hinge lies along (1,1,0)/sqrt 2.
inline std::vector<Vec3d> folded_square(double alpha, double scale) {
  const V3 axis = V3(1, 1, 0).normalized();
  const V3 mid(0.5, 0.5, 0);
  auto rotate = [&](const V3& p, double angle) {  // about the hinge line through mid
    const V3 d = p - mid;
    const V3 par = d.dot(axis) * axis, perp = d - par;
    return V3(mid + par + std::cos(angle) * perp + std::sin(angle) * axis.cross(perp));
  };
  // Vertex 1 (in face 0) and vertex 3 (in face 1) each turn by alpha/2, in opposite senses.
  std::vector<V3> p = {V3(0, 0, 0), rotate(V3(1, 0, 0), alpha / 2), V3(1, 1, 0), rotate(V3(0, 1, 0), -alpha / 2)};
  std::vector<Vec3d> out;
  for (const V3& q : p) out.push_back(arr(scale * q));
  return out;
}

/// The logical states are equal, bit for bit (positions, velocities, masses, topology).
inline bool same_snapshot(const Snapshot& a, const Snapshot& b) {
  if (!(a.position == b.position && a.velocity == b.velocity && a.mass == b.mass && a.rest == b.rest &&
        a.vertex_alive == b.vertex_alive && a.triangles == b.triangles && a.edges.size() == b.edges.size()))
    return false;
  for (std::size_t e = 0; e < a.edges.size(); ++e) {
    const EdgeView &p = a.edges[e], &q = b.edges[e];
    if (p.a != q.a || p.b != q.b || p.wing_l != q.wing_l || p.wing_r != q.wing_r || p.rest != q.rest ||
        p.auxiliary != q.auxiliary || p.breakable != q.breakable)
      return false;
  }
  return true;
}


/// Parameters with every force off (nothing moves unless the test says so).
inline Params still_params() {
  Params p;
  p.scene = Scene::Free;
  p.squeeze = 1.0;
  p.perturb = 0;
  p.kappa = 0;
  p.bend = 0;
  p.gravity = 0;
  return p;
}

/// A free sheet, squeezed and easy to break and restore: splits and restores every step.
inline Params churn_params() {
  Params p;
  p.scene = Scene::Free;
  p.squeeze = 0.6;
  p.phi = 0.2;
  p.epsilon = 0.15;
  p.floor = 0.05;
  return p;
}

/// Tolerance for comparisons of a backend with exact (hand-derived) values.
inline double tolerance(const std::string& backend) { return backend == "reference" ? 1e-12 : 2e-5; }

/// Value-parameterized base: each suite deriving from it runs once per registered backend.
class EachBackend : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<Simulator> make(const InputMesh& m, const Params& p, int threads = 1) const {
    return make_simulator(GetParam(), m, p, threads);
  }
  double tol() const { return tolerance(GetParam()); }
};

inline std::string backend_test_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

#define CRUMPLE_FOR_EACH_BACKEND(Suite) \
  INSTANTIATE_TEST_SUITE_P(All, Suite, ::testing::ValuesIn(::crumple::backend_names()), \
                           ::crumple::test::backend_test_name)

inline std::string data_file(const std::string& name) { return std::string(CRUMPLE_TEST_DATA) + "/" + name; }

}  // namespace crumple::test
