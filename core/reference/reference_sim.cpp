#include "reference/reference_sim.h"

#include <cmath>
#include <stdexcept>

namespace crumple::ref {

namespace {
V3 to_v3(const Vec3d& a) { return V3(a[0], a[1], a[2]); }
Vec3d to_arr(const V3& a) { return {a.x(), a.y(), a.z()}; }
}  // namespace

ReferenceSimulator::ReferenceSimulator(const InputMesh& input, const Params& params)
    : params_(params), scene_(make_scene(input, params)) {
  const int nv = int(input.positions.size());
  mesh_.verts.resize(nv);
  for (int k = 0; k < nv; ++k) {
    Vertex& V = mesh_.verts[k];
    V.alive = true;
    V.X = to_v3(scene_.rest[k]);
    V.x = to_v3(scene_.position[k]);
    V.m = scene_.mass[k];
  }
  for (const auto& t : input.triangles) {
    const int id = mesh_.new_triangle();
    if (!mesh_.attach(id, t[0], t[1], t[2]))
      throw InputError("mesh is not an oriented manifold at triangle " + std::to_string(id));
  }
  for (int e = 0; e < int(mesh_.edges.size()); ++e) {
    const Edge& E = mesh_.edges[e];
    mesh_.edges[e].kappa = params_.kappa * (mesh_.verts[E.a].m + mesh_.verts[E.b].m);  // [Eq 5]
  }
  mesh_.euler = mesh_.live_vertices() - mesh_.live_mesh_edges() + mesh_.live_triangles();
}

StepEvents ReferenceSimulator::step() {
  advance_step(total_forces());
  StepEvents ev;
  if (adapt_clock_.tick(params_)) {
    ev = adapt();
    apply_manipulators();  // a split's new vertex may land inside an obstacle
  }
  ++steps_;
  return ev;
}

// The step from its forces on: the caller's grabs, the integrator, the clock, the pinned corners
// (hang scene), the sphere and the manipulators.
void ReferenceSimulator::advance_step(std::vector<V3> f) {
  add_grab_forces(f);
  integrate(params_.h(), f);
  time_ += params_.h();
  for (int k : scene_.pinned) {  // hang scene: pinned corners stay where they started
    mesh_.verts[k].x = to_v3(scene_.position[k]);
    mesh_.verts[k].v.setZero();
  }
  apply_sphere();
  apply_manipulators();
}

// The passes in this order are step() up to its adapt pass, bit for bit (the forces summed in
// total_forces()' order): a benchmark that runs them and then "topology_apply" applies the very
// events step() would.
std::vector<std::string> ReferenceSimulator::pass_names() const {
  return {"normals", "bending", "springs", "integrate", "adapt_test", "topology_apply"};
}

void ReferenceSimulator::run_pass(const std::string& name) {
  if (pass_normals_.size() != mesh_.verts.size()) pass_normals_ = vertex_normals();
  if (pass_forces_.size() != mesh_.verts.size()) pass_forces_.assign(mesh_.verts.size(), V3::Zero());
  if (name == "normals") {
    pass_normals_ = vertex_normals();
  } else if (name == "bending") {  // with gravity: external_forces()
    std::fill(pass_forces_.begin(), pass_forces_.end(), V3::Zero());
    add_bending_forces(pass_normals_, pass_forces_);
    add_gravity(pass_forces_);
  } else if (name == "springs") {
    add_spring_forces(pass_forces_);
  } else if (name == "integrate") {  // the rest of the step's physics (sphere included)
    advance_step(pass_forces_);
  } else if (name == "adapt_test") {
    (void)decide();
  } else if (name == "topology_apply") {  // the whole adapt pass: test and apply
    adapt();
  } else {
    throw std::invalid_argument("unknown pass '" + name + "'");
  }
}

void ReferenceSimulator::apply_sphere() {
  if (!scene_.sphere) return;
  const double R = scene_.sphere_radius(time_);
  const V3 c = to_v3(scene_.center);
  for (Vertex& V : mesh_.verts) {
    if (!V.alive) continue;
    const V3 d = V.x - c;
    const double r = d.norm();
    if (r <= R) continue;
    const V3 u = d / r;
    V.x = c + R * u;
    const double out = V.v.dot(u);
    if (out > 0) V.v -= out * u;
  }
}

double ReferenceSimulator::stiffness_bound() const {
  std::vector<double> row(mesh_.verts.size(), 0.0);
  for (const Edge& E : mesh_.edges) {
    if (!E.alive) continue;
    const double ma = mesh_.verts[E.a].m, mb = mesh_.verts[E.b].m, off = (ma + mb) / std::sqrt(ma * mb);
    row[E.a] += (ma + mb) / ma + off;
    row[E.b] += (ma + mb) / mb + off;
  }
  double mu = 0;
  for (double r : row) mu = std::max(mu, r);
  return mu;
}

Totals ReferenceSimulator::totals() const {
  Totals T;
  T.vertices = mesh_.live_vertices();
  T.edges = mesh_.live_mesh_edges();
  T.triangles = mesh_.live_triangles();
  V3 p = V3::Zero();
  const V3 c = to_v3(scene_.center);
  for (const Vertex& V : mesh_.verts) {
    if (!V.alive) continue;
    T.mass += V.m;
    p += V.m * V.v;
    T.kinetic += 0.5 * V.m * V.v.squaredNorm();
    T.max_distance = std::max(T.max_distance, (V.x - c).norm());
    T.max_speed = std::max(T.max_speed, V.v.norm());
  }
  T.momentum = to_arr(p);
  for (const Edge& E : mesh_.edges) {
    if (!E.alive) continue;
    if (E.auxiliary) {
      ++T.auxiliary;
      continue;
    }
    const double lt = (mesh_.verts[E.a].x - mesh_.verts[E.b].x).norm();
    T.max_strain = std::max(T.max_strain, std::abs(lt / E.l0 - 1.0));
    T.rms_strain += (lt / E.l0 - 1.0) * (lt / E.l0 - 1.0);
  }
  T.rms_strain = std::sqrt(T.rms_strain / std::max(1, T.edges));
  return T;
}

Snapshot ReferenceSimulator::snapshot() const {
  Snapshot s;
  for (const Vertex& V : mesh_.verts) {
    s.vertex_alive.push_back(V.alive);
    s.rest.push_back(V.alive ? to_arr(V.X) : Vec3d{});
    s.position.push_back(V.alive ? to_arr(V.x) : Vec3d{});
    s.velocity.push_back(V.alive ? to_arr(V.v) : Vec3d{});
    s.mass.push_back(V.alive ? V.m : 0.0);
  }
  for (int e = 0; e < int(mesh_.edges.size()); ++e) {
    const Edge& E = mesh_.edges[e];
    EdgeView ev;
    if (E.alive) {
      ev.a = E.a;
      ev.b = E.b;
      ev.wing_l = mesh_.wing(e, 0);
      ev.wing_r = mesh_.wing(e, 1);
      ev.rest = E.l0;
      ev.auxiliary = E.auxiliary;
      ev.breakable = E.breakable;
    }
    s.edges.push_back(ev);
  }
  for (const Triangle& T : mesh_.tris)
    s.triangles.push_back(T.alive ? T.v : std::array<int, 3>{-1, -1, -1});
  return s;
}

void ReferenceSimulator::set_state(const std::vector<Vec3d>& x, const std::vector<Vec3d>& v) {
  for (size_t k = 0; k < mesh_.verts.size() && k < x.size() && k < v.size(); ++k) {
    if (!mesh_.verts[k].alive) continue;
    mesh_.verts[k].x = to_v3(x[k]);
    mesh_.verts[k].v = to_v3(v[k]);
  }
}

void ReferenceSimulator::set_masses(const std::vector<double>& m) {
  for (size_t k = 0; k < mesh_.verts.size() && k < m.size(); ++k)
    if (mesh_.verts[k].alive) mesh_.verts[k].m = m[k];
  for (size_t k = 0; k < mesh_.verts.size(); ++k)
    if (mesh_.verts[k].alive) update_kappa(int(k));
}

std::vector<Vec3d> ReferenceSimulator::normals() const {
  std::vector<Vec3d> out;
  for (const V3& n : vertex_normals()) out.push_back(to_arr(n));
  return out;
}

std::vector<Vec3d> ReferenceSimulator::forces() const {
  std::vector<V3> f = total_forces();
  add_grab_forces(f);
  std::vector<Vec3d> out;
  for (const V3& g : f) out.push_back(to_arr(g));
  return out;
}

}  // namespace crumple::ref
