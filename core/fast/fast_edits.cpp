// One event's edits in the fast backend (MODEL.md §5, §7): a split of an edge [Eq 3, 4, 7] and
// the restoration of an auxiliary edge [Eq 10-12], with the same id policy as the reference
// backend. Mass and momentum bookkeeping is done in double and stored in float. Each edit reads
// and writes only its own vertices, their lists and the edges and triangles among them, so that
// split_rounds.cpp and restore_waves.cpp can apply events of disjoint vertices in parallel.
#include <algorithm>
#include <cmath>

#include "fast/fast_sim.h"
#include "fast/kernels.h"
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

// nu of [Eq 7]: the mean of the adjacent faces' unit normals, or of the vertex normals of i and
// j where those cancel (0 where both do).
D3 split_direction(const Triangles& T, int tL, int tR, Float4 ni, Float4 nj) {
  D3 nu;
  for (int t : {tL, tR}) {
    if (t < 0) continue;
    const D3 w{T.area[t].x, T.area[t].y, T.area[t].z};
    const double len = norm(w);
    if (len > 0) nu = {nu.x + w.x / len, nu.y + w.y / len, nu.z + w.z / len};
  }
  if (!(norm(nu) > 1e-12)) nu = {double(ni.x) + nj.x, double(ni.y) + nj.y, double(ni.z) + nj.z};
  const double nlen = norm(nu);
  return nlen > 1e-12 ? D3{nu.x / nlen, nu.y / nlen, nu.z / nlen} : D3{};
}

// What a split takes from the vertices of N = rec.k: [Eq 3] each gives up part of its mass
// (kept in rec.delta and rec.dm for the restore), and the new vertex gets the sum with its
// momentum [Eq 4]. dist holds |X_k - X_n| of each k in N.
struct SplitMasses {
  std::array<double, 4> dist{};
  double mn = 0;
  D3 pn;
};
SplitMasses split_masses(Vertices& V, SplitRecord& rec, const D3& Xn, double varphi) {
  SplitMasses out;
  double dsum = 0;
  for (int q = 0; q < 4; ++q) {
    if (rec.k[q] < 0) continue;
    const Float4 Xk = V.rest[rec.k[q]];
    out.dist[q] = norm({Xk.x - Xn.x, Xk.y - Xn.y, Xk.z - Xn.z});
    dsum += out.dist[q];
  }
  for (int q = 0; q < 4; ++q) {
    const int k = rec.k[q];
    if (k < 0) continue;
    rec.delta[q] = out.dist[q] / dsum;
    const float m_new = float(0.5 * (root_of_delta(rec.delta[q], varphi) + 1.0) * V.mass(k));
    rec.dm[q] = double(V.mass(k) - m_new);  // exact in float (Sterbenz: m_new >= m_k / 2)
    V.set_mass(k, m_new);
    out.mn += rec.dm[q];
    const Float4 vk = V.vm[k];
    out.pn = {out.pn.x + rec.dm[q] * vk.x, out.pn.y + rec.dm[q] * vk.y, out.pn.z + rec.dm[q] * vk.z};
  }
  return out;
}

// Corner of v in triangle t (0, 1 or 2; t has v as a corner).
int corner_of(const Triangles& T, int t, int v) {
  const Face& f = T[t];
  return f.v[0] == v ? 0 : f.v[1] == v ? 1 : 2;
}

// Points the link that edge s keeps to triangle `from` (its tri0 or tri1) at triangle `to`, whose
// corner off s is `wing`.
void relink_side(Edges& E, int s, int from, int to, int wing) {
  EdgeRecord& r = E[s];
  if (r.tri0 == from) r.tri0 = to, r.wl = wing;
  else r.tri1 = to, r.wr = wing;
}

// The links of a new edge: its triangle traversing a->b with that triangle's third corner, the
// same for b->a (-1 where a triangle does not exist).
void link_edge(Edges& E, int e, int t0, int w0, int t1, int w1) {
  EdgeRecord& r = E[e];
  r.tri0 = t0, r.wl = t0 >= 0 ? w0 : -1;
  r.tri1 = t1, r.wr = t1 >= 0 ? w1 : -1;
}

