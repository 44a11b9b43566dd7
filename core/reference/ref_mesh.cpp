#include "reference/ref_mesh.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace crumple::ref {

namespace {
template <class T>
int take(std::vector<T>& items, std::vector<int>& free_list) {
  if (!free_list.empty()) {
    const int id = free_list.back();
    free_list.pop_back();
    items[id] = T{};
    items[id].alive = true;
    return id;
  }
  items.emplace_back();
  items.back().alive = true;
  return int(items.size()) - 1;
}
}  // namespace

int Mesh::new_vertex() { return take(verts, free_verts); }
int Mesh::new_triangle() { return take(tris, free_tris); }

int Mesh::new_edge(int a, int b, double l0) {
  const int e = take(edges, free_edges);
  Edge& E = edges[e];
  E.a = a;
  E.b = b;
  E.l0 = l0;
  E.breakable = true;
  verts[a].edges.push_back(e);
  verts[b].edges.push_back(e);
  return e;
}

void Mesh::free_vertex(int v) {
  verts[v] = Vertex{};
  free_verts.push_back(v);
}

void Mesh::free_edge(int e) {
  for (int end : {edges[e].a, edges[e].b}) {
    auto& list = verts[end].edges;
    list.erase(std::find(list.begin(), list.end(), e));
  }
  edges[e] = Edge{};
  free_edges.push_back(e);
}

void Mesh::free_triangle(int t) {
  tris[t] = Triangle{};
  free_tris.push_back(t);
}

int Mesh::mesh_edge(int a, int b) const {
  for (int e : verts[a].edges) {
    const Edge& E = edges[e];
    if (!E.auxiliary && ((E.a == a && E.b == b) || (E.a == b && E.b == a))) return e;
  }
  return -1;
}

bool Mesh::attach(int t, int a, int b, int c) {
  Triangle& T = tris[t];
  T.v = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const int p = T.v[k], q = T.v[(k + 1) % 3];
    int e = mesh_edge(p, q);
    if (e < 0) e = new_edge(p, q, (verts[p].X - verts[q].X).norm());
    const int side = edges[e].a == p ? 0 : 1;
    if (edges[e].tri[side] >= 0) return false;
    edges[e].tri[side] = t;
    T.e[k] = e;
  }
  return true;
}

void Mesh::detach(int t) {
  for (int e : tris[t].e) {
    if (e < 0) continue;
    for (int& s : edges[e].tri)
      if (s == t) s = -1;
  }
  tris[t].e = {-1, -1, -1};
}

int Mesh::wing(int e, int s) const {
  const int t = edges[e].tri[s];
  if (t < 0) return -1;
  for (int v : tris[t].v)
    if (v != edges[e].a && v != edges[e].b) return v;
  return -1;
}

int Mesh::live_vertices() const {
  return int(std::count_if(verts.begin(), verts.end(), [](const Vertex& v) { return v.alive; }));
}
int Mesh::live_mesh_edges() const {
  return int(std::count_if(edges.begin(), edges.end(),
                           [](const Edge& e) { return e.alive && !e.auxiliary; }));
}
int Mesh::live_triangles() const {
  return int(std::count_if(tris.begin(), tris.end(), [](const Triangle& t) { return t.alive; }));
}

