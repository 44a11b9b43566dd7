// One event's edits in the fast backend (MODEL.md §5, §7): a split of an edge [Eq 3, 4, 7] and
// the restoration of an auxiliary edge [Eq 10-12], with the same id policy as the reference
// backend. Mass and momentum bookkeeping is done in double and stored in float. Each edit reads
// and writes only its own vertices, their lists and the edges and triangles among them, so that
// split_rounds.cpp and restore_waves.cpp can apply events of disjoint vertices in parallel.
#include <algorithm>
#include <cmath>

#include "fast/fast_sim.h"
#include "model/random.h"

namespace crumple::fast {

namespace {
struct D3 {
  double x = 0, y = 0, z = 0;
};
double norm(const D3& a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// delta^(1/varphi) of [Eq 3] and [Eq 11]. The default varphi = 2 is a square root: exactly
// rounded, where pow is within about half an ulp and costs some hundred instructions a call.
double root_of_delta(double delta, double varphi) { return varphi == 2.0 ? std::sqrt(delta) : std::pow(delta, 1.0 / varphi); }

// Triangle t's side out of corner v (its edge from v to the next corner), or -1.
int side_from(const Triangles& T, int t, int v) {
  const Face& f = T[t];
  for (int k = 0; k < 3; ++k)
    if (f.v[k] == v) return f.e[k];
  return -1;
}

// Triangle t with corner `from` moved to `to`, keeping the rotation: the side into the corner
// becomes edge `in`, the side out of it edge `out`, the third side stays. Read before detach(t).
Face moved_corner(const Triangles& T, int t, int from, int to, int in, int out) {
  Face f = T[t];
  for (int k = 0; k < 3; ++k)
    if (f.v[k] == from) f.v[k] = to, f.e[k] = out, f.e[(k + 2) % 3] = in;
  return f;
}

// A split's topology (MODEL.md §5): e_ij becomes an auxiliary spring holding the crease at its
// current length `lt`, with the crease's wings in its wing slots (for [Eq 10]); n joins i, j, l,
// r by new mesh edges of rest lengths `rest`; (i,j,l) and (j,i,r) become four triangles. Fills
// rec.t and stores rec; false if a triangle does not link.
bool relink_split(Topology& m, const SplitPlan& plan, SplitRecord& rec, float lt, const std::array<float, 4>& rest) {
  const int e = plan.e, n = plan.n;
  const int i = m.E[e].a, j = m.E[e].b, l = m.E[e].wl, r = m.E[e].wr, tL = m.E[e].tri0, tR = m.E[e].tri1;
  // The four triangles' sides, read before detach clears them.
  const std::array<int, 4>& en = plan.edges;  // e_in, e_nj, e_ln, e_nr
  Face faces[4];
  if (tL >= 0) {  // (i,j,l) -> (i,n,l) and (n,j,l)
    faces[0] = moved_corner(m.T, tL, j, n, en[0], en[2]);
    faces[1] = {{n, j, l}, {en[1], side_from(m.T, tL, j), en[2]}};
  }
  if (tR >= 0) {  // (j,i,r) -> (j,n,r) and (n,i,r)
    faces[2] = moved_corner(m.T, tR, i, n, en[1], en[3]);
    faces[3] = {{n, i, r}, {en[0], side_from(m.T, tR, i), en[3]}};
  }
  for (int t : {tL, tR})
    if (t >= 0) m.detach(t);
  m.E[e].flags = kAlive;
  m.E[e].wl = l;
  m.E[e].wr = r;
  m.E[e].l0 = lt;
  m.init_edge(en[0], i, n, rest[0]);
  m.init_edge(en[1], n, j, rest[1]);
  if (l >= 0) m.init_edge(en[2], l, n, rest[2]);
  if (r >= 0) m.init_edge(en[3], n, r, rest[3]);
  if (tL >= 0) rec.t[0] = tL, rec.t[1] = plan.tris[0], m.init_triangle(plan.tris[0]);
  if (tR >= 0) rec.t[2] = tR, rec.t[3] = plan.tris[1], m.init_triangle(plan.tris[1]);
  bool ok = true;
  for (int q = 0; q < 4; ++q)
    if (rec.t[q] >= 0) ok &= m.attach(rec.t[q], faces[q]);
  m.records[plan.record] = rec;
  m.E[e].record = plan.record;
  return ok;
}

bool is_triangle(const Triangles& T, int t, int a, int b, int c) {
  if (t < 0 || t >= T.size() || !T.alive[t]) return false;
  const auto v = T.corners(t);
  for (int k = 0; k < 3; ++k)
    if (v[k] == a && v[(k + 1) % 3] == b && v[(k + 2) % 3] == c) return true;
  return false;
}
}  // namespace

SplitCandidate FastSimulator::split_candidate(int e) const {
  const Edges& E = topo_.E;
  SplitCandidate c;
  if (E[e].flags != (kAlive | kMesh | kBreakable)) return c;
  c.e = e;
  c.tris = {E[e].tri0, E[e].tri1};
  c.ends = {E[e].a, E[e].b, E[e].wl, E[e].wr};
  c.flat_draw = float(uniform(params_.seed, steps_, std::uint32_t(E.lid[e]), Draw::FlatSign));
  return c;
}

SplitPlan FastSimulator::plan_split(const SplitCandidate& c) {
  Topology& m = topo_;
  SplitPlan p;
  if (c.e < 0) return p;
  p.e = c.e;
  p.flat_draw = c.flat_draw;
  p.ends = c.ends;
  // The order in which a split allocates (the id policy of sim/simulator.h).
  p.n = m.take_vertex();
  p.edges[0] = m.take_edge();
  p.edges[1] = m.take_edge();
  if (c.ends[2] >= 0) p.edges[2] = m.take_edge();
  if (c.ends[3] >= 0) p.edges[3] = m.take_edge();
  if (c.tris[0] >= 0) p.tris[0] = m.take_triangle();
  if (c.tris[1] >= 0) p.tris[1] = m.take_triangle();
  p.record = m.take_record();
  return p;
}

bool FastSimulator::split_edge(int e) {
  const SplitPlan p = plan_split(split_candidate(e));
  if (p.e < 0) return false;
  topo_.fit();
  return apply_split(p);
}

bool FastSimulator::apply_split(const SplitPlan& plan) {
  Topology& m = topo_;
  Vertices& V = m.V;
  const int e = plan.e;
  const float flat_draw = plan.flat_draw;
  const int i = m.E[e].a, j = m.E[e].b, tL = m.E[e].tri0, tR = m.E[e].tri1;
  const int l = m.E[e].wl, r = m.E[e].wr;
  const Float4 pi = V.xm[i], pj = V.xm[j];
  const D3 xi{pi.x, pi.y, pi.z}, xj{pj.x, pj.y, pj.z};
  const D3 d{xj.x - xi.x, xj.y - xi.y, xj.z - xi.z};
  const double lt = norm(d), l0 = m.E[e].l0;

  // [Eq 7] x_n = (x_i + x_j)/2 + s theta nu; nu from the adjacent face normals.
  D3 nu;
  for (int t : {tL, tR}) {
    if (t < 0) continue;
    const D3 w{m.T.area[t].x, m.T.area[t].y, m.T.area[t].z};
    const double len = norm(w);
    if (len > 0) nu = {nu.x + w.x / len, nu.y + w.y / len, nu.z + w.z / len};
  }
  const Float4 ni = V.nr[i], nj = V.nr[j];
  if (!(norm(nu) > 1e-12)) nu = {double(ni.x) + nj.x, double(ni.y) + nj.y, double(ni.z) + nj.z};
  const double nlen = norm(nu);
  nu = nlen > 1e-12 ? D3{nu.x / nlen, nu.y / nlen, nu.z / nlen} : D3{};
  const double theta = 0.5 * params_.psi * std::sqrt(std::max(0.0, l0 * l0 - lt * lt));
  const double curl = (double(nj.x) - ni.x) * d.x + (double(nj.y) - ni.y) * d.y + (double(nj.z) - ni.z) * d.z;
  const double s = std::abs(curl) <= 1e-6 * lt ? (flat_draw < 0.5f ? -1.0 : 1.0) : (curl > 0 ? 1.0 : -1.0);

  // [Eq 3] masses of N = {i, j, l, r}; [Eq 4] the new vertex's momentum.
  const Float4 Xi = V.rest[i], Xj = V.rest[j];
  const D3 Xn{0.5 * (double(Xi.x) + Xj.x), 0.5 * (double(Xi.y) + Xj.y), 0.5 * (double(Xi.z) + Xj.z)};
  SplitRecord rec;
  rec.k = {i, j, l, r};
  rec.l0 = l0;
  std::array<double, 4> dist{};  // |X_k - X_n| of each k in N
  double dsum = 0;
  for (int q = 0; q < 4; ++q) {
    if (rec.k[q] < 0) continue;
    const Float4 Xk = V.rest[rec.k[q]];
    dist[q] = norm({Xk.x - Xn.x, Xk.y - Xn.y, Xk.z - Xn.z});
    dsum += dist[q];
  }
  double mn = 0;
  D3 pn;
  for (int q = 0; q < 4; ++q) {
    const int k = rec.k[q];
    if (k < 0) continue;
    rec.delta[q] = dist[q] / dsum;
    const float m_new = float(0.5 * (root_of_delta(rec.delta[q], params_.varphi) + 1.0) * V.mass(k));
    rec.dm[q] = double(V.mass(k) - m_new);  // exact in float (Sterbenz: m_new >= m_k / 2)
    V.set_mass(k, m_new);
    mn += rec.dm[q];
    const Float4 vk = V.vm[k];
    pn = {pn.x + rec.dm[q] * vk.x, pn.y + rec.dm[q] * vk.y, pn.z + rec.dm[q] * vk.z};
  }

  const int n = plan.n;
  m.init_vertex(n);
  V.rest[n] = Float4{float(Xn.x), float(Xn.y), float(Xn.z), 0.0f};
  V.xm[n] = Float4{float(0.5 * (xi.x + xj.x) + s * theta * nu.x), float(0.5 * (xi.y + xj.y) + s * theta * nu.y),
                   float(0.5 * (xi.z + xj.z) + s * theta * nu.z), float(mn)};
  V.vm[n] = Float4{float(pn.x / mn), float(pn.y / mn), float(pn.z / mn), float(mn)};
  V.nr[n] = Float4{float(nu.x), float(nu.y), float(nu.z), 0.0f};
  rec.n = n;
  rec.e = plan.edges;
  const float lt_f = float(lt);
  const std::array<float, 4> rest{float(l0 / 2), float(l0 / 2), float(dist[2]), float(dist[3])};
  return relink_split(m, plan, rec, lt_f, rest);
}

bool FastSimulator::can_restore(int e) const {
  const Topology& m = topo_;
  if (e < 0 || e >= m.E.size() || m.E[e].flags != kAlive || m.E[e].record < 0) return false;
  const SplitRecord& s = m.records[m.E[e].record];
  const int i = s.k[0], j = s.k[1], l = s.k[2], r = s.k[3], n = s.n;
  if (!(m.V.mass(n) > 0)) return false;
  const int ends[4][2] = {{i, n}, {n, j}, {l, n}, {n, r}};
  int expected = 0;
  for (int q = 0; q < 4; ++q) {
    if (s.k[q] < 0) continue;
    const int id = s.e[q];
    if (m.E[id].flags != (kAlive | kMesh | kBreakable)) return false;  // [Eq 10]
    const int a = m.E[id].a, b = m.E[id].b;
    if (!((a == ends[q][0] && b == ends[q][1]) || (a == ends[q][1] && b == ends[q][0]))) return false;
    ++expected;
  }
  if (m.V.spring_list[n].count != expected) return false;  // n still has exactly its own edges
  if (l >= 0 && !(is_triangle(m.T, s.t[0], i, n, l) && is_triangle(m.T, s.t[1], n, j, l))) return false;
  if (r >= 0 && !(is_triangle(m.T, s.t[2], j, n, r) && is_triangle(m.T, s.t[3], n, i, r))) return false;
  return true;
}

void FastSimulator::restore_edge(int e) { topo_.free_ids(restore_edge_local(e)); }

Freed FastSimulator::restore_edge_local(int e) {
  Topology& m = topo_;
  Vertices& V = m.V;
  const int rid = m.E[e].record;
  const SplitRecord s = m.records[rid];
  const int i = s.k[0], j = s.k[1], n = s.n;
  const Float4 row_n = V.vm[n];
  const double mn = row_n.w;
  const D3 vn{row_n.x, row_n.y, row_n.z};
  if (params_.restore == RestoreForm::Exact) {
    double dsum = 0;
    for (int q = 0; q < 4; ++q)
      if (s.k[q] >= 0) dsum += s.dm[q];
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      const Float4 vk = V.vm[k];
      const double mk = vk.w, m_new = mk + mn * s.dm[q] / dsum;
      V.vm[k] = Float4{float((mk * vk.x + (m_new - mk) * vn.x) / m_new), float((mk * vk.y + (m_new - mk) * vn.y) / m_new),
                       float((mk * vk.z + (m_new - mk) * vn.z) / m_new), float(m_new)};
      V.xm[k].w = float(m_new);
    }
  } else {
    double msum = 0;
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      V.set_mass(k, float(2.0 * V.mass(k) / (root_of_delta(s.delta[q], params_.varphi) + 1.0)));  // [Eq 11]
      msum += V.mass(k);
    }
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      Float4& vk = V.vm[k];
      vk.x = float(vk.x + mn * vn.x / msum);  // [Eq 12]
      vk.y = float(vk.y + mn * vn.y / msum);
      vk.z = float(vk.z + mn * vn.z / msum);
    }
  }
  // (i,n,l) -> (i,j,l) and (j,n,r) -> (j,i,r), their sides read before detach clears them.
  Face faces[2];
  if (s.t[0] >= 0) faces[0] = moved_corner(m.T, s.t[0], n, j, e, side_from(m.T, s.t[1], j));
  if (s.t[2] >= 0) faces[1] = moved_corner(m.T, s.t[2], n, i, e, side_from(m.T, s.t[3], i));
  // n goes with its four triangles and edges: its lists are dropped whole here, so that the
  // detaches and releases below erase their entries only at the other corners and ends.
  V.spring_list[n].count = V.tri_list[n].count = 0;
  for (int t : s.t)
    if (t >= 0) m.detach(t);
  Freed freed;
  for (int q = 0; q < 4; ++q)
    if (s.e[q] >= 0) m.release_edge(s.e[q]), freed.edges[q] = s.e[q];
  if (s.t[1] >= 0) m.release_triangle(s.t[1]), freed.tris[0] = s.t[1];
  if (s.t[3] >= 0) m.release_triangle(s.t[3]), freed.tris[1] = s.t[3];
  m.release_vertex(n);
  freed.vertex = n;
  freed.record = rid;
  m.E[e].flags = kAlive | kMesh | kBreakable;
  m.E[e].l0 = float(s.l0);
  m.E[e].record = -1;
  m.E[e].wl = m.E[e].wr = -1;  // attach below links its triangles' wings
  if (s.t[0] >= 0) m.attach(s.t[0], faces[0]);
  if (s.t[2] >= 0) m.attach(s.t[2], faces[1]);
  return freed;
}

}  // namespace crumple::fast
