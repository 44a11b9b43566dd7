// The reference backend's manipulators (sim/manipulators.h): grab forces, then the position
// passes (spheres, planes, pins), and the render buffers.
#include <cmath>

#include "reference/reference_sim.h"

namespace crumple::ref {

namespace {
V3 to_v3(const std::array<double, 3>& a) { return V3(a[0], a[1], a[2]); }
}  // namespace

void ReferenceSimulator::set_manipulators(const Manipulators& m) { manip_ = m; }

void ReferenceSimulator::add_grab_forces(std::vector<V3>& f) const {
  const double h = params_.h();
  for (const Grab& g : manip_.grabs) {
    if (g.vertex < 0 || g.vertex >= int(mesh_.verts.size()) || !mesh_.verts[g.vertex].alive) continue;
    const Vertex& V = mesh_.verts[g.vertex];
    double row = V.m;  // M: the scalar W_e of ref_integrate.cpp's implicit_block, summed
    for (int e : V.edges) {
      const Edge& E = mesh_.edges[e];
      const double stiff = params_.integrator == Integrator::Approx ? h * h * E.kappa : 0.0;
      row += stiff + h * params_.viscosity * (mesh_.verts[E.a].m + mesh_.verts[E.b].m);
    }
    f[g.vertex] += to_v3(grab_force(g, {V.x.x(), V.x.y(), V.x.z()}, {V.v.x(), V.v.y(), V.v.z()}, row, h));
  }
}

// Spheres, then planes, then pins, each over every live vertex (the order sim/manipulators.h
// promises, so both backends end a step with the same vertex on the same side).
void ReferenceSimulator::apply_manipulators() {
  for (const KinematicSphere& s : manip_.spheres) {
    const V3 c = to_v3(s.center);
    for (Vertex& V : mesh_.verts) {
      if (!V.alive) continue;
      const V3 d = V.x - c;
      const double r = d.norm();
      if (!(r < s.radius) || r == 0) continue;  // a vertex at the very centre has no outward ray
      const V3 u = d / r;
      V.x = c + s.radius * u;
      const double in = V.v.dot(u);
      if (in < 0) V.v -= in * u;
    }
  }
  for (const KinematicPlane& p : manip_.planes) {
    const V3 n = to_v3(p.normal).normalized(), o = to_v3(p.point);
    for (Vertex& V : mesh_.verts) {
      if (!V.alive) continue;
      const double d = (V.x - o).dot(n);
      if (!(d < 0)) continue;
      V.x -= d * n;
      const double in = V.v.dot(n);
      if (in < 0) V.v -= in * n;
    }
  }
  for (const Pin& p : manip_.pins) {
    if (p.vertex < 0 || p.vertex >= int(mesh_.verts.size()) || !mesh_.verts[p.vertex].alive) continue;
    mesh_.verts[p.vertex].x = to_v3(p.target);
    mesh_.verts[p.vertex].v.setZero();
  }
}

void ReferenceSimulator::render(RenderBuffers& out, bool triangles) {
  const std::vector<V3> n = vertex_normals();
  const std::size_t nv = mesh_.verts.size();
  out.positions.assign(3 * nv, 0.0f);
  out.normals.assign(3 * nv, 0.0f);
  for (std::size_t k = 0; k < nv; ++k) {
    if (!mesh_.verts[k].alive) continue;
    for (int d = 0; d < 3; ++d) {
      out.positions[3 * k + d] = float(mesh_.verts[k].x[d]);
      out.normals[3 * k + d] = float(n[k][d]);
    }
  }
  if (!triangles) return;
  out.triangles.clear();
  for (const Triangle& T : mesh_.tris)
    if (T.alive)
      for (int c = 0; c < 3; ++c) out.triangles.push_back(std::uint32_t(T.v[c]));
}

}  // namespace crumple::ref
