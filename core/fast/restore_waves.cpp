#include "fast/restore_waves.h"

#include <algorithm>

#include "fast/event_prefetch.h"
#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
constexpr int kWaveGrain = 32;          ///< waves are smaller than rounds, and a restore costs about what a split does
constexpr int kRestoreTestGrain = 128;  ///< a restore test reads a record and its triangles: more per item
}  // namespace

void RestoreWaves::reserve(std::size_t vertices) { wave_last_.reserve_warm(vertices); }

int RestoreWaves::apply(FastSimulator& sim, const std::vector<int>& restores, const std::vector<int>& records,
                        const PassStamps& stamps) {
  pretest(sim, records, stamps);
  wave_last_.resize(std::size_t(sim.topo_.V.size()), 0);  // all 0 between passes
  const int waves = assign_waves();
  const Topology& m = sim.topo_;
  freed_.resize(restorable_.size());
  auto candidate_at = [&](int q) { return restorable_[by_wave_[q]]; };  // at place q of the waves
  for (int w = 0; w < waves; ++w) {
    const int first = start_[w], size = start_[w + 1] - first;
    sim.par_.run(size, kWaveGrain, [&](int b, int e) {
      const int end = first + e;
      for (int q = first + b; q < end; ++q) {
        if (q + kFar < end) {
          const int k = candidate_at(q + kFar);
          prefetch(&m.records[candidates_[k].record]), prefetch_edge(m, restores[k]);
        }
        if (q + kNear < end) prefetch_restore(m, m.records[candidates_[candidate_at(q + kNear)].record]);
        const int p = by_wave_[q], k = restorable_[p];
        freed_[p] = {k, sim.restore_edge_local(restores[k])};
        renew_normals(sim, candidates_[k].verts);
      }
    });
    large_waves_ += size > kWaveGrain;
  }
  return int(freed_.size());
}

void RestoreWaves::free_ids(Topology& m) const {
  for (const auto& f : freed_) m.free_ids(f.second);
}

void RestoreWaves::applied_edges(const std::vector<int>& restores, std::vector<int>& out) const {
  for (const auto& f : freed_) out.push_back(restores[std::size_t(f.first)]);
}

// The normals of a restore's live vertices i, j, l, r (n is released), renewed while their
// lists and the restore's areas are in cache. No event reads a normal after the splits, and a
// later restore at a vertex renews it again: the last leaves the normal of the final areas. The
// renewal reads the vertex's list and the areas of its triangles, which only the events at the
// vertex write: the restores of a wave, vertex-disjoint, neither race nor depend on their order.
void RestoreWaves::renew_normals(FastSimulator& sim, const std::array<int, 5>& verts) {
  Topology& m = sim.topo_;
  for (int q = 1; q < 5; ++q)
    if (verts[q] >= 0) vertex_normal(m, m.V.nr.data(), verts[q]);
}

std::vector<RestoreWaves::Applied> RestoreWaves::applied() const {
  std::vector<Applied> out;
  for (const auto& f : freed_) out.push_back({f.first, candidates_[std::size_t(f.first)].wave, candidates_[std::size_t(f.first)].verts});
  return out;
}

// Every candidate's answer on the state after the splits, in parallel: restorable unless an
// accepted split of the pass changed a triangle of its record (the splits' stamps) or
// can_restore says no. No restore of the pass changes it (the class comment). A candidate stays
// an alive auxiliary edge with the same split record through the splits (a split changes the
// flags and record of its own mesh edge alone, takes only free slots and records, and frees
// nothing), so its record, carried from the decisions, is all the test reads: not the edge.
void RestoreWaves::pretest(FastSimulator& sim, const std::vector<int>& records, const PassStamps& stamps) {
  const Topology& m = sim.topo_;
  const int nr = int(records.size());
  candidates_.resize(std::size_t(nr));
  sim.par_.run(nr, kRestoreTestGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kNear < e) prefetch(&m.records[records[k + kNear]]);
      const SplitRecord& r = m.records[records[k]];
      candidates_[k] = Candidate{{r.n, r.k[0], r.k[1], r.k[2], r.k[3]}, !stamps.any_touched(r.t) && sim.can_restore_record(r), -1, records[k]};
    }
  });
}

// Serial, but it reads only the candidates' vertices and one int a vertex: the restores' records
// were read by the parallel pretest.
int RestoreWaves::assign_waves() {
  restorable_.clear(), claimed_.clear();
  for (int k = 0; k < int(candidates_.size()); ++k)
    if (candidates_[k].restorable) restorable_.push_back(k);
  int waves = 0;
  for (std::size_t p = 0; p < restorable_.size(); ++p) {
    if (p + kFar < restorable_.size())
      for (int v : candidates_[restorable_[p + kFar]].verts)
        if (v >= 0) prefetch(&wave_last_[v]);
    Candidate& c = candidates_[restorable_[p]];
    int wave = 0;  // one past the last wave at any of its vertices
    for (int v : c.verts)
      if (v >= 0) wave = std::max(wave, wave_last_[v]);
    for (int v : c.verts) {
      if (v < 0) continue;
      if (!wave_last_[v]) claimed_.push_back(v);
      wave_last_[v] = wave + 1;
    }
    c.wave = wave;
    waves = std::max(waves, wave + 1);
  }
  for (int v : claimed_) wave_last_[v] = 0;
  order_by_group(int(restorable_.size()), waves, [&](int p) { return candidates_[restorable_[p]].wave; }, start_, by_wave_);
  return waves;
}

}  // namespace crumple::fast
