// Mesh validation and the orientation fix (see input_mesh.h for the properties checked).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <sstream>
#include <tuple>
#include <utility>

#include "mesh/mesh_checks.h"

namespace crumple {
namespace mesh_detail {
namespace {

// One triangle's use of an undirected edge {lo, hi}.
struct EdgeUse {
  int lo;        // smaller vertex index of the edge
  int hi;        // larger vertex index of the edge
  int tri;       // the triangle using it
  int slot;      // the edge runs from corner slot to corner (slot + 1) % 3 of the triangle
  bool forward;  // true if the triangle traverses the edge lo -> hi
};

// Every edge use of every triangle, sorted so that the uses of one edge are adjacent.
std::vector<EdgeUse> sorted_edge_uses(const InputMesh& mesh) {
  std::vector<EdgeUse> uses;
  uses.reserve(3 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles[t][k];
      const int b = mesh.triangles[t][(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), static_cast<int>(t), k, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.lo, x.hi, x.tri) < std::tie(y.lo, y.hi, y.tri);
  });
  return uses;
}

// Calls f(first, last) for each run [first, last) of uses of the same edge.
template <class F>
void for_each_edge(const std::vector<EdgeUse>& uses, F f) {
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    f(i, j);
    i = j;
  }
}

std::string vertex_name(const MeshLabels& labels, int k) {
  const bool known = k >= 0 && static_cast<std::size_t>(k) < labels.vertex_number.size();
  return std::to_string(known ? labels.vertex_number[k] : k);
}

std::string edge_name(const MeshLabels& labels, int a, int b) {
  return "edge (" + vertex_name(labels, a) + "," + vertex_name(labels, b) + ")";
}

// "line 12" for a triangle read from a file, "triangle 7" otherwise.
std::string triangle_ref(const MeshLabels& labels, int t) {
  if (labels.triangle_line.empty()) return "triangle " + std::to_string(t);
  return "line " + std::to_string(labels.triangle_line[t]);
}

// Message start for a problem with one triangle: "f.obj:12: triangle (3,4,5)" or
// "where: triangle 7 (2,3,4)".
std::string triangle_prefix(const InputMesh& mesh, const MeshLabels& labels, int t) {
  const auto& tri = mesh.triangles[t];
  std::string corners(1, '(');
  for (int k = 0; k < 3; ++k) (corners += vertex_name(labels, tri[k])) += k < 2 ? ',' : ')';
  if (labels.triangle_line.empty()) {
    return labels.where + ": triangle " + std::to_string(t) + " " + corners;
  }
  return labels.where + ":" + std::to_string(labels.triangle_line[t]) + ": triangle " + corners;
}

[[noreturn]] void fail(const std::string& message) { throw InputError(message); }

// Throws for the first edge used by more than two triangles.
void check_edge_use_counts(const std::vector<EdgeUse>& uses, const MeshLabels& labels) {
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first <= 2) return;
    std::string refs = labels.triangle_line.empty() ? "triangles " : "lines ";
    for (std::size_t i = first; i < last; ++i) {
      const int t = uses[i].tri;
      if (i > first) refs += ", ";
      refs += std::to_string(labels.triangle_line.empty() ? t : labels.triangle_line[t]);
    }
    fail(labels.where + ": " + edge_name(labels, uses[first].lo, uses[first].hi) +
         " is non-manifold: shared by " + std::to_string(last - first) + " triangles (" + refs +
         ")");
  });
}

// Number of edge-connected fans formed by the triangles `around` vertex v (edges through v
// are used by at most two triangles when this is called).
int count_fans(const InputMesh& mesh, int v, const std::vector<int>& around) {
  // Union-find over the positions in `around`; triangles sharing a neighbor of v are joined.
  std::vector<int> parent(around.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<std::pair<int, int>> neighbor_of;  // (neighbor vertex, position in `around`)
  for (std::size_t i = 0; i < around.size(); ++i) {
    for (int corner : mesh.triangles[around[i]]) {
      if (corner != v) neighbor_of.emplace_back(corner, static_cast<int>(i));
    }
  }
  std::sort(neighbor_of.begin(), neighbor_of.end());
  int fans = static_cast<int>(around.size());
  for (std::size_t i = 1; i < neighbor_of.size(); ++i) {
    if (neighbor_of[i].first != neighbor_of[i - 1].first) continue;
    const int a = root(neighbor_of[i].second);
    const int b = root(neighbor_of[i - 1].second);
    if (a != b) {
      parent[a] = b;
      --fans;
    }
  }
  return fans;
}

}  // namespace

