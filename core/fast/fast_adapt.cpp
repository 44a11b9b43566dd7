// The adaptive mesh of the fast backend (MODEL.md §4, §5, §7): decisions by the adapt_test
// kernel in parallel, then the serial edits, in the same order and with the same id policy as
// the reference backend. Mass and momentum bookkeeping is done in double and stored in float.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "fast/fast_sim.h"
#include "fast/layout.h"
#include "fast/pass_timer.h"
#include "model/random.h"

namespace crumple::fast {

namespace {
constexpr double kReferenceStep = 1.0 / 60.0;  ///< h_ref of P_step (MODEL.md §4)

struct D3 {
  double x = 0, y = 0, z = 0;
};
double norm(const D3& a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// Triangle t's corners with `from` replaced by `to`, keeping the rotation.
std::array<int, 3> replaced(const Triangles& T, int t, int from, int to) {
  std::array<int, 3> v = T.corners(t);
  for (int& k : v)
    if (k == from) k = to;
  return v;
}

bool is_triangle(const Triangles& T, int t, int a, int b, int c) {
  if (t < 0 || t >= T.size() || !T.alive[t]) return false;
  const auto v = T.corners(t);
  for (int k = 0; k < 3; ++k)
    if (v[k] == a && v[(k + 1) % 3] == b && v[(k + 2) % 3] == c) return true;
  return false;
}
}  // namespace

void FastSimulator::adapt_decide() {
  compute_normals();
  AdaptConstants c;
  c.phi = float(params_.phi);
  c.epsilon = float(params_.epsilon);
  c.floor_length = float(scene_.floor_length);
  c.step_exponent = float(params_.h() / kReferenceStep);
  c.seed = params_.seed;
  c.step = steps_;
  c.fracture = params_.fracture;
  c.restoration = params_.restoration;
  decisions_.resize(std::size_t(topo_.E.size()));
  par_.run(topo_.E.size(), 4096, [&](int b, int e) { adapt_test(topo_, c, decisions_.data(), b, e); });
}

StepEvents FastSimulator::adapt_apply() {
  StepEvents ev;
  ++pass_;
  std::vector<int> splits, restores;
  const int n = int(decisions_.size());
  for (int e = 0; e < n;) {
    if (e + 8 <= n) {  // most decisions are 0: skip them eight at a time
      std::uint64_t word;
      std::memcpy(&word, &decisions_[e], 8);
      if (word == 0) {
        e += 8;
        continue;
      }
    }
    if (decisions_[e] == 1) splits.push_back(topo_.E.lid[e]);
    if (decisions_[e] == 2) restores.push_back(topo_.E.lid[e]);
    ++e;
  }
  // Events apply in ascending logical edge id (the order of MODEL.md §4 and of the reference);
  // each event's slot is looked up when it applies, as earlier events of the pass reuse slots
  // only of ids they free, never of pending ones.
  std::sort(splits.begin(), splits.end());
  std::sort(restores.begin(), restores.end());
  auto touched = [&](int t) { return t >= 0 && t < int(tri_stamp_.size()) && tri_stamp_[t] == pass_; };
  std::vector<int> changed;  // triangles changed in this pass
  auto stamp = [&](int t) {
    if (t < 0) return;
    if (t >= int(tri_stamp_.size())) tri_stamp_.resize(std::size_t(t) + 1, 0);
    if (tri_stamp_[t] != pass_) changed.push_back(t);
    tri_stamp_[t] = pass_;
  };
  for (int id : splits) {
    const int e = topo_.E.phys[id];
    if (touched(topo_.E.tri0[e]) || touched(topo_.E.tri1[e])) continue;
    if (!split_edge(e, float(uniform(params_.seed, steps_, std::uint32_t(id), Draw::FlatSign)))) continue;
    for (int t : topo_.records[topo_.E.record[e]].t) stamp(t);
    ++ev.splits;
  }
  for (int id : restores) {
    const int e = topo_.E.phys[id];
    const auto t = topo_.records[topo_.E.record[e]].t;
    if (std::any_of(t.begin(), t.end(), touched) || !can_restore(e)) continue;
    restore_edge(e);
    for (int k : t) stamp(k);
    ++ev.restores;
  }
  // Bring the areas and normals computed for the decisions up to date where the topology
  // changed, so the next step need not recompute them all (range kernels on single elements).
  std::vector<int> verts;
  for (int t : changed) {
    if (!topo_.T.alive[t]) continue;
    triangle_areas(topo_, t, t + 1);
    for (int v : topo_.T.corners(t)) verts.push_back(v);
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  for (int v : verts) vertex_normals(topo_, v, v + 1);
  normals_valid_ = true;
  return ev;
}

StepEvents FastSimulator::adapt() {
  if (!params_.fracture && !params_.restoration) return {};
  {
    PassTimer t(pass_seconds_, int(Pass::AdaptTest));
    adapt_decide();
  }
  StepEvents ev;
  {
    PassTimer t(pass_seconds_, int(Pass::TopologyApply));
    ev = adapt_apply();
  }
  if (layout_stale(topo_, layout_fraction_)) {
    PassTimer t(pass_seconds_, int(Pass::Layout));
    relayout(topo_, par_, layout_scratch_);
  }
  return ev;
}

bool FastSimulator::split_edge(int e, float flat_draw) {
  Topology& m = topo_;
  Vertices& V = m.V;
  if (!(m.E.flags[e] & kAlive) || !(m.E.flags[e] & kMesh) || !(m.E.flags[e] & kBreakable)) return false;
  const int i = m.E.a[e], j = m.E.b[e], tL = m.E.tri0[e], tR = m.E.tri1[e];
  const int l = m.E.wl[e], r = m.E.wr[e];
  const D3 xi{V.x[i], V.y[i], V.z[i]}, xj{V.x[j], V.y[j], V.z[j]};
  const D3 d{xj.x - xi.x, xj.y - xi.y, xj.z - xi.z};
  const double lt = norm(d), l0 = m.E.l0[e];

  // [Eq 7] x_n = (x_i + x_j)/2 + s theta nu; nu from the adjacent face normals.
  D3 nu;
  for (int t : {tL, tR}) {
    if (t < 0) continue;
    const D3 w{m.T.area[t].x, m.T.area[t].y, m.T.area[t].z};
    const double len = norm(w);
    if (len > 0) nu = {nu.x + w.x / len, nu.y + w.y / len, nu.z + w.z / len};
  }
  if (!(norm(nu) > 1e-12)) nu = {double(V.nx[i]) + V.nx[j], double(V.ny[i]) + V.ny[j], double(V.nz[i]) + V.nz[j]};
  const double nlen = norm(nu);
  nu = nlen > 1e-12 ? D3{nu.x / nlen, nu.y / nlen, nu.z / nlen} : D3{};
  const double theta = 0.5 * params_.psi * std::sqrt(std::max(0.0, l0 * l0 - lt * lt));
  const double curl = (double(V.nx[j]) - V.nx[i]) * d.x + (double(V.ny[j]) - V.ny[i]) * d.y + (double(V.nz[j]) - V.nz[i]) * d.z;
  const double s = std::abs(curl) <= 1e-6 * lt ? (flat_draw < 0.5f ? -1.0 : 1.0) : (curl > 0 ? 1.0 : -1.0);

  // [Eq 3] masses of N = {i, j, l, r}; [Eq 4] the new vertex's momentum.
  const D3 Xn{0.5 * (double(V.rx[i]) + V.rx[j]), 0.5 * (double(V.ry[i]) + V.ry[j]), 0.5 * (double(V.rz[i]) + V.rz[j])};
  auto rest_dist = [&](int k) { return norm({V.rx[k] - Xn.x, V.ry[k] - Xn.y, V.rz[k] - Xn.z}); };
  SplitRecord rec;
  rec.k = {i, j, l, r};
  rec.l0 = l0;
  double dsum = 0;
  for (int k : rec.k)
    if (k >= 0) dsum += rest_dist(k);
  double mn = 0;
  D3 pn;
  for (int q = 0; q < 4; ++q) {
    const int k = rec.k[q];
    if (k < 0) continue;
    rec.delta[q] = rest_dist(k) / dsum;
    const float m_new = float(0.5 * (std::pow(rec.delta[q], 1.0 / params_.varphi) + 1.0) * V.m[k]);
    rec.dm[q] = double(V.m[k] - m_new);  // exact in float (Sterbenz: m_new >= m_k / 2)
    V.m[k] = m_new;
    mn += rec.dm[q];
    pn = {pn.x + rec.dm[q] * V.vx[k], pn.y + rec.dm[q] * V.vy[k], pn.z + rec.dm[q] * V.vz[k]};
  }

  const int n = m.new_vertex();
  V.rx[n] = float(Xn.x), V.ry[n] = float(Xn.y), V.rz[n] = float(Xn.z);
  V.x[n] = float(0.5 * (xi.x + xj.x) + s * theta * nu.x);
  V.y[n] = float(0.5 * (xi.y + xj.y) + s * theta * nu.y);
  V.z[n] = float(0.5 * (xi.z + xj.z) + s * theta * nu.z);
  V.m[n] = float(mn);
  V.vx[n] = float(pn.x / mn), V.vy[n] = float(pn.y / mn), V.vz[n] = float(pn.z / mn);
  V.nx[n] = float(nu.x), V.ny[n] = float(nu.y), V.nz[n] = float(nu.z);
  for (int t : {tL, tR})
    if (t >= 0) m.detach(t);
  // e_ij becomes an auxiliary spring holding the crease at its current length.
  m.E.flags[e] = kAlive;
  m.E.l0[e] = float(lt);
  rec.n = n;
  rec.e[0] = m.new_edge(i, n, float(l0 / 2));
  rec.e[1] = m.new_edge(n, j, float(l0 / 2));
  if (l >= 0) rec.e[2] = m.new_edge(l, n, float(rest_dist(l)));
  if (r >= 0) rec.e[3] = m.new_edge(n, r, float(rest_dist(r)));
  if (tL >= 0) rec.t[0] = tL, rec.t[1] = m.new_triangle();
  if (tR >= 0) rec.t[2] = tR, rec.t[3] = m.new_triangle();
  bool ok = true;
  if (tL >= 0) {
    const auto v = replaced(m.T, tL, j, n);
    ok &= m.attach(tL, v[0], v[1], v[2]);
    ok &= m.attach(rec.t[1], n, j, l);
  }
  if (tR >= 0) {
    const auto v = replaced(m.T, tR, i, n);
    ok &= m.attach(tR, v[0], v[1], v[2]);
    ok &= m.attach(rec.t[3], n, i, r);
  }
  int id;
  if (!m.free_records.empty()) {
    id = m.free_records.back();
    m.free_records.pop_back();
    m.records[id] = rec;
  } else {
    id = int(m.records.size());
    m.records.push_back(rec);
  }
  m.E.record[e] = id;
  for (int k : rec.k)
    if (k >= 0) m.update_msum(k);
  m.update_msum(n);
  return ok;
}

bool FastSimulator::can_restore(int e) const {
  const Topology& m = topo_;
  if (e < 0 || e >= m.E.size() || m.E.flags[e] != kAlive || m.E.record[e] < 0) return false;
  const SplitRecord& s = m.records[m.E.record[e]];
  const int i = s.k[0], j = s.k[1], l = s.k[2], r = s.k[3], n = s.n;
  if (!(m.V.m[n] > 0)) return false;
  const int ends[4][2] = {{i, n}, {n, j}, {l, n}, {n, r}};
  int expected = 0;
  for (int q = 0; q < 4; ++q) {
    if (s.k[q] < 0) continue;
    const int id = s.e[q];
    if (m.E.flags[id] != (kAlive | kMesh | kBreakable)) return false;  // [Eq 10]
    const int a = m.E.a[id], b = m.E.b[id];
    if (!((a == ends[q][0] && b == ends[q][1]) || (a == ends[q][1] && b == ends[q][0]))) return false;
    ++expected;
  }
  if (m.V.n_springs[n] != expected) return false;  // n still has exactly its own edges
  if (l >= 0 && !(is_triangle(m.T, s.t[0], i, n, l) && is_triangle(m.T, s.t[1], n, j, l))) return false;
  if (r >= 0 && !(is_triangle(m.T, s.t[2], j, n, r) && is_triangle(m.T, s.t[3], n, i, r))) return false;
  return true;
}

void FastSimulator::restore_edge(int e) {
  Topology& m = topo_;
  Vertices& V = m.V;
  const int rid = m.E.record[e];
  const SplitRecord s = m.records[rid];
  const int i = s.k[0], j = s.k[1], n = s.n;
  const double mn = V.m[n];
  const D3 vn{V.vx[n], V.vy[n], V.vz[n]};
  if (params_.restore == RestoreForm::Exact) {
    double dsum = 0;
    for (int q = 0; q < 4; ++q)
      if (s.k[q] >= 0) dsum += s.dm[q];
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      const double mk = V.m[k], m_new = mk + mn * s.dm[q] / dsum;
      V.vx[k] = float((mk * V.vx[k] + (m_new - mk) * vn.x) / m_new);
      V.vy[k] = float((mk * V.vy[k] + (m_new - mk) * vn.y) / m_new);
      V.vz[k] = float((mk * V.vz[k] + (m_new - mk) * vn.z) / m_new);
      V.m[k] = float(m_new);
    }
  } else {
    double msum = 0;
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      V.m[k] = float(2.0 * V.m[k] / (std::pow(s.delta[q], 1.0 / params_.varphi) + 1.0));  // [Eq 11]
      msum += V.m[k];
    }
    for (int q = 0; q < 4; ++q) {
      const int k = s.k[q];
      if (k < 0) continue;
      V.vx[k] = float(V.vx[k] + mn * vn.x / msum);  // [Eq 12]
      V.vy[k] = float(V.vy[k] + mn * vn.y / msum);
      V.vz[k] = float(V.vz[k] + mn * vn.z / msum);
    }
  }
  for (int t : s.t)
    if (t >= 0) m.detach(t);
  for (int id : s.e)
    if (id >= 0) m.free_edge(id);
  if (s.t[1] >= 0) m.free_triangle(s.t[1]);
  if (s.t[3] >= 0) m.free_triangle(s.t[3]);
  m.free_vertex(n);
  m.E.flags[e] = kAlive | kMesh | kBreakable;
  m.E.l0[e] = float(s.l0);
  m.E.record[e] = -1;
  m.free_records.push_back(rid);
  if (s.t[0] >= 0) {
    const auto v = replaced(m.T, s.t[0], n, j);
    m.attach(s.t[0], v[0], v[1], v[2]);
  }
  if (s.t[2] >= 0) {
    const auto v = replaced(m.T, s.t[2], n, i);
    m.attach(s.t[2], v[0], v[1], v[2]);
  }
  for (int k : s.k)
    if (k >= 0) m.update_msum(k);
}

std::vector<Decision> FastSimulator::decide() const {
  FastSimulator tmp(*this);
  tmp.adapt_decide();
  std::vector<Decision> out(tmp.decisions_.size());
  for (size_t e = 0; e < out.size(); ++e) out[tmp.topo_.E.lid[e]].kind = tmp.decisions_[e];
  return out;
}

bool FastSimulator::split(int id) {
  if (id < 0 || id >= topo_.E.size()) return false;
  compute_normals();
  normals_valid_ = false;
  return split_edge(topo_.E.phys[id], float(uniform(params_.seed, steps_, std::uint32_t(id), Draw::FlatSign)));
}

bool FastSimulator::restore(int id) {
  if (id < 0 || id >= topo_.E.size()) return false;
  const int e = topo_.E.phys[id];
  if (!can_restore(e)) return false;
  normals_valid_ = false;
  restore_edge(e);
  return true;
}

}  // namespace crumple::fast
