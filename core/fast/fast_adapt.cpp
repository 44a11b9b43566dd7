// The adaptive mesh of the fast backend (MODEL.md §4, §5, §7), the topology pass: decisions by
// the adapt_test kernel in parallel, then the events in the order of the reference backend
// (splits in parallel rounds, restores in parallel waves, each with the serial result), then the
// areas and normals renewed where triangles changed. One event's edits are in fast_edits.cpp.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "fast/fast_sim.h"
#include "fast/pass_timer.h"
#include "model/random.h"

namespace crumple::fast {

namespace {
constexpr double kReferenceStep = 1.0 / 60.0;  ///< h_ref of P_step (MODEL.md §4)

template <class T>
void prefetch(const T* p) {  // for lines the event will write
  __builtin_prefetch(p, 1, 3);
}
template <class T>
void prefetch_read(const T* p) {  // for lines it only reads (no claim on other cores' copies)
  __builtin_prefetch(p, 0, 3);
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

// Each event touches a few hundred bytes in some fifty cache lines of the SoA arrays, far from
// the previous event's: prefetching the next events' lines while one applies overlaps those
// misses (the events themselves still apply in order). kFar ahead: the first lines (the edge,
// the record); kNear ahead: what those lines point to.
constexpr int kFar = 8;   ///< beyond kNear, so the first lines are cached when kNear reads through them
constexpr int kNear = 3;  ///< few: kNear events' lines (some fifty each) must stay in L1 until used
constexpr int kRoundGrain = 64;  ///< smaller split rounds run inline: too few splits to repay a parallel loop's start
constexpr int kWaveGrain = 32;   ///< waves are smaller than rounds, and a restore costs about what a split does
constexpr int kTestGrain = 4096;       ///< adapt_test streams cheaply over every edge: large chunks
constexpr int kCandidateGrain = 256;   ///< a candidate read misses several lines: smaller chunks repay
constexpr int kRestoreTestGrain = 128; ///< a restore test reads a record and its triangles: more per item
constexpr int kRenewGrain = 512;       ///< an area or a few normals per triangle: less than an event

}  // namespace

void FastSimulator::adapt_decide() {
  compute_normals();
  AdaptConstants c;
  const double budget = params_.budget_factor(topo_.live_vertices());  // D22, as the reference
  c.budget = float(budget);
  c.unit = length_unit();
  c.phi = float(params_.phi);
  c.epsilon = float(budget * params_.epsilon);
  c.floor_length = float(scene_.floor_length);
  c.step_exponent = float(params_.adapt_interval() / kReferenceStep);
  c.seed = params_.seed;
  c.step = steps_;
  c.fracture = params_.fracture;
  c.restoration = params_.restoration;
  decisions_.resize(std::size_t(topo_.E.size()));
  par_.run_lanes(topo_.E.size(), kTestGrain, [&](int b, int e) { adapt_test(topo_, c, decisions_.data(), b, e); });
}

StepEvents FastSimulator::adapt_apply() {
  ++pass_;
  collect_events();
  if (params_.max_vertices > 0) {  // the hard guard, as the reference: the budget's first candidates
    std::vector<int>& splits = scratch_.splits;
    splits.resize(std::min<std::size_t>(splits.size(), std::max(0, params_.max_vertices - topo_.live_vertices())));
  }
  scratch_.changed.clear();
  StepEvents ev;
  ev.splits = apply_splits();
  ev.restores = apply_restores();
  // The ids, read off the candidates in event order: a split leaves its edge auxiliary, a
  // restore makes its auxiliary edge a mesh edge again, and nothing else changes either flag.
  // (A restore may free a candidate that did not split: hence the alive bit in the test.)
  for (int e : scratch_.splits)
    if ((topo_.E.flags[e] & (kAlive | kMesh)) == kAlive) ev.split_edges.push_back(topo_.E.lid[e]);
  for (int e : scratch_.restores)
    if (topo_.E.flags[e] & kMesh) ev.restored_edges.push_back(topo_.E.lid[e]);
  renew_normals();
  return ev;
}

bool FastSimulator::touched(int t) const { return t >= 0 && t < int(tri_stamp_.size()) && tri_stamp_[t] == pass_; }

void FastSimulator::stamp(int t) {
  if (t < 0) return;
  if (t >= int(tri_stamp_.size())) tri_stamp_.resize(std::size_t(t) + 1, 0);
  if (tri_stamp_[t] != pass_) scratch_.changed.push_back(t);
  tri_stamp_[t] = pass_;
}

void FastSimulator::collect_events() {
  AdaptScratch& s = scratch_;
  // The events apply in ascending logical edge id (the order of MODEL.md §4 and of the
  // reference). Two parallel passes over fixed blocks, no sort: the decisions (per slot) are
  // copied to their logical ids, then read back in logical order, each block listing its
  // events' slots. A pending event's edge keeps its slot through the pass: splits free no
  // edge, and restores free only mesh edges, never a pending (auxiliary) one.
  const int n = int(decisions_.size());
  constexpr int kBlock = 16384;  // ids per block: short per-block lists, and blocks for every thread on a large mesh
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
  par_.run(blocks, kBlockGrain, [&](int b0, int b1) {
    for (int b = b0; b < b1; ++b)
      each_nonzero(decisions_.data(), b * kBlock, std::min(n, (b + 1) * kBlock),
                   [&](int e) { by_id_[topo_.E.lid[e]] = decisions_[e]; });
  });
  std::vector<std::vector<int>>& found = s.found;  // per block and kind: slots in id order
  found.resize(2 * std::size_t(blocks));
  par_.run(blocks, kBlockGrain, [&](int b0, int b1) {
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
}

int FastSimulator::apply_splits() {
  AdaptScratch& s = scratch_;
  const Topology& m = topo_;
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
  if (serial_edits_) {  // the definition the rounds reproduce: one split after the other
    int done = 0;
    for (int e : s.splits) {
      if (touched(m.E.tri0[e]) || touched(m.E.tri1[e])) continue;
      if (!split_edge(e)) continue;
      for (int t : m.records[m.E.record[e]].t) stamp(t);
      ++done;
    }
    return done;
  }
  std::vector<SplitPlan>& plans = s.plans;
  std::vector<int>& round_of = s.round_of;
  plans.clear(), round_of.clear();
  // Per-vertex scratch, all 0 between passes (reset below for the vertices used): no pass
  // clears or allocates an array the size of the mesh.
  for (Array<int>* a : {&round_last_, &spring_adds_, &tri_adds_}) a->resize(std::size_t(nv0), 0);
  std::vector<int>& involved = s.involved;  // vertices of accepted splits (i, j, l, r), once each
  std::vector<SplitCandidate>& candidates = s.split_candidates;
  involved.clear();
  int rounds = 0;
  // What the serial pre-pass needs of each candidate, read in parallel into a compact array
  // (the pre-pass then touches only it, the stamps and the rounds).
  candidates.resize(s.splits.size());
  par_.run(int(s.splits.size()), kCandidateGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kFar < e) prefetch_edge(m, s.splits[k + kFar]);
      candidates[k] = split_candidate(s.splits[k]);
    }
  });
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    if (k + kNear < candidates.size()) {
      const SplitCandidate& f = candidates[k + kNear];
      for (int t : f.tris)
        if (t >= 0 && t < int(tri_stamp_.size())) prefetch(&tri_stamp_[t]);
      for (int v : f.ends)
        if (v >= 0) prefetch(&round_last_[v]);
    }
    const SplitCandidate& c = candidates[k];
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
      if (round_last_[v] == 0) involved.push_back(v);  // its first split of the pass
      round_last_[v] = round;
    }
    rounds = std::max(rounds, round);
    for (int t : {tL, tR, p.tris[0], p.tris[1]}) stamp(t);
    plans.push_back(p);
    round_of.push_back(round);
  }
  topo_.fit();  // the slots plan_split took
  // Room in the adjacency lists for every append, so that no block moves while rounds run: a
  // split adds one spring at each of i, j, l, r and, net, one triangle at l and at r (i and j
  // lose their two triangles before they gain two).
  for (const SplitPlan& p : plans) {
    for (int v : p.ends)
      if (v >= 0) ++spring_adds_[v];
    for (int v : {p.ends[2], p.ends[3]})
      if (v >= 0) ++tri_adds_[v];
  }
  for (int v : involved) {
    topo_.make_room(v, m.V.n_springs[v] + spring_adds_[v], m.V.n_tris[v] + tri_adds_[v]);
    round_last_[v] = spring_adds_[v] = tri_adds_[v] = 0;
  }
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
  return int(std::count(applied.begin(), applied.end(), std::uint8_t(1)));
}