// One wing of a split: triangle t = (stay, moved, wing), in its rotation, becomes (stay, n, wing)
// in its slot and tn = (n, moved, wing) is new; e_stay joins stay and n, e_moved n and moved,
// e_wing the wing and n (new edges, listed). Each link is written once, where it changes: t
// keeps its entries at stay and wing with a new opposite edge, its entry at moved becomes tn's
// in place, and the wing appends tn (a detach and an attach of t and tn would erase three
// entries and append six).
void split_wing(Topology& m, int t, int tn, int n, int moved, int e_stay, int e_moved, int e_wing) {
  Edges& E = m.E;
  Face& f = m.T[t];
  const int km = corner_of(m.T, t, moved), ks = (km + 2) % 3, kw = (km + 1) % 3;
  const int stay = f.v[ks], wing = f.v[kw], s_mw = f.e[km], s_ws = f.e[kw];
  if (E[e_wing].a == n) link_edge(E, e_wing, t, stay, tn, moved);  // t runs n -> wing, tn back
  else link_edge(E, e_wing, tn, moved, t, stay);
  relink_side(E, s_mw, t, tn, n);
  relink_side(E, s_ws, t, t, n);
  f.v[km] = n, f.e[km] = e_wing, f.e[ks] = e_stay;
  m.init_triangle(tn);
  m.T[tn] = Face{{n, moved, wing}, {e_moved, s_mw, e_wing}};
  m.relist_tri(stay, (t << 2) | ks, (t << 2) | ks, e_wing);
  m.relist_tri(wing, (t << 2) | kw, (t << 2) | kw, e_stay);
  m.relist_tri(moved, (t << 2) | km, (tn << 2) | 1, e_wing);
  m.list_tri(wing, (tn << 2) | 2, e_moved);
}

// A split's topology (MODEL.md §5): e_ij becomes an auxiliary spring holding the crease at its
// current length `lt`, with the crease's wings in its wing slots (for [Eq 10]); n joins i, j, l,
// r by new mesh edges of rest lengths `rest`; (i,j,l) and (j,i,r) become (i,n,l), (n,j,l),
// (j,n,r) and (n,i,r). Fills rec.t and stores rec.
void relink_split(Topology& m, const SplitPlan& plan, SplitRecord& rec, float lt, const std::array<float, 4>& rest) {
  Edges& E = m.E;
  const int e = plan.e, n = plan.n;
  const int i = E[e].a, j = E[e].b, l = E[e].wl, r = E[e].wr, tL = E[e].tri0, tR = E[e].tri1;
  const std::array<int, 4>& en = plan.edges;       // e_in, e_nj, e_ln, e_nr
  const int t1 = plan.tris[0], t3 = plan.tris[1];  // (n,j,l), (n,i,r)
  E[e].flags = kAlive;
  E[e].tri0 = E[e].tri1 = -1;
  E[e].l0 = lt;
  E[e].record = plan.record;  // wl, wr keep l and r
  m.init_edge(en[0], i, n, rest[0]);
  m.init_edge(en[1], n, j, rest[1]);
  link_edge(E, en[0], tL, l, t3, r);
  link_edge(E, en[1], t1, l, tR, r);
  if (tL >= 0) {
    m.init_edge(en[2], l, n, rest[2]);
    split_wing(m, tL, t1, n, j, en[0], en[1], en[2]);
    rec.t[0] = tL, rec.t[1] = t1;
  }
  if (tR >= 0) {
    m.init_edge(en[3], n, r, rest[3]);
    split_wing(m, tR, t3, n, i, en[1], en[0], en[3]);
    rec.t[2] = tR, rec.t[3] = t3;
  }
  // n's list in the order of the triangles in rec.t, each entry's wing the side opposite n.
  std::int32_t entries[4], wings[4];
  int count = 0;
  for (int q = 0; q < 4; ++q) {
    const int t = rec.t[q];
    if (t < 0) continue;
    const int k = corner_of(m.T, t, n);
    entries[count] = (t << 2) | k, wings[count++] = m.T[t].e[(k + 1) % 3];
  }
  m.list_tris(n, entries, wings, count);
  m.records[plan.record] = rec;
}

