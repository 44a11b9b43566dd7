// What a caller moves each frame besides the scene (MODEL.md §8 has only the shrinking sphere):
// kinematic spheres and planes, pinned vertices and grab springs. Plain data shared by the
// embedding API (crumple/crumple.h, which installs this header beside it) and every backend,
// which apply it in small passes of their own (reference/ref_manipulators.cpp,
// fast/fast_manipulators.cpp). docs/DECISIONS.md "API: manipulators" gives the reasons.
//
// Within a step: the grab forces join the model's forces before integration; after
// integration, and again after the adapt pass (a split's new vertex [Eq 7] may land inside an
// obstacle), every live vertex is projected out of each sphere, then onto each plane's side,
// in list order, and finally the pins set their vertices. So at the end of a step every pinned
// vertex is exactly at its target, and every other vertex is outside the last-applied
// obstacle (outside all of them when they do not overlap).
#pragma once

#include <array>
#include <vector>

namespace crumple {

/// A solid ball: vertices inside are moved to its surface along the ray from its centre, and
/// lose the part of their velocity pointing inwards.
struct KinematicSphere {
  std::array<double, 3> center{};  ///< where the caller has put it this frame
  double radius = 0;               ///< > 0
};

/// A half-space boundary (a table): vertices are kept where dot(x - point, normal) >= 0,
/// projected onto the plane along the normal, and lose the part of their velocity into it.
struct KinematicPlane {
  std::array<double, 3> point{};          ///< any point of the plane
  std::array<double, 3> normal{0, 0, 1};  ///< towards the allowed side; normalized when applied
};

/// A vertex held at a target (x = target, v = 0 at the end of every step).
struct Pin {
  int vertex = -1;                 ///< vertex id (a dead id is ignored)
  std::array<double, 3> target{};  ///< where it is held
};

/// A spring pulling one vertex towards a target the caller moves (a hand dragging the sheet).
/// Its force is the backward-Euler force of a zero-length spring of stiffness k on that vertex's
/// row of the approximate implicit system (MODEL.md §3) with its neighbours held, evaluated on
/// the state at the start of the step (x, v, time step h):
///     F = k (target - x - h v) / (1 + h^2 k / M),   M = m + sum_e w_e
/// (m the vertex's mass; over its springs, mesh and auxiliary, w_e = h^2 kappa_e [Eq 5] + h c_e,
/// the scalar block of the implicit velocity step, DECISIONS.md D17, whose h^2 kappa_e term only
/// the approximate implicit method has). It is stable
/// for any k; as k grows the vertex is moved to the target within one step and the sheet
/// follows through its springs. The h v term damps the motion relative to the target.
struct Grab {
  int vertex = -1;                 ///< vertex id (a dead id is ignored)
  std::array<double, 3> target{};  ///< where the spring pulls it
  double stiffness = 1.0;          ///< k, N/m (> 0)
};

struct Manipulators {
  std::vector<KinematicSphere> spheres;  ///< solid balls (a hand, a finger)
  std::vector<KinematicPlane> planes;    ///< half-spaces (a table, a wall)
  std::vector<Pin> pins;                 ///< held vertices
  std::vector<Grab> grabs;               ///< grab springs

  bool empty() const { return spheres.empty() && planes.empty() && pins.empty() && grabs.empty(); }
};

/// The grab force of g on a vertex at x with velocity v, for step h; `row` is M above.
inline std::array<double, 3> grab_force(const Grab& g, const std::array<double, 3>& x,
                                        const std::array<double, 3>& v, double row, double h) {
  const double s = g.stiffness / (1.0 + h * h * g.stiffness / row);
  return {s * (g.target[0] - x[0] - h * v[0]), s * (g.target[1] - x[1] - h * v[1]),
          s * (g.target[2] - x[2] - h * v[2])};
}

}  // namespace crumple