void check_triangles(const InputMesh& mesh, const MeshLabels& labels) {
  const auto& where = labels.where;
  if (mesh.triangles.empty()) fail(where + ": no triangles");

  const int n = static_cast<int>(mesh.positions.size());
  std::vector<bool> used(mesh.positions.size(), false);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k : mesh.triangles[t]) {
      if (k < 0 || k >= n) {
        fail(triangle_prefix(mesh, labels, static_cast<int>(t)) + " refers to vertex " +
             std::to_string(k) + " but the mesh has " + std::to_string(n) + " vertices");
      }
      used[k] = true;
    }
  }
  for (int k = 0; k < n; ++k) {
    for (double c : mesh.positions[k]) {
      if (!std::isfinite(c)) fail(where + ": vertex " + vertex_name(labels, k) + " is not finite");
    }
    if (!used[k]) fail(where + ": vertex " + vertex_name(labels, k) + " is not used by any triangle");
  }

  // Squared bounding-box diagonal, the scale for the degenerate-area threshold.
  std::array<double, 3> lo = mesh.positions[0], hi = mesh.positions[0];
  for (const auto& p : mesh.positions) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  }
  double diagonal2 = 0.0;
  for (int d = 0; d < 3; ++d) diagonal2 += (hi[d] - lo[d]) * (hi[d] - lo[d]);
  const double min_area = 1e-12 * diagonal2;

  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      const int repeated = tri[0] == tri[1] || tri[0] == tri[2] ? tri[0] : tri[1];
      fail(triangle_prefix(mesh, labels, static_cast<int>(t)) + " is degenerate: repeats vertex " +
           vertex_name(labels, repeated));
    }
    const auto& p0 = mesh.positions[tri[0]];
    const auto& p1 = mesh.positions[tri[1]];
    const auto& p2 = mesh.positions[tri[2]];
    const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const double w[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const double cx = u[1] * w[2] - u[2] * w[1];
    const double cy = u[2] * w[0] - u[0] * w[2];
    const double cz = u[0] * w[1] - u[1] * w[0];
    const double area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    if (area == 0.0 || area < min_area) {
      std::ostringstream msg;
      msg.precision(3);
      msg << triangle_prefix(mesh, labels, static_cast<int>(t)) << " is degenerate: area " << area
          << " is below 1e-12 * (bounding-box diagonal)^2 = " << min_area;
      fail(msg.str());
    }
  }
}

void check_float_range(const InputMesh& mesh, const MeshLabels& labels) {
  double largest = 0.0;
  int at = 0;
  for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
    for (double c : mesh.positions[k]) {
      if (std::abs(c) > largest) largest = std::abs(c), at = static_cast<int>(k);
    }
  }
  std::ostringstream msg;
  msg.precision(3);
  if (largest > kMaxCoordinate) {
    msg << labels.where << ": vertex " << vertex_name(labels, at) << " has a coordinate of magnitude "
        << largest << ", beyond " << kMaxCoordinate << ": too large to simulate in float";
    fail(msg.str());
  }
  const double shortest_allowed = std::max(kMinEdgeLength, kMinEdgeRelative * largest);
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto& a = mesh.positions[tri[k]];
      const auto& b = mesh.positions[tri[(k + 1) % 3]];
      const double length = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      if (length >= shortest_allowed) continue;
      msg << labels.where << ": " << edge_name(labels, tri[k], tri[(k + 1) % 3]) << " has length "
          << length << ", below max(" << kMinEdgeLength << ", " << kMinEdgeRelative
          << " x the largest coordinate magnitude " << largest
          << "): float cannot resolve it (scale the mesh or move it to the origin)";
      fail(msg.str());
    }
  }
}

