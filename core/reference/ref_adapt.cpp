// The adaptive mesh of the reference backend: stochastic fracture [Eq 6], the split with mass and
// momentum redistribution [Eq 2-4, 7], and restoration [Eq 10-12] (MODEL.md §4, §5, §7).
#include <algorithm>
#include <cmath>

#include "model/random.h"
#include "reference/reference_sim.h"

namespace crumple::ref {

namespace {
constexpr double kReferenceStep = 1.0 / 60.0;  ///< h_ref: the paper's P is per 1/60 s step

// Triangle t's vertices with `from` replaced by `to`, keeping the rotation.
std::array<int, 3> replaced(const Triangle& t, int from, int to) {
  std::array<int, 3> v = t.v;
  for (int& k : v)
    if (k == from) k = to;
  return v;
}

// True if triangle t is alive and is (a, b, c) up to rotation.
bool is_triangle(const Mesh& m, int t, int a, int b, int c) {
  if (t < 0 || t >= int(m.tris.size()) || !m.tris[t].alive) return false;
  const auto& v = m.tris[t].v;
  for (int k = 0; k < 3; ++k)
    if (v[k] == a && v[(k + 1) % 3] == b && v[(k + 2) % 3] == c) return true;
  return false;
}

// nu of [Eq 7]: the mean of the unit normals of the edge's faces tL and tR (-1: none), or of
// the vertex normals ni and nj where those cancel (zero where both do).
V3 split_direction(const Mesh& m, int tL, int tR, const V3& ni, const V3& nj) {
  V3 nu = V3::Zero();
  for (int t : {tL, tR}) {
    if (t < 0) continue;
    const auto& v = m.tris[t].v;
    const V3 w = (m.verts[v[1]].x - m.verts[v[0]].x).cross(m.verts[v[2]].x - m.verts[v[0]].x);
    if (w.norm() > 0) nu += w.normalized();
  }
  if (!(nu.norm() > 1e-12)) nu = ni + nj;
  if (nu.norm() > 1e-12) nu.normalize(); else nu.setZero();
  return nu;
}

// [Eq 3]: each vertex of N = rec.k (-1: none) gives up part of its mass, kept in rec.delta and
// rec.dm; [Eq 4]: mn and pn are the new vertex's mass and momentum, their sums.
void split_masses(Mesh& m, SplitRecord& rec, const V3& Xn, double varphi, double& mn, V3& pn) {
  double dsum = 0;
  for (int q = 0; q < 4; ++q)
    if (rec.k[q] >= 0) dsum += (m.verts[rec.k[q]].X - Xn).norm();
  for (int q = 0; q < 4; ++q) {
    if (rec.k[q] < 0) continue;
    Vertex& K = m.verts[rec.k[q]];
    rec.delta[q] = (K.X - Xn).norm() / dsum;
    const double m_new = 0.5 * (std::pow(rec.delta[q], 1.0 / varphi) + 1.0) * K.m;
    rec.dm[q] = K.m - m_new;
    K.m = m_new;
    mn += rec.dm[q];
    pn += rec.dm[q] * K.v;
  }
}

// The split's topology around the new vertex rec.n: (i,j,l), (j,i,r) -> (i,n,l), (n,j,l),
// (j,n,r), (n,i,r); edge e becomes auxiliary at its current length lt. Fills rec.e and rec.t;
// false if a triangle could not be attached.
bool split_topology(Mesh& m, int e, SplitRecord& rec, double lt) {
  const int i = rec.k[0], j = rec.k[1], l = rec.k[2], r = rec.k[3], nv = rec.n;
  const int tL = m.edges[e].tri[0], tR = m.edges[e].tri[1];
  const double l0 = rec.l0;
  const V3 Xn = m.verts[nv].X;
  for (int t : {tL, tR})
    if (t >= 0) m.detach(t);
  Edge& E = m.edges[e];
  E.auxiliary = true;
  E.breakable = false;
  E.tri = {-1, -1};
  E.l0 = lt;  // holds the crease ("maintains the damage")
  rec.e[0] = m.new_edge(i, nv, l0 / 2);
  rec.e[1] = m.new_edge(nv, j, l0 / 2);
  if (l >= 0) rec.e[2] = m.new_edge(l, nv, (m.verts[l].X - Xn).norm());
  if (r >= 0) rec.e[3] = m.new_edge(nv, r, (m.verts[r].X - Xn).norm());
  if (tL >= 0) rec.t[0] = tL, rec.t[1] = m.new_triangle();
  if (tR >= 0) rec.t[2] = tR, rec.t[3] = m.new_triangle();
  bool ok = true;
  if (tL >= 0) {
    const auto v = replaced(m.tris[tL], j, nv);
    ok &= m.attach(tL, v[0], v[1], v[2]);
    ok &= m.attach(rec.t[1], nv, j, l);
  }
  if (tR >= 0) {
    const auto v = replaced(m.tris[tR], i, nv);
    ok &= m.attach(tR, v[0], v[1], v[2]);
    ok &= m.attach(rec.t[3], nv, i, r);
  }
  return ok;
}
}  // namespace

void ReferenceSimulator::update_kappa(int v) {
  for (int e : mesh_.verts[v].edges) {
    Edge& E = mesh_.edges[e];
    E.kappa = params_.kappa * (mesh_.verts[E.a].m + mesh_.verts[E.b].m);  // [Eq 5]
  }
}

// [Eq 6] P = 1/4 c (1 - phi n_ij)(1 + phi n_rl), c = 1 - lt/l0, made per pass as
// P_step = 1 - (1 - P)^(t / h_ref), t the pass's interval (a step, or a frame: D27). Zero for
// edges that cannot break.
double ReferenceSimulator::break_probability(int e, const std::vector<V3>& n) const {
  const Edge& E = mesh_.edges[e];
  if (!E.alive || E.auxiliary || !E.breakable || E.l0 < scene_.floor_length) return 0;
  const double lt = (mesh_.verts[E.a].x - mesh_.verts[E.b].x).norm();
  if (!(lt < E.l0)) return 0;
  const double c = 1.0 - lt / E.l0;
  const int l = mesh_.wing(e, 0), r = mesh_.wing(e, 1);
  const double n_ij = n[E.a].dot(n[E.b]);
  const double n_rl = (l >= 0 && r >= 0) ? n[r].dot(n[l]) : 1.0;
  const double P = std::clamp(0.25 * c * (1 - params_.phi * n_ij) * (1 + params_.phi * n_rl), 0.0, 1.0);
  return 1.0 - std::pow(1.0 - P, params_.adapt_interval() / kReferenceStep);
}

// [Eq 10]'s angle test quantity (1 - n_rl)/2 of auxiliary edge e's crease (wings l, r of its
// split; n_rl = 1 for a boundary edge, D6).
double ReferenceSimulator::restoration_angle(int e, const std::vector<V3>& n) const {
  const int l = mesh_.edges[e].split.k[2], r = mesh_.edges[e].split.k[3];
  const double n_rl = (l >= 0 && r >= 0) ? n[r].dot(n[l]) : 1.0;
  return (1.0 - n_rl) / 2.0;
}

bool ReferenceSimulator::split_edge(int e, const std::vector<V3>& n, double flat_draw) {
  Edge& E0 = mesh_.edges[e];
  if (!E0.alive || E0.auxiliary || !E0.breakable) return false;
  const int i = E0.a, j = E0.b, tL = E0.tri[0], tR = E0.tri[1];
  const int l = mesh_.wing(e, 0), r = mesh_.wing(e, 1);
  const V3 xi = mesh_.verts[i].x, xj = mesh_.verts[j].x;
  const double lt = (xi - xj).norm(), l0 = E0.l0;

  // [Eq 7] x_n = (x_i + x_j)/2 + s theta nu, theta = (psi/2) sqrt(l0^2 - lt^2).
  const V3 nu = split_direction(mesh_, tL, tR, n[i], n[j]);
  const double theta = 0.5 * params_.psi * std::sqrt(std::max(0.0, l0 * l0 - lt * lt));
  const double curl = (n[j] - n[i]).dot(xj - xi);
  const double s = std::abs(curl) <= 1e-6 * lt ? (flat_draw < 0.5 ? -1.0 : 1.0) : (curl > 0 ? 1.0 : -1.0);

  // [Eq 3] masses of N = {i, j, l, r}; [Eq 4] momentum of the new vertex.
  const V3 Xn = 0.5 * (mesh_.verts[i].X + mesh_.verts[j].X);
  SplitRecord rec;
  rec.k = {i, j, l, r};
  rec.l0 = l0;
  double mn = 0;
  V3 pn = V3::Zero();
  split_masses(mesh_, rec, Xn, params_.varphi, mn, pn);

  const int nv = mesh_.new_vertex();
  Vertex& N = mesh_.verts[nv];
  N.X = Xn;
  N.x = 0.5 * (xi + xj) + s * theta * nu;
  N.m = mn;
  N.v = pn / mn;
  rec.n = nv;
  const bool ok = split_topology(mesh_, e, rec, lt);
  mesh_.edges[e].split = rec;
  for (int k : rec.k)
    if (k >= 0) update_kappa(k);
  update_kappa(nv);
  return ok;
}

bool ReferenceSimulator::can_restore(int e) const {
  if (e < 0 || e >= int(mesh_.edges.size())) return false;
  const Edge& E = mesh_.edges[e];
  if (!E.alive || !E.auxiliary || E.split.n < 0) return false;
  const SplitRecord& s = E.split;
  const int i = s.k[0], j = s.k[1], l = s.k[2], r = s.k[3], n = s.n;
  if (!mesh_.verts[n].alive) return false;
  // [Eq 10]: the four new edges are still unbroken mesh edges ...
  const int ends[4][2] = {{i, n}, {n, j}, {l, n}, {n, r}};
  int expected = 0;
  for (int q = 0; q < 4; ++q) {
    if (s.k[q] < 0) continue;
    const int id = s.e[q];
    const Edge& F = mesh_.edges[id];
    if (!F.alive || !F.breakable || F.auxiliary) return false;
    if (!((F.a == ends[q][0] && F.b == ends[q][1]) || (F.a == ends[q][1] && F.b == ends[q][0]))) return false;
    ++expected;
  }
  // ... and (our addition) n has exactly those edges and the split's triangles are intact.
  if (int(mesh_.verts[n].edges.size()) != expected) return false;
  if (l >= 0 && !(is_triangle(mesh_, s.t[0], i, n, l) && is_triangle(mesh_, s.t[1], n, j, l))) return false;
  if (r >= 0 && !(is_triangle(mesh_, s.t[2], j, n, r) && is_triangle(mesh_, s.t[3], n, i, r))) return false;
  return true;
}

void ReferenceSimulator::restore_edge(int e) {
  const SplitRecord s = mesh_.edges[e].split;
  const int i = s.k[0], j = s.k[1], n = s.n;
  const double mn = mesh_.verts[n].m;
  const V3 vn = mesh_.verts[n].v;
  if (params_.restore == RestoreForm::Exact) {
    // Give m_n back in the proportions taken; merge momentum inelastically: exact conservation.
    double dsum = 0;
    for (int q = 0; q < 4; ++q)
      if (s.k[q] >= 0) dsum += s.dm[q];
    for (int q = 0; q < 4; ++q) {
      if (s.k[q] < 0) continue;
      Vertex& K = mesh_.verts[s.k[q]];
      const double m_new = K.m + mn * s.dm[q] / dsum;
      K.v = (K.m * K.v + (m_new - K.m) * vn) / m_new;
      K.m = m_new;
    }
  } else {
    double msum = 0;
    for (int q = 0; q < 4; ++q) {
      if (s.k[q] < 0) continue;
      Vertex& K = mesh_.verts[s.k[q]];
      K.m = 2.0 * K.m / (std::pow(s.delta[q], 1.0 / params_.varphi) + 1.0);  // [Eq 11]
      msum += K.m;
    }
    for (int q = 0; q < 4; ++q)
      if (s.k[q] >= 0) mesh_.verts[s.k[q]].v += mn * vn / msum;  // [Eq 12]
  }

  for (int t : s.t)
    if (t >= 0) mesh_.detach(t);
  for (int id : s.e)
    if (id >= 0) mesh_.free_edge(id);
  if (s.t[1] >= 0) mesh_.free_triangle(s.t[1]);
  if (s.t[3] >= 0) mesh_.free_triangle(s.t[3]);
  mesh_.free_vertex(n);
  Edge& E = mesh_.edges[e];
  E.auxiliary = false;
  E.breakable = true;
  E.l0 = s.l0;
  E.split = SplitRecord{};
  if (s.t[0] >= 0) {
    const auto v = replaced(mesh_.tris[s.t[0]], n, j);
    mesh_.attach(s.t[0], v[0], v[1], v[2]);
  }
  if (s.t[2] >= 0) {
    const auto v = replaced(mesh_.tris[s.t[2]], n, i);
    mesh_.attach(s.t[2], v[0], v[1], v[2]);
  }
  for (int k : s.k)
    if (k >= 0) update_kappa(k);
}

bool ReferenceSimulator::split(int e) {
  if (e < 0 || e >= int(mesh_.edges.size())) return false;
  return split_edge(e, vertex_normals(), uniform(params_.seed, steps_, std::uint32_t(e), Draw::FlatSign));
}

bool ReferenceSimulator::restore(int e) {
  if (!can_restore(e)) return false;
  restore_edge(e);
  return true;
}

std::vector<Decision> ReferenceSimulator::decide() const {
  std::vector<Decision> out(mesh_.edges.size());
  const std::vector<V3> n = vertex_normals();
  const double budget = params_.budget_factor(mesh_.live_vertices());  // D22
  for (int e = 0; e < int(mesh_.edges.size()); ++e) {
    const Edge& E = mesh_.edges[e];
    if (!E.alive) continue;
    if (params_.fracture && !E.auxiliary) {
      const double P = budget * break_probability(e, n);
      const double u = uniform(params_.seed, steps_, std::uint32_t(e), Draw::Fracture);
      out[e].margin = P - u;
      if (P > 0 && u < P) out[e].kind = 1;
    }
    if (params_.restoration && E.auxiliary && E.split.n >= 0) {
      const double bent = restoration_angle(e, n);
      if (bent >= budget * params_.epsilon) out[e].kind = 2;
      out[e].margin = bent - budget * params_.epsilon;
    }
  }
  return out;
}

StepEvents ReferenceSimulator::adapt() {
  StepEvents ev;
  if (!params_.fracture && !params_.restoration) return ev;
  ++pass_;
  const std::vector<V3> n = vertex_normals();
  std::vector<int> splits, restores;
  // The budget's shaping (D22): P_step and epsilon scaled by one factor of the pass's start.
  const double budget = params_.budget_factor(mesh_.live_vertices());
  for (int e = 0; e < int(mesh_.edges.size()); ++e) {
    const Edge& E = mesh_.edges[e];
    if (!E.alive) continue;
    if (params_.fracture && !E.auxiliary) {
      const double P = budget * break_probability(e, n);
      if (P > 0 && uniform(params_.seed, steps_, std::uint32_t(e), Draw::Fracture) < P) splits.push_back(e);
    }
    if (params_.restoration && E.auxiliary && E.split.n >= 0) {
      if (restoration_angle(e, n) >= budget * params_.epsilon) restores.push_back(e);  // [Eq 10]
    }
  }
  if (params_.max_vertices > 0) {  // the hard guard: a split adds one vertex, the budget's first candidates only
    splits.resize(std::min<std::size_t>(splits.size(), std::max(0, params_.max_vertices - mesh_.live_vertices())));
  }
  auto touched = [&](int t) {
    return t >= 0 && t < int(tri_stamp_.size()) && tri_stamp_[t] == pass_;
  };
  auto stamp = [&](int t) {
    if (t < 0) return;
    if (t >= int(tri_stamp_.size())) tri_stamp_.resize(t + 1, 0);
    tri_stamp_[t] = pass_;
  };
  for (int e : splits) {
    const Edge& E = mesh_.edges[e];
    if (touched(E.tri[0]) || touched(E.tri[1])) continue;
    if (!split_edge(e, n, uniform(params_.seed, steps_, std::uint32_t(e), Draw::FlatSign))) continue;
    for (int t : mesh_.edges[e].split.t) stamp(t);
    ++ev.splits;
    ev.split_edges.push_back(e);
  }
  for (int e : restores) {
    const SplitRecord& s = mesh_.edges[e].split;
    if (std::any_of(s.t.begin(), s.t.end(), touched) || !can_restore(e)) continue;
    const auto t = s.t;
    restore_edge(e);
    for (int k : t) stamp(k);
    ++ev.restores;
    ev.restored_edges.push_back(e);
  }
  return ev;
}

}  // namespace crumple::ref