// One wing of a restore, the inverse of split_wing: t = (stay, n, wing) becomes (stay, moved,
// wing) again, its sides the restored edge e and tn's; tn = (n, moved, wing) leaves the wing's
// list and its entry at moved becomes t's in place, so that a split undone before any other
// edit at its vertices gives back every list as it was.
void restore_wing(Topology& m, int t, int tn, int n, int moved, int e) {
  Edges& E = m.E;
  Face& f = m.T[t];
  const int km = corner_of(m.T, t, n), ks = (km + 2) % 3, kw = (km + 1) % 3;
  const int stay = f.v[ks], wing = f.v[kw], s_ws = f.e[kw];
  const int c = corner_of(m.T, tn, moved), s_mw = m.T[tn].e[c];
  relink_side(E, s_mw, tn, t, stay);
  relink_side(E, s_ws, t, t, moved);
  f.v[km] = moved, f.e[km] = s_mw, f.e[ks] = e;
  m.relist_tri(stay, (t << 2) | ks, (t << 2) | ks, s_mw);
  m.relist_tri(wing, (t << 2) | kw, (t << 2) | kw, e);
  m.relist_tri(moved, (tn << 2) | c, (t << 2) | km, s_ws);
  m.unlist_tri(wing, (tn << 2) | corner_of(m.T, tn, wing));
}

