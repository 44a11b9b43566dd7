#include "sim/scene.h"

#include <algorithm>
#include <cmath>

namespace crumple {

namespace {
double dist(const Vec3d& a, const Vec3d& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// The initial dome (D11): x += perturb * reach * (1 - (r/reach)^2) * n_rest, with n_rest the
// area-weighted vertex normal of the rest mesh and r the rest distance from the centre.
void add_dome(SceneSetup& s, const InputMesh& mesh, double perturb) {
  const size_t n = mesh.positions.size();
  std::vector<Vec3d> normal(n, Vec3d{0, 0, 0});
  for (const auto& t : mesh.triangles) {
    const Vec3d &a = s.rest[t[0]], &b = s.rest[t[1]], &c = s.rest[t[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const Vec3d cr = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) normal[t[k]][d] += cr[d];
  }
  for (size_t k = 0; k < n; ++k) {
    const double len = std::sqrt(normal[k][0] * normal[k][0] + normal[k][1] * normal[k][1] + normal[k][2] * normal[k][2]);
    const double r = dist(s.rest[k], s.center) / s.reach;
    const double lift = len > 0 ? perturb * s.reach * (1 - r * r) / len : 0.0;
    for (int d = 0; d < 3; ++d) s.position[k][d] += lift * normal[k][d];
  }
}

// The two "top corners": the vertices farthest along y - x and y + x (on the unit-square grid,
// (0,1) and (1,1)); the lowest id wins a tie.
std::vector<int> top_corners(const std::vector<Vec3d>& rest) {
  int left = 0, right = 0;
  for (size_t k = 0; k < rest.size(); ++k) {
    if (rest[k][1] - rest[k][0] > rest[left][1] - rest[left][0]) left = int(k);
    if (rest[k][1] + rest[k][0] > rest[right][1] + rest[right][0]) right = int(k);
  }
  return {left, right};
}
}  // namespace

SceneSetup make_scene(const InputMesh& mesh, const Params& p) {
  SceneSetup s;
  const size_t n = mesh.positions.size();
  s.rest = mesh.positions;
  s.mass.assign(n, 0.0);

  // Vertex area: one third of each adjacent triangle's rest area; mean edge length on the way.
  double total_area = 0, edge_sum = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3d &a = s.rest[t[0]], &b = s.rest[t[1]], &c = s.rest[t[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2],
                 cz = u[0] * w[1] - u[1] * w[0];
    const double area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    for (int k = 0; k < 3; ++k) s.mass[t[k]] += area / 3.0;
    total_area += area;
    edge_sum += dist(a, b) + dist(b, c) + dist(c, a);  // interior edges counted twice: a mean
  }
  for (double& m : s.mass) m *= p.total_mass / total_area;
  const double mean_edge = edge_sum / (3.0 * double(mesh.triangles.size()));
  s.floor_length = p.floor * mean_edge;

  Vec3d lo = s.rest[0], hi = s.rest[0];
  for (size_t k = 0; k < n; ++k) {
    for (int d = 0; d < 3; ++d) {
      s.center[d] += s.mass[k] * s.rest[k][d] / p.total_mass;
      lo[d] = std::min(lo[d], s.rest[k][d]);
      hi[d] = std::max(hi[d], s.rest[k][d]);
    }
  }
  s.size = dist(lo, hi);
  for (const Vec3d& x : s.rest) s.reach = std::max(s.reach, dist(x, s.center));

  s.position = s.rest;
  if (p.perturb > 0) add_dome(s, mesh, p.perturb);
  if (p.scene == Scene::Hang) s.pinned = top_corners(s.rest);
  if (p.scene == Scene::Free) {
    for (Vec3d& x : s.position)
      for (int d = 0; d < 3; ++d) x[d] = s.center[d] + p.squeeze * (x[d] - s.center[d]);
  } else if (p.scene == Scene::Sphere) {
    s.sphere = true;
    s.radius_start = p.sphere_start * s.reach;
    s.radius_end = p.sphere_end * s.reach;
    s.shrink_time = p.sphere_time;
  }
  return s;
}

double SceneSetup::sphere_radius(double t) const {
  if (shrink_time <= 0 || t >= shrink_time) return radius_end;
  return radius_start + (radius_end - radius_start) * (t / shrink_time);
}

}  // namespace crumple