int FastSimulator::apply_restores() {
  AdaptScratch& s = scratch_;
  const Topology& m = topo_;
  auto is_touched = [&](int t) { return touched(t); };
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
  if (serial_edits_) {  // the definition the waves reproduce
    int done = 0;
    for (int e : s.restores) {
      const SplitRecord& r = m.records[m.E.record[e]];
      if (std::any_of(r.t.begin(), r.t.end(), is_touched) || !can_restore(e)) continue;
      const auto t = r.t;
      restore_edge(e);
      for (int q : t) stamp(q);
      ++done;
    }
    return done;
  }
  const std::vector<int>& wave_restores = s.restores;
  const int nr = int(wave_restores.size());
  enum : std::uint8_t { kNever, kNotNow, kRestorable };  // a candidate's answer on the state after the splits
  std::vector<RestoreCandidate>& candidates = s.restore_candidates;
  candidates.resize(std::size_t(nr));
  par_.run(nr, kRestoreTestGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kNear < e) prefetch(&m.records[m.E.record[wave_restores[k + kNear]]]);
      const int edge = wave_restores[k];
      const SplitRecord& r = m.records[m.E.record[edge]];
      // is_touched sees the splits' stamps only: a restore's stamps matter to candidates that
      // share its vertices, which wait for a later wave and test it again there.
      const std::uint8_t answer = std::any_of(r.t.begin(), r.t.end(), is_touched) ? kNever
                                  : can_restore(edge)                           ? kRestorable
                                                                                : kNotNow;
      candidates[k] = RestoreCandidate{{r.n, r.k[0], r.k[1], r.k[2], r.k[3]}, answer};
    }
  });
  claim_.resize(std::size_t(m.V.size()), 0);  // all 0 between waves
  std::vector<int>&pending = s.pending, &next = s.next, &wave = s.wave, &claimed = s.claimed;
  pending.clear();
  for (int k = 0; k < nr; ++k)
    if (candidates[k].answer != kNever) pending.push_back(k);
  std::vector<std::pair<int, Freed>>& freed = s.freed;  // (candidate, what its restore freed)
  freed.clear();
  for (bool first = true; !pending.empty(); first = false) {
    next.clear(), wave.clear(), claimed.clear();
    for (std::size_t q = 0; q < pending.size(); ++q) {
      if (q + kFar < pending.size())
        for (int v : candidates[pending[q + kFar]].verts)
          if (v >= 0) prefetch(&claim_[v]);
      const int k = pending[q], e = wave_restores[k];
      const std::array<int, 5>& verts = candidates[k].verts;
      const bool waits = std::any_of(verts.begin(), verts.end(), [&](int v) { return v >= 0 && claim_[v]; });
      if (!waits) {
        if (first && candidates[k].answer != kRestorable) continue;
        if (!first) {
          const SplitRecord& r = m.records[m.E.record[e]];
          if (std::any_of(r.t.begin(), r.t.end(), is_touched) || !can_restore(e)) continue;
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
  return int(freed.size());
}

void FastSimulator::renew_normals() {
  // Bring the areas and normals computed for the decisions up to date where the topology
  // changed, so the next step need not recompute them all: the changed triangles' areas (a dead
  // one gets the zero it has), then the normal of each of their corners, once, by whichever
  // thread claims it first (each normal is a function of the areas alone, so who computes it
  // and in which order changes nothing).
  const std::vector<int>& changed = scratch_.changed;
  const float unit = length_unit();
  vertex_stamp_.resize(std::size_t(topo_.V.size()), 0);
  // Both loops prefetch what the changed triangle kNear on reads: its corners' positions, then
  // its corners' triangle lists (the triangle lines themselves, kFar on): the changed triangles
  // are scattered, so each one's lines miss. Not the areas those lists name: prefetching them too
  // made the renewal slower (docs/PERFORMANCE.md).
  const Vertices& V = topo_.V;
  const Triangles& T = topo_.T;
  Float4* area = topo_.T.area.data();
  const NormalsOut normals{topo_.V.nx.data(), topo_.V.ny.data(), topo_.V.nz.data()};
  par_.run(int(changed.size()), kRenewGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kFar < e) prefetch_triangle(topo_, changed[k + kFar]);
      if (k + kNear < e)
        for (int v : T.corners(changed[k + kNear])) prefetch_read(&V.x[v]), prefetch_read(&V.y[v]), prefetch_read(&V.z[v]);
      triangle_areas(topo_, unit, area, changed[k], changed[k] + 1);
    }
  });
  par_.run(int(changed.size()), kRenewGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kNear < e)
        for (int v : T.corners(changed[k + kNear])) prefetch_read(&V.n_tris[v]), prefetch_read(topo_.tris_of(v));
      const int t = changed[k];
      if (!T.alive[t]) continue;
      for (int v : T.corners(t)) {
        std::atomic_ref<std::uint64_t> mark(vertex_stamp_[v]);
        std::uint64_t seen = mark.load(std::memory_order_relaxed);
        if (seen != pass_ && mark.compare_exchange_strong(seen, pass_, std::memory_order_relaxed))
          vertex_normals(topo_, normals, v, v + 1);
      }
    }
  });
  normals_valid_ = true;
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

