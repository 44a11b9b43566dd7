// The adaptive mesh of the fast backend (MODEL.md §4, §5, §7): decisions by the adapt_test
// kernel in parallel, then the serial edits, in the same order and with the same id policy as
// the reference backend. Mass and momentum bookkeeping is done in double and stored in float.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "fast/fast_sim.h"
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

template <class T>
void prefetch(const T* p) {
  __builtin_prefetch(p, 1, 3);
}
/// The per-edge lines an event on edge e reads first.
void prefetch_edge(const Topology& m, int e) {
  const Edges& E = m.E;
  prefetch(&E.flags[e]), prefetch(&E.a[e]), prefetch(&E.b[e]), prefetch(&E.wl[e]), prefetch(&E.wr[e]);
  prefetch(&E.tri0[e]), prefetch(&E.tri1[e]), prefetch(&E.l0[e]), prefetch(&E.record[e]), prefetch(&E.lid[e]);
}
void prefetch_vertex(const Topology& m, int v) {
  if (v < 0) return;
  const Vertices& V = m.V;
  for (const Array<float>* a : {&V.x, &V.y, &V.z, &V.vx, &V.vy, &V.vz, &V.m, &V.nx, &V.ny, &V.nz, &V.rx, &V.ry, &V.rz})
    prefetch(&(*a)[v]);
  prefetch(&V.n_springs[v]), prefetch(&V.n_tris[v]);
  prefetch(m.springs_of(v)), prefetch(m.nbrs_of(v)), prefetch(m.tris_of(v)), prefetch(m.wings_of(v));
}
void prefetch_triangle(const Topology& m, int t) {
  if (t < 0) return;
  const Triangles& T = m.T;
  prefetch(&T.v0[t]), prefetch(&T.v1[t]), prefetch(&T.v2[t]), prefetch(&T.e0[t]), prefetch(&T.e1[t]);
  prefetch(&T.e2[t]), prefetch(&T.alive[t]), prefetch(&T.area[t]);
}
/// Everything a split of e reads (its edge lines must be cached already: prefetch_edge).
void prefetch_split(const Topology& m, int e) {
  for (int v : {m.E.a[e], m.E.b[e], m.E.wl[e], m.E.wr[e]}) prefetch_vertex(m, v);
  prefetch_triangle(m, m.E.tri0[e]);
  prefetch_triangle(m, m.E.tri1[e]);
}
/// Everything a restore of e reads (its record must be cached already).
void prefetch_restore(const Topology& m, int e) {
  const SplitRecord& r = m.records[m.E.record[e]];
  prefetch_vertex(m, r.n);
  for (int q = 0; q < 4; ++q) {
    prefetch_vertex(m, r.k[q]);
    if (r.e[q] >= 0) prefetch_edge(m, r.e[q]);
    prefetch_triangle(m, r.t[q]);
  }
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
  AdaptScratch& s = scratch_;  // the pass's temporaries, kept from pass to pass
  // The events apply in ascending logical edge id (the order of MODEL.md §4 and of the
  // reference). Two parallel passes over fixed blocks, no sort: the decisions (per slot) are
  // copied to their logical ids, then read back in logical order, each block listing its
  // events' slots. A pending event's edge keeps its slot through the pass: splits free no
  // edge, and restores free only mesh edges, never a pending (auxiliary) one.
  const int n = int(decisions_.size());
  constexpr int kBlock = 16384;
  const int blocks = (n + kBlock - 1) / kBlock;
  by_id_.resize(std::size_t(n), 0);  // all 0 between passes
  auto each_nonzero = [](const std::uint8_t* bytes, int begin, int end, auto&& f) {
    for (int k = begin; k < end;) {
      if (k + 8 <= end) {  // most decisions are 0: skip them eight at a time
        std::uint64_t word;
        std::memcpy(&word, bytes + k, 8);
        if (word == 0) {
          k += 8;
          continue;
        }
      }
      if (bytes[k]) f(k);
      ++k;
    }
  };
  par_.run(blocks, 1, [&](int b0, int b1) {
    for (int b = b0; b < b1; ++b)
      each_nonzero(decisions_.data(), b * kBlock, std::min(n, (b + 1) * kBlock),
                   [&](int e) { by_id_[topo_.E.lid[e]] = decisions_[e]; });
  });
  std::vector<std::vector<int>>& found = s.found;  // per block and kind: slots in id order
  found.resize(2 * std::size_t(blocks));
  par_.run(blocks, 1, [&](int b0, int b1) {
    for (int b = b0; b < b1; ++b) {
      found[2 * b].clear(), found[2 * b + 1].clear();
      each_nonzero(by_id_.data(), b * kBlock, std::min(n, (b + 1) * kBlock), [&](int id) {
        found[2 * b + by_id_[id] - 1].push_back(topo_.E.phys[id]);
        by_id_[id] = 0;
      });
    }
  });
  for (int kind : {0, 1}) {
    std::vector<int>& slots = kind == 0 ? s.splits : s.restores;
    slots.clear();
    for (int b = 0; b < blocks; ++b) slots.insert(slots.end(), found[2 * b + kind].begin(), found[2 * b + kind].end());
  }
  const std::vector<int>&splits = s.splits, &restores = s.restores;
  auto touched = [&](int t) { return t >= 0 && t < int(tri_stamp_.size()) && tri_stamp_[t] == pass_; };
  std::vector<int>& changed = s.changed;  // triangles changed in this pass
  changed.clear();
  auto stamp = [&](int t) {
    if (t < 0) return;
    if (t >= int(tri_stamp_.size())) tri_stamp_.resize(std::size_t(t) + 1, 0);
    if (tri_stamp_[t] != pass_) changed.push_back(t);
    tri_stamp_[t] = pass_;
  };
  // Each event touches a few hundred bytes in some fifty cache lines of the SoA arrays, far
  // from the previous event's: prefetching the next events' lines while one applies overlaps
  // those misses (the events themselves still apply one by one, in order).
  const Topology& m = topo_;
  constexpr int kFar = 8, kNear = 3;
  // Splits. Acceptance and new ids are decided first, serially in event order: a split is
  // skipped when an earlier accepted split of the pass changed one of its edge's two
  // triangles, and those are still the triangles it had at the start of the pass (a split
  // changes only its own two, and any later split sharing one is skipped). Accepted splits then
  // apply in rounds: a split's round is one more than the last round of an earlier split
  // sharing one of its vertices, so the splits of a round have disjoint vertex sets (hence
  // disjoint edges, triangles and adjacency lists) and run in parallel, while every vertex
  // still receives its edits in event order: the result is the serial one, bit for bit
  // (docs/DECISIONS.md D13).
  const int nv0 = m.V.size();
  if (serial_splits_) {  // the definition the rounds reproduce: one split after the other
    for (int e : splits) {
      if (touched(m.E.tri0[e]) || touched(m.E.tri1[e])) continue;
      if (!split_edge(e)) continue;
      for (int t : m.records[m.E.record[e]].t) stamp(t);
      ++ev.splits;
    }
  }
  const std::vector<int> no_splits;
  const std::vector<int>& round_splits = serial_splits_ ? no_splits : splits;
  std::vector<SplitPlan>& plans = s.plans;
  std::vector<int>& round_of = s.round_of;
  plans.clear(), round_of.clear();
  // Per-vertex scratch, all 0 between passes (reset below for the vertices used): no pass
  // clears or allocates an array the size of the mesh.
  for (std::vector<int>* a : {&round_last_, &spring_adds_, &tri_adds_}) a->resize(std::size_t(nv0), 0);
  split_vertex_.resize(std::size_t(nv0), 0);
  std::vector<int>& involved = s.involved;  // vertices of accepted splits (i, j, l, r), once each
  involved.clear();
  int rounds = 0, need_springs = 0, need_tris = 0;
  // What the serial pre-pass needs of each candidate, read in parallel into a compact array
  // (the pre-pass then touches only it, the stamps and the rounds).
  split_candidates_.resize(round_splits.size());
  par_.run(int(round_splits.size()), 256, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kFar < e) prefetch_edge(m, round_splits[k + kFar]);
      split_candidates_[k] = split_candidate(round_splits[k]);
    }
  });
  for (std::size_t k = 0; k < round_splits.size(); ++k) {
    if (k + kNear < round_splits.size()) {
      const SplitCandidate& f = split_candidates_[k + kNear];
      for (int t : f.tris)
        if (t >= 0 && t < int(tri_stamp_.size())) prefetch(&tri_stamp_[t]);
      for (int v : f.ends)
        if (v >= 0) prefetch(&round_last_[v]), prefetch(&split_vertex_[v]);
    }
    const SplitCandidate& c = split_candidates_[k];
    const int tL = c.tris[0], tR = c.tris[1];
    if (touched(tL) || touched(tR)) continue;
    const SplitPlan p = plan_split(c);
    if (p.e < 0) continue;
    const std::array<int, 4>& ends = c.ends;
    int round = 0;
    for (int v : ends)
      if (v >= 0) round = std::max(round, round_last_[v]);
    ++round;
    for (int v : ends) {
      if (v < 0) continue;
      round_last_[v] = round;
      if (!split_vertex_[v]) split_vertex_[v] = 1, involved.push_back(v);
    }
    rounds = std::max(rounds, round);
    for (int t : {tL, tR, p.tris[0], p.tris[1]}) stamp(t);
    plans.push_back(p);
    round_of.push_back(round);
  }
  topo_.fit();  // the slots plan_split took
  // Room in the adjacency lists for every append, so that no list widens while rounds run: a
  // split adds one spring at each of i, j, l, r and, net, one triangle at l and at r (i and j
  // lose their two triangles before they gain two). Exact, so strides widen when the serial
  // order would have widened them, not earlier (a wider stride slows every gather).
  for (const SplitPlan& p : plans) {
    for (int v : p.ends)
      if (v >= 0) ++spring_adds_[v];
    for (int v : {p.ends[2], p.ends[3]})
      if (v >= 0) ++tri_adds_[v];
  }
  for (int v : involved) {
    need_springs = std::max(need_springs, m.V.n_springs[v] + spring_adds_[v]);
    need_tris = std::max(need_tris, m.V.n_tris[v] + tri_adds_[v]);
    round_last_[v] = spring_adds_[v] = tri_adds_[v] = 0;
  }
  topo_.make_room(std::max(need_springs, 4), std::max(need_tris, 4));
  // The rounds, each a parallel loop over its splits (in event order within the round).
  std::vector<int>&by_round = s.by_round, &start = s.start;
  by_round.resize(plans.size());
  start.assign(std::size_t(rounds) + 2, 0);
  for (int r : round_of) ++start[r + 1];
  for (int r = 1; r <= rounds; ++r) start[r + 1] += start[r];
  s.fill.assign(start.begin(), start.end());
  for (std::size_t k = 0; k < plans.size(); ++k) by_round[s.fill[round_of[k]]++] = int(k);
  std::vector<std::uint8_t>& applied = s.applied;
  applied.assign(plans.size(), 0);
  constexpr int kRoundGrain = 64;  // smaller rounds run inline: a parallel loop costs ~10 us
  constexpr int kWaveGrain = 32;   // a restore costs about as much as a split (3-4 us)
  for (int r = 1; r <= rounds; ++r) {
    large_rounds_ += start[r + 1] - start[r] > kRoundGrain;
    par_.run(start[r + 1] - start[r], kRoundGrain, [&](int b, int e) {
      for (int k = start[r] + b; k < start[r] + e; ++k) {
        if (k + kNear < start[r] + e) prefetch_split(m, plans[by_round[k + kNear]].e);
        const int i = by_round[k];
        applied[i] = apply_split(plans[i]);
      }
    });
  }
  for (int v : involved) split_vertex_[v] = 0;
  for (std::uint8_t a : applied) ev.splits += a;
  // Restores, in waves (docs/DECISIONS.md D14). A restore reads and writes only its own
  // vertices {n, i, j, l, r} with their lists, edges and triangles, so a candidate's answer
  // can change only through an earlier candidate sharing one of its vertices. A wave scans the
  // pending candidates in event order: one sharing a vertex with an earlier candidate of the
  // scan that is accepted or waiting waits for the next wave (and claims its vertices, so
  // that later candidates at them wait too); the others are decided on the current state and
  // the accepted ones, vertex-disjoint, apply in parallel. Every vertex sees its restores in
  // event order, and the freed ids reach the free lists in event order after the waves: the
  // serial result, bit for bit. The first wave's answers are pre-tested in parallel, so its
  // serial scan reads only a compact array and the claims.
  if (serial_splits_) {  // the definition the waves reproduce
    for (int e : restores) {
      const SplitRecord& r = m.records[m.E.record[e]];
      if (std::any_of(r.t.begin(), r.t.end(), touched) || !can_restore(e)) continue;
      const auto t = r.t;
      restore_edge(e);
      for (int q : t) stamp(q);
      ++ev.restores;
    }
  }
  const std::vector<int>& wave_restores = serial_splits_ ? no_splits : restores;
  const int nr = int(wave_restores.size());
  enum : std::uint8_t { kNever, kNotNow, kRestorable };  // a candidate's answer on the state after the splits
  candidates_.resize(std::size_t(nr));
  par_.run(nr, 128, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kNear < e) prefetch(&m.records[m.E.record[wave_restores[k + kNear]]]);
      const int edge = wave_restores[k];
      const SplitRecord& r = m.records[m.E.record[edge]];
      // touched() sees the splits' stamps only: a restore's stamps matter to candidates that
      // share its vertices, which wait for a later wave and test touched() again there.
      const std::uint8_t answer = std::any_of(r.t.begin(), r.t.end(), touched) ? kNever
                                  : can_restore(edge)                           ? kRestorable
                                                                                : kNotNow;
      candidates_[k] = RestoreCandidate{{r.n, r.k[0], r.k[1], r.k[2], r.k[3]}, answer};
    }
  });
  claim_.resize(std::size_t(m.V.size()), 0);  // all 0 between waves
  std::vector<int>&pending = s.pending, &next = s.next, &wave = s.wave, &claimed = s.claimed;
  pending.clear();
  for (int k = 0; k < nr; ++k)
    if (candidates_[k].answer != kNever) pending.push_back(k);
  std::vector<std::pair<int, Freed>>& freed = s.freed;  // (candidate, what its restore freed)
  freed.clear();
  for (bool first = true; !pending.empty(); first = false) {
    next.clear(), wave.clear(), claimed.clear();
    for (std::size_t q = 0; q < pending.size(); ++q) {
      if (q + kFar < pending.size())
        for (int v : candidates_[pending[q + kFar]].verts)
          if (v >= 0) prefetch(&claim_[v]);
      const int k = pending[q], e = wave_restores[k];
      const std::array<int, 5>& verts = candidates_[k].verts;
      const bool waits = std::any_of(verts.begin(), verts.end(), [&](int v) { return v >= 0 && claim_[v]; });
      if (!waits) {
        if (first && candidates_[k].answer != kRestorable) continue;
        if (!first) {
          const SplitRecord& r = m.records[m.E.record[e]];
          if (std::any_of(r.t.begin(), r.t.end(), touched) || !can_restore(e)) continue;
        }
      }
      for (int v : verts)
        if (v >= 0 && !claim_[v]) claim_[v] = k + 1, claimed.push_back(v);
      if (waits) {
        next.push_back(k);
        continue;
      }
      wave.push_back(k);
      for (int t : m.records[m.E.record[e]].t) stamp(t);
    }
    const std::size_t done = freed.size();
    freed.resize(done + wave.size());
    par_.run(int(wave.size()), kWaveGrain, [&](int b, int e) {
      for (int q = b; q < e; ++q) {
        if (q + kNear < e) prefetch_restore(m, wave_restores[wave[q + kNear]]);
        const int k = wave[q];
        freed[done + q] = {k, restore_edge_local(wave_restores[k])};
      }
    });
    for (int v : claimed) claim_[v] = 0;
    large_waves_ += wave.size() > std::size_t(kWaveGrain);
    pending.swap(next);
  }
  std::sort(freed.begin(), freed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& f : freed) topo_.free_ids(f.second);
  ev.restores += int(freed.size());
  // Bring the areas and normals computed for the decisions up to date where the topology
  // changed, so the next step need not recompute them all (range kernels on single elements,
  // in parallel; each corner once).
  vertex_stamp_.resize(std::size_t(m.V.size()), 0);
  std::vector<int>&live = s.live, &verts = s.verts;
  live.clear(), verts.clear();
  for (int t : changed) {
    if (!topo_.T.alive[t]) continue;
    live.push_back(t);
    for (int v : topo_.T.corners(t))
      if (vertex_stamp_[v] != pass_) vertex_stamp_[v] = pass_, verts.push_back(v);
  }
  par_.run(int(live.size()), 512, [&](int b, int e) {
    for (int k = b; k < e; ++k) triangle_areas(topo_, live[k], live[k] + 1);
  });
  par_.run(int(verts.size()), 512, [&](int b, int e) {
    for (int k = b; k < e; ++k) vertex_normals(topo_, verts[k], verts[k] + 1);
  });
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
  return ev;
}