// A restore's topology: (i,n,l) -> (i,j,l) and (j,n,r) -> (j,i,r) in their slots, e_ij a mesh
// edge of both again. n's own lists are dropped whole, so that the releases after this erase
// n's edges only at their other ends.
void relink_restore(Topology& m, int e, const SplitRecord& s) {
  const int l = s.k[2], r = s.k[3], n = s.n;
  m.V.spring_list[n].count = m.V.tri_list[n].count = 0;
  m.E[e].flags = kAlive | kMesh | kBreakable;
  m.E[e].l0 = float(s.l0);
  m.E[e].record = -1;
  link_edge(m.E, e, s.t[0], l, s.t[2], r);  // e joins i -> j (its a and b since the split)
  if (s.t[0] >= 0) restore_wing(m, s.t[0], s.t[1], n, s.k[1], e);
  if (s.t[2] >= 0) restore_wing(m, s.t[2], s.t[3], n, s.k[0], e);
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

SplitPlan FastSimulator::plan_split_at(const SplitCandidate& c, int split, int edge_at, int tri_at) const {
  const Topology& m = topo_;
  SplitPlan p;
  if (c.e < 0) return p;
  p.e = c.e;
  p.flat_draw = c.flat_draw;
  p.ends = c.ends;
  // plan_split's takes, in its order. Written out again rather than shared, so that the serial
  // oracle (split_edge -> plan_split -> take_X) stays an independent check of these positions.
  p.n = m.peek_vertex(split);
  p.edges[0] = m.peek_edge(edge_at++);
  p.edges[1] = m.peek_edge(edge_at++);
  if (c.ends[2] >= 0) p.edges[2] = m.peek_edge(edge_at++);
  if (c.ends[3] >= 0) p.edges[3] = m.peek_edge(edge_at);
  if (c.tris[0] >= 0) p.tris[0] = m.peek_triangle(tri_at++);
  if (c.tris[1] >= 0) p.tris[1] = m.peek_triangle(tri_at);
  p.record = m.peek_record(split);
  return p;
}

bool FastSimulator::split_edge(int e) {
  const SplitPlan p = plan_split(split_candidate(e));
  if (p.e < 0) return false;
  topo_.fit();
  apply_split(p);
  return true;
}

void FastSimulator::apply_split(const SplitPlan& plan) {
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

  // [Eq 7] x_n = (x_i + x_j)/2 + s theta nu.
  const Float4 ni = V.nr[i], nj = V.nr[j];
  const D3 nu = split_direction(m.T, tL, tR, ni, nj);
  const double theta = 0.5 * params_.psi * std::sqrt(std::max(0.0, l0 * l0 - lt * lt));
  const double curl = (double(nj.x) - ni.x) * d.x + (double(nj.y) - ni.y) * d.y + (double(nj.z) - ni.z) * d.z;
  const double s = std::abs(curl) <= 1e-6 * lt ? (flat_draw < 0.5f ? -1.0 : 1.0) : (curl > 0 ? 1.0 : -1.0);

  // [Eq 3] masses of N = {i, j, l, r}; [Eq 4] the new vertex's momentum.
  const Float4 Xi = V.rest[i], Xj = V.rest[j];
  const D3 Xn{0.5 * (double(Xi.x) + Xj.x), 0.5 * (double(Xi.y) + Xj.y), 0.5 * (double(Xi.z) + Xj.z)};
  SplitRecord rec;
  rec.k = {i, j, l, r};
  rec.l0 = l0;
  const auto [dist, mn, pn] = split_masses(V, rec, Xn, params_.varphi);

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
  relink_split(m, plan, rec, lt_f, rest);
  // The four triangles' areas while their corners are cached (the normals' renewal reads them;
  // no later split of the pass changes these triangles: the stamps skip it).
  const float unit = length_unit();
  for (int t : rec.t)
    if (t >= 0) triangle_area(m, unit, m.T.area.data(), t);
}

bool FastSimulator::can_restore(int e) const {
  const Topology& m = topo_;
  if (e < 0 || e >= m.E.size() || m.E[e].flags != kAlive || m.E[e].record < 0) return false;
  return can_restore_record(m.records[m.E[e].record]);
}

bool FastSimulator::can_restore_record(const SplitRecord& s) const {
  const Topology& m = topo_;
  const int i = s.k[0], j = s.k[1], l = s.k[2], r = s.k[3], n = s.n;
  // n still has exactly its own edges. Tested first: most candidates that fail, fail here (a
  // later split at n, not yet restored), and this needs only n's list head, not the edges.
  const int expected = int(std::count_if(s.k.begin(), s.k.end(), [](int k) { return k >= 0; }));
  if (m.V.spring_list[n].count != expected) return false;
  if (!(m.V.mass(n) > 0)) return false;
  const int ends[4][2] = {{i, n}, {n, j}, {l, n}, {n, r}};
  for (int q = 0; q < 4; ++q) {
    if (s.k[q] < 0) continue;
    const int id = s.e[q];
    if (m.E[id].flags != (kAlive | kMesh | kBreakable)) return false;  // [Eq 10]
    const int a = m.E[id].a, b = m.E[id].b;
    if (!((a == ends[q][0] && b == ends[q][1]) || (a == ends[q][1] && b == ends[q][0]))) return false;
  }
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
  const int n = s.n;
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
  relink_restore(m, e, s);
  const float unit = length_unit();
  for (int t : {s.t[0], s.t[2]})  // as after a split; the two released triangles' areas are 0
    if (t >= 0) triangle_area(m, unit, m.T.area.data(), t);
  Freed freed;
  for (int q = 0; q < 4; ++q)
    if (s.e[q] >= 0) m.release_edge(s.e[q]), freed.edges[q] = s.e[q];
  if (s.t[1] >= 0) m.release_triangle(s.t[1]), freed.tris[0] = s.t[1];
  if (s.t[3] >= 0) m.release_triangle(s.t[3]), freed.tris[1] = s.t[3];
  m.release_vertex(n);
  freed.vertex = n;
  freed.record = rid;
  return freed;
}

}  // namespace crumple::fast
