#include "api/api_checks.h"

#include <algorithm>
#include <cmath>

#include "sim/backends.h"

namespace crumple::api {

namespace {
bool finite3(const std::array<double, 3>& a) {
  return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]);
}

std::string bad(const char* kind, std::size_t k, const std::string& what) {
  return std::string(kind) + " " + std::to_string(k) + ": " + what;
}

std::string check_vertex(const char* kind, std::size_t k, int v, int vertex_ids) {
  if (v >= 0 && v < vertex_ids) return {};
  return bad(kind, k, "vertex " + std::to_string(v) + " does not exist (the sheet has " +
                          std::to_string(vertex_ids) + " vertex ids)");
}
}  // namespace

InputMesh input_mesh(const SheetDesc& d) {
  if (d.positions.empty() && d.triangles.empty()) return make_grid(d.grid, d.alternate_diagonals);
  if (d.positions.size() % 3 != 0) throw InputError("mesh: positions must hold 3 floats per vertex");
  if (d.triangles.size() % 3 != 0) throw InputError("mesh: triangles must hold 3 vertex ids per triangle");
  InputMesh mesh;
  for (std::size_t k = 0; k < d.positions.size(); k += 3)
    mesh.positions.push_back({d.positions[k], d.positions[k + 1], d.positions[k + 2]});
  for (std::size_t k = 0; k < d.triangles.size(); k += 3) {
    const std::uint32_t a = d.triangles[k], b = d.triangles[k + 1], c = d.triangles[k + 2];
    if (std::max({a, b, c}) > 0x7fffffffu) throw InputError("mesh: triangle " + std::to_string(k / 3) + " has a vertex id over 2^31");
    mesh.triangles.push_back({int(a), int(b), int(c)});
  }
  validate_mesh(mesh, "mesh");
  return mesh;
}

std::string check_desc(const SheetDesc& d) {
  if (std::string m = d.params.validate(); !m.empty()) return m;
  if (d.threads < 0 || d.threads > 256) return "threads must be in [0, 256] (0: the caller's arena)";
  const auto& names = backend_names();
  if (std::find(names.begin(), names.end(), d.backend) == names.end()) return "unknown backend '" + d.backend + "'";
  if (d.positions.empty() && d.triangles.empty() && (d.grid < 2 || d.grid > 8192)) return "--grid must be in [2, 8192]";
  return {};
}

std::string check_manipulators(const Manipulators& m, int vertex_ids) {
  for (std::size_t k = 0; k < m.spheres.size(); ++k) {
    const KinematicSphere& s = m.spheres[k];
    if (!finite3(s.center) || !std::isfinite(s.radius) || !(s.radius > 0))
      return bad("sphere", k, "needs a finite centre and a finite radius > 0");
  }
  for (std::size_t k = 0; k < m.planes.size(); ++k) {
    const KinematicPlane& p = m.planes[k];
    const double n2 = p.normal[0] * p.normal[0] + p.normal[1] * p.normal[1] + p.normal[2] * p.normal[2];
    if (!finite3(p.point) || !finite3(p.normal) || !(n2 > 0) || !std::isfinite(n2))
      return bad("plane", k, "needs a finite point and a finite nonzero normal");
  }
  for (std::size_t k = 0; k < m.pins.size(); ++k) {
    if (std::string e = check_vertex("pin", k, m.pins[k].vertex, vertex_ids); !e.empty()) return e;
    if (!finite3(m.pins[k].target)) return bad("pin", k, "needs a finite target");
  }
  for (std::size_t k = 0; k < m.grabs.size(); ++k) {
    const Grab& g = m.grabs[k];
    if (std::string e = check_vertex("grab", k, g.vertex, vertex_ids); !e.empty()) return e;
    if (!finite3(g.target) || !std::isfinite(g.stiffness) || !(g.stiffness > 0))
      return bad("grab", k, "needs a finite target and a finite stiffness > 0");
  }
  return {};
}

}  // namespace crumple::api
