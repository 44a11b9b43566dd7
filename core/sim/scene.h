// Scene set-up shared by every backend (MODEL.md §8): initial state, masses, the sphere.
#pragma once

#include <vector>

#include "mesh/input_mesh.h"
#include "model/params.h"
#include "sim/simulator.h"

namespace crumple {

/// Everything a backend needs to start a run, derived once from the mesh and the parameters.
struct SceneSetup {
  std::vector<Vec3d> rest;       ///< X_k, the input positions
  std::vector<Vec3d> position;   ///< x_k at t = 0 (squeezed about the centroid in the free scene)
  std::vector<double> mass;      ///< m_k: total_mass spread by vertex area (1/3 of each triangle)
  Vec3d center{};                ///< c: mass-weighted centroid of the rest positions
  double reach = 0;              ///< distance of the farthest vertex from c
  double size = 0;               ///< bounding-box diagonal of the rest positions
  double floor_length = 0;       ///< rest length below which an edge never breaks (MODEL.md §4)
  bool sphere = false;           ///< the manipulation sphere is active
  double radius_start = 0;       ///< R0 = sphere_start * reach
  double radius_end = 0;         ///< R1 = sphere_end * reach
  double shrink_time = 0;        ///< T
  std::vector<int> pinned;       ///< vertices held at their initial position (hang scene)

  /// R(t): linear from R0 to R1 over T, then R1.
  double sphere_radius(double t) const;
};

/// Builds the scene for a validated mesh; params must validate().
SceneSetup make_scene(const InputMesh& mesh, const Params& params);

}  // namespace crumple