FastSimulator::SplitCandidate FastSimulator::split_candidate(int e) const {
  const Edges& E = topo_.E;
  SplitCandidate c;
  if (E.flags[e] != (kAlive | kMesh | kBreakable)) return c;
  c.e = e;
  c.tris = {E.tri0[e], E.tri1[e]};
  c.ends = {E.a[e], E.b[e], E.wl[e], E.wr[e]};
  c.flat_draw = float(uniform(params_.seed, steps_, std::uint32_t(E.lid[e]), Draw::FlatSign));
  return c;
}

FastSimulator::SplitPlan FastSimulator::plan_split(const SplitCandidate& c) {
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

  const int n = plan.n;
  m.init_vertex(n);
  V.rx[n] = float(Xn.x), V.ry[n] = float(Xn.y), V.rz[n] = float(Xn.z);
  V.x[n] = float(0.5 * (xi.x + xj.x) + s * theta * nu.x);
  V.y[n] = float(0.5 * (xi.y + xj.y) + s * theta * nu.y);
  V.z[n] = float(0.5 * (xi.z + xj.z) + s * theta * nu.z);
  V.m[n] = float(mn);
  V.vx[n] = float(pn.x / mn), V.vy[n] = float(pn.y / mn), V.vz[n] = float(pn.z / mn);
  V.nx[n] = float(nu.x), V.ny[n] = float(nu.y), V.nz[n] = float(nu.z);
  for (int t : {tL, tR})
    if (t >= 0) m.detach(t);
  // e_ij becomes an auxiliary spring holding the crease at its current length, with the
  // crease's wings in its wing slots (for [Eq 10]).
  m.E.flags[e] = kAlive;
  m.E.wl[e] = l;
  m.E.wr[e] = r;
  m.E.l0[e] = float(lt);
  rec.n = n;
  rec.e = plan.edges;
  m.init_edge(rec.e[0], i, n, float(l0 / 2));
  m.init_edge(rec.e[1], n, j, float(l0 / 2));
  if (l >= 0) m.init_edge(rec.e[2], l, n, float(rest_dist(l)));
  if (r >= 0) m.init_edge(rec.e[3], n, r, float(rest_dist(r)));
  if (tL >= 0) rec.t[0] = tL, rec.t[1] = plan.tris[0], m.init_triangle(plan.tris[0]);
  if (tR >= 0) rec.t[2] = tR, rec.t[3] = plan.tris[1], m.init_triangle(plan.tris[1]);
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
  m.records[plan.record] = rec;
  m.E.record[e] = plan.record;
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

void FastSimulator::restore_edge(int e) { topo_.free_ids(restore_edge_local(e)); }

Freed FastSimulator::restore_edge_local(int e) {
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
  Freed freed;
  for (int q = 0; q < 4; ++q)
    if (s.e[q] >= 0) m.release_edge(s.e[q]), freed.edges[q] = s.e[q];
  if (s.t[1] >= 0) m.release_triangle(s.t[1]), freed.tris[0] = s.t[1];
  if (s.t[3] >= 0) m.release_triangle(s.t[3]), freed.tris[1] = s.t[3];
  m.release_vertex(n);
  freed.vertex = n;
  freed.record = rid;
  m.E.flags[e] = kAlive | kMesh | kBreakable;
  m.E.l0[e] = float(s.l0);
  m.E.record[e] = -1;
  m.E.wl[e] = m.E.wr[e] = -1;  // attach below links its triangles' wings
  if (s.t[0] >= 0) {
    const auto v = replaced(m.T, s.t[0], n, j);
    m.attach(s.t[0], v[0], v[1], v[2]);
  }
  if (s.t[2] >= 0) {
    const auto v = replaced(m.T, s.t[2], n, i);
    m.attach(s.t[2], v[0], v[1], v[2]);
  }
  return freed;
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
  return split_edge(topo_.E.phys[id]);
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