std::vector<Decision> FastSimulator::decide() const {
  FastSimulator tmp(*this);
  tmp.adapt_decide();
  std::vector<Decision> out(tmp.decisions_.size());
  const double budget = params_.budget_factor(topo_.live_vertices());
  for (size_t e = 0; e < out.size(); ++e) {
    out[tmp.topo_.E.lid[e]].kind = tmp.decisions_[e];
    out[tmp.topo_.E.lid[e]].margin = tmp.margin(int(e), budget);
  }
  return out;
}

// Decision::margin as the reference defines it, in double from this backend's float state (a
// test hook: the kernel decides in float and keeps no margin). Mesh edges: P_step - u [Eq 6];
// auxiliary edges with a split record: (1 - n_rl)/2 - epsilon [Eq 10]; P_step and epsilon
// scaled by the budget's factor (D22).
double FastSimulator::margin(int e, double budget) const {
  const Vertices& V = topo_.V;
  const Edges& E = topo_.E;
  const std::uint8_t f = E.flags[e];
  auto dot_n = [&](int a, int b) { return double(V.nx[a]) * V.nx[b] + double(V.ny[a]) * V.ny[b] + double(V.nz[a]) * V.nz[b]; };
  if (!(f & kAlive)) return 0;  // a dead slot's indices may be stale
  const int a = E.a[e], b = E.b[e], l = E.wl[e], r = E.wr[e];
  const double n_rl = (l >= 0 && r >= 0) ? dot_n(r, l) : 1.0;
  if (!(f & kMesh)) return (params_.restoration && E.record[e] >= 0) ? (1.0 - n_rl) / 2.0 - budget * params_.epsilon : 0;
  if (!params_.fracture) return 0;
  const double u = uniform(params_.seed, steps_, std::uint32_t(E.lid[e]), Draw::Fracture);
  const double dx = double(V.x[a]) - V.x[b], dy = double(V.y[a]) - V.y[b], dz = double(V.z[a]) - V.z[b];
  const double lt = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(f & kBreakable) || E.l0[e] < scene_.floor_length || !(lt < E.l0[e])) return -u;
  const double c = 1.0 - lt / E.l0[e];
  const double P = std::clamp(0.25 * c * (1 - params_.phi * dot_n(a, b)) * (1 + params_.phi * n_rl), 0.0, 1.0);
  return budget * (1.0 - std::pow(1.0 - P, params_.adapt_interval() / kReferenceStep)) - u;
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
