// Forces of the reference backend: vertex normals (MODEL.md §1), springs (§2, [Eq 5]),
// bending (§6, [Eq 8-9]), gravity and spring-axis damping.
#include <cmath>

#include "reference/reference_sim.h"

namespace crumple::ref {

std::vector<V3> ReferenceSimulator::vertex_normals() const {
  std::vector<V3> n(mesh_.verts.size(), V3::Zero());
  for (const Triangle& T : mesh_.tris) {
    if (!T.alive) continue;
    const V3 &a = mesh_.verts[T.v[0]].x, &b = mesh_.verts[T.v[1]].x, &c = mesh_.verts[T.v[2]].x;
    const V3 w = (b - a).cross(c - a);  // twice the area times the unit normal
    for (int v : T.v) n[v] += w;
  }
  for (V3& k : n) {
    const double len = k.norm();
    if (len > 0) k /= len;
  }
  return n;
}

void ReferenceSimulator::add_spring_forces(std::vector<V3>& f) const {
  for (const Edge& E : mesh_.edges) {
    if (!E.alive) continue;
    const Vertex &A = mesh_.verts[E.a], &B = mesh_.verts[E.b];
    const V3 d = A.x - B.x;
    const double lt = d.norm();
    if (!(lt > 0)) continue;
    const V3 u = d / lt;
    V3 fa = -E.kappa * (lt - E.l0) * u;  // Hookean spring, kappa_e from [Eq 5]
    if (params_.damping > 0) {
      const double kd = params_.damping * (A.m + B.m);
      fa -= kd * (A.v - B.v).dot(u) * u;
    }
    f[E.a] += fa;
    f[E.b] -= fa;
  }
}

void ReferenceSimulator::add_bending_forces(const std::vector<V3>& n, std::vector<V3>& f) const {
  if (params_.bend == 0) return;
  for (int e = 0; e < int(mesh_.edges.size()); ++e) {
    const Edge& E = mesh_.edges[e];
    if (!E.alive || E.auxiliary) continue;
    const int l = mesh_.wing(e, 0), r = mesh_.wing(e, 1);
    if (l < 0 || r < 0) continue;
    const V3 &xi = mesh_.verts[E.a].x, &xj = mesh_.verts[E.b].x;
    const V3 &xl = mesh_.verts[l].x, &xr = mesh_.verts[r].x;
    const double B = (1.0 - n[r].dot(n[l])) * (xi - xj).norm() / 2.0;  // [Eq 8]
    const double gap = ((xr + n[r]) - (xl + n[l])).norm() - (xr - xl).norm();
    const double s = gap > 0 ? 1.0 : gap < 0 ? -1.0 : 0.0;
    const double cb = params_.bend * (mesh_.verts[E.a].m + mesh_.verts[E.b].m);
    const double k = s * cb * B;
    V3 fi = -k * n[E.a], fj = -k * n[E.b], fr = k * n[r], fl = k * n[l];  // [Eq 9]
    if (params_.bending == BendingForm::Balanced) {
      const V3 mean = (fi + fj + fr + fl) / 4.0;
      fi -= mean;
      fj -= mean;
      fr -= mean;
      fl -= mean;
    }
    f[E.a] += fi;
    f[E.b] += fj;
    f[r] += fr;
    f[l] += fl;
  }
}

std::vector<V3> ReferenceSimulator::external_forces() const {
  std::vector<V3> f(mesh_.verts.size(), V3::Zero());
  add_bending_forces(vertex_normals(), f);
  add_gravity(f);
  return f;
}

void ReferenceSimulator::add_gravity(std::vector<V3>& f) const {
  for (size_t k = 0; k < f.size(); ++k)
    if (mesh_.verts[k].alive) f[k].z() -= mesh_.verts[k].m * params_.gravity;
}

std::vector<V3> ReferenceSimulator::total_forces() const {
  std::vector<V3> f = external_forces();
  add_spring_forces(f);
  return f;
}

}  // namespace crumple::ref