namespace {
/// The parts written one after the other: a check's one-line finding.
template <class... P>
std::string describe(const P&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

// Each live triangle's corners are live and distinct, and its sides live mesh edges that join
// them and link back to it.
std::string check_triangles(const Mesh& m) {
  for (int t = 0; t < int(m.tris.size()); ++t) {
    const Triangle& T = m.tris[t];
    if (!T.alive) continue;
    for (int k = 0; k < 3; ++k) {
      const int p = T.v[k], q = T.v[(k + 1) % 3], e = T.e[k];
      if (p < 0 || p >= int(m.verts.size()) || !m.verts[p].alive)
        return describe("triangle ", t, " uses dead vertex ", p);
      if (p == T.v[(k + 1) % 3] || p == T.v[(k + 2) % 3])
        return describe("triangle ", t, " repeats vertex ", p);
      if (e < 0 || !m.edges[e].alive || m.edges[e].auxiliary)
        return describe("triangle ", t, " side ", k, " has no live mesh edge");
      const Edge& E = m.edges[e];
      const int side = (E.a == p && E.b == q) ? 0 : (E.a == q && E.b == p) ? 1 : -1;
      if (side < 0) return describe("edge ", e, " does not join triangle ", t, "'s side ", k);
      if (E.tri[side] != t) return describe("edge ", e, " does not link back to triangle ", t);
    }
  }
  return {};
}

// Each live edge joins two live vertices that list it once; an auxiliary edge is in no
// triangle; a mesh edge is a side of its triangles, and no two join the same vertices.
std::string check_edges(const Mesh& m) {
  std::set<std::pair<int, int>> pairs;
  for (int e = 0; e < int(m.edges.size()); ++e) {
    const Edge& E = m.edges[e];
    if (!E.alive) continue;
    if (E.a == E.b || !m.verts[E.a].alive || !m.verts[E.b].alive)
      return describe("edge ", e, " has a bad endpoint");
    for (int end : {E.a, E.b}) {
      const auto& l = m.verts[end].edges;
      if (std::count(l.begin(), l.end(), e) != 1)
        return describe("edge ", e, " is not listed once at vertex ", end);
    }
    if (!(E.l0 > 0) || !(E.kappa >= 0)) return describe("edge ", e, " has bad rest length or kappa");
    if (E.auxiliary) {
      if (E.breakable || E.tri[0] >= 0 || E.tri[1] >= 0)
        return describe("auxiliary edge ", e, " is breakable or in a triangle");
      continue;
    }
    if (E.tri[0] < 0 && E.tri[1] < 0) return describe("mesh edge ", e, " is in no triangle");
    for (int s = 0; s < 2; ++s) {
      const int t = E.tri[s];
      if (t < 0) continue;
      if (!m.tris[t].alive) return describe("edge ", e, " links dead triangle ", t);
      const auto& tv = m.tris[t].v;
      bool found = false;
      for (int k = 0; k < 3; ++k)
        found |= m.tris[t].e[k] == e && tv[k] == (s ? E.b : E.a) && tv[(k + 1) % 3] == (s ? E.a : E.b);
      if (!found) return describe("edge ", e, " side ", s, " is not in triangle ", t);
    }
    if (!pairs.insert({std::min(E.a, E.b), std::max(E.a, E.b)}).second)
      return describe("two mesh edges join ", E.a, " and ", E.b);
  }
  return {};
}

// Each live vertex has a positive mass and lists only springs that touch it, one in a triangle;
// the free lists hold only dead ids.
std::string check_vertices(const Mesh& m) {
  for (int v = 0; v < int(m.verts.size()); ++v) {
    const Vertex& V = m.verts[v];
    if (!V.alive) continue;
    if (!(V.m > 0) || !std::isfinite(V.m)) return describe("vertex ", v, " has mass ", V.m);
    bool in_triangle = false;
    for (int e : V.edges) {
      if (e < 0 || e >= int(m.edges.size()) || !m.edges[e].alive || (m.edges[e].a != v && m.edges[e].b != v))
        return describe("vertex ", v, " lists a spring that does not touch it");
      in_triangle |= !m.edges[e].auxiliary;
    }
    if (!in_triangle) return describe("vertex ", v, " is in no triangle");
  }
  for (int f : m.free_verts) if (m.verts[f].alive) return describe("free vertex ", f, " is alive");
  for (int f : m.free_edges) if (m.edges[f].alive) return describe("free edge ", f, " is alive");
  for (int f : m.free_tris) if (m.tris[f].alive) return describe("free triangle ", f, " is alive");
  return {};
}
}  // namespace

std::string Mesh::check() const {
  std::string found = check_triangles(*this);
  if (found.empty()) found = check_edges(*this);
  if (found.empty()) found = check_vertices(*this);
  if (!found.empty()) return found;
  const int chi = live_vertices() - live_mesh_edges() + live_triangles();
  if (chi != euler) return describe("Euler characteristic ", chi, " differs from the input's ", euler);
  return {};
}

}  // namespace crumple::ref