void orient_consistently(InputMesh& mesh, const MeshLabels& labels) {
  const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);
  check_edge_use_counts(uses, labels);

  // Across each shared edge: the neighbor triangle, and whether the two triangles traverse the
  // edge in the same direction (then exactly one of them must be flipped).
  struct Link {
    int other = -1;          // neighbor across this edge, -1 on the boundary
    bool same_dir = false;   // both traverse the edge the same way
    const EdgeUse* edge{};   // the edge, for messages
  };
  std::vector<Link> links(3 * mesh.triangles.size());
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first != 2) return;
    const EdgeUse& a = uses[first];
    const EdgeUse& b = uses[first + 1];
    links[3 * a.tri + a.slot] = {b.tri, a.forward == b.forward, &a};
    links[3 * b.tri + b.slot] = {a.tri, a.forward == b.forward, &a};
  });

  // flip[t]: -1 not reached yet, 0 keep, 1 reverse. Seeds are visited in index order, so each
  // component keeps the orientation of its lowest-numbered triangle.
  const int count = static_cast<int>(mesh.triangles.size());
  std::vector<int> flip(mesh.triangles.size(), -1);
  std::vector<int> queue;
  for (int seed = 0; seed < count; ++seed) {
    if (flip[seed] != -1) continue;
    flip[seed] = 0;
    queue.assign(1, seed);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int t = queue[head];
      for (int k = 0; k < 3; ++k) {
        const Link& link = links[3 * t + k];
        if (link.other < 0) continue;
        const int wanted = flip[t] ^ (link.same_dir ? 1 : 0);
        if (flip[link.other] == -1) {
          flip[link.other] = wanted;
          queue.push_back(link.other);
        } else if (flip[link.other] != wanted) {
          fail(labels.where + ": " + edge_name(labels, link.edge->lo, link.edge->hi) +
               " is non-orientable: no consistent orientation of its component (e.g. a Moebius "
               "strip) exists across it (" +
               triangle_ref(labels, t) + " and " + triangle_ref(labels, link.other) + ")");
        }
      }
    }
  }
  for (int t = 0; t < count; ++t) {
    if (flip[t] == 1) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
  }
}

void check_manifold(const InputMesh& mesh, const MeshLabels& labels) {
  const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);
  check_edge_use_counts(uses, labels);
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first != 2 || uses[first].forward != uses[first + 1].forward) return;
    const EdgeUse& e = uses[first];
    const int a = e.forward ? e.lo : e.hi;
    const int b = e.forward ? e.hi : e.lo;
    fail(labels.where + ": " + edge_name(labels, e.lo, e.hi) +
         " has inconsistent orientation: both of its triangles (" + triangle_ref(labels, e.tri) +
         " and " + triangle_ref(labels, uses[first + 1].tri) + ") run from vertex " +
         vertex_name(labels, a) + " to " + vertex_name(labels, b));
  });

  // Triangles around each vertex, in compressed rows: around[start[v] .. start[v + 1]).
  const std::size_t n = mesh.positions.size();
  std::vector<int> start(n + 1, 0);
  for (const auto& tri : mesh.triangles) {
    for (int k : tri) ++start[k + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> around(start[n]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k : mesh.triangles[t]) around[fill[k]++] = static_cast<int>(t);
  }
  std::vector<int> fan;
  for (std::size_t v = 0; v < n; ++v) {
    fan.assign(around.begin() + start[v], around.begin() + start[v + 1]);
    const int fans = count_fans(mesh, static_cast<int>(v), fan);
    if (fans > 1) {
      fail(labels.where + ": vertex " + vertex_name(labels, static_cast<int>(v)) +
           " is non-manifold: its triangles form " + std::to_string(fans) +
           " fans that share only this vertex");
    }
  }
}

}  // namespace mesh_detail

void validate_mesh(const InputMesh& mesh, const std::string& where) {
  const mesh_detail::MeshLabels labels{where, {}, {}};
  mesh_detail::check_triangles(mesh, labels);
  mesh_detail::check_float_range(mesh, labels);
  mesh_detail::check_manifold(mesh, labels);
}

}  // namespace crumple
