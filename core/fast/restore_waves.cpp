#include "fast/restore_waves.h"

#include <algorithm>

#include "fast/event_prefetch.h"
#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
constexpr int kWaveGrain = 32;          ///< waves are smaller than rounds, and a restore costs about what a split does
constexpr int kRestoreTestGrain = 128;  ///< a restore test reads a record and its triangles: more per item
}  // namespace

void RestoreWaves::reserve(std::size_t vertices) { claim_.reserve_warm(vertices); }

int RestoreWaves::apply(FastSimulator& sim, const std::vector<int>& restores, TriangleStamps& stamps) {
  pretest(sim, restores, stamps);
  claim_.resize(std::size_t(sim.topo_.V.size()), 0);  // all 0 between waves
  pending_.clear();
  for (int k = 0; k < int(candidates_.size()); ++k)
    if (candidates_[k].restorable) pending_.push_back(k);
  freed_.clear();
  const Topology& m = sim.topo_;
  for (int wave = 0; !pending_.empty(); ++wave) {
    scan(restores, m, stamps, wave);
    const std::size_t done = freed_.size();
    freed_.resize(done + wave_.size());
    sim.par_.run(int(wave_.size()), kWaveGrain, [&](int b, int e) {
      for (int q = b; q < e; ++q) {
        if (q + kNear < e) prefetch_restore(m, restores[wave_[q + kNear]]);
        const int k = wave_[q];
        freed_[done + q] = {k, sim.restore_edge_local(restores[k])};
      }
    });
    for (int v : claimed_) claim_[v] = 0;
    large_waves_ += wave_.size() > std::size_t(kWaveGrain);
    pending_.swap(next_);
  }
  std::sort(freed_.begin(), freed_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return int(freed_.size());
}

void RestoreWaves::free_ids(Topology& m) const {
  for (const auto& f : freed_) m.free_ids(f.second);
}

void RestoreWaves::touched(std::vector<int>& out) const {
  for (const auto& f : freed_) {
    const auto& verts = candidates_[std::size_t(f.first)].verts;
    append_live(verts.begin() + 1, verts.end(), out);  // verts[0] is n, released
  }
}

std::vector<RestoreWaves::Applied> RestoreWaves::applied() const {
  std::vector<Applied> out;
  for (const auto& f : freed_) out.push_back({f.first, candidates_[std::size_t(f.first)].wave, candidates_[std::size_t(f.first)].verts});
  return out;
}

// Every candidate's answer on the state after the splits, in parallel: restorable unless an
// accepted split of the pass changed a triangle of its record (the splits' stamps) or
// can_restore says no. No restore of the pass changes it (the class comment).
void RestoreWaves::pretest(FastSimulator& sim, const std::vector<int>& restores, const TriangleStamps& stamps) {
  const Topology& m = sim.topo_;
  const int nr = int(restores.size());
  candidates_.resize(std::size_t(nr));
  sim.par_.run(nr, kRestoreTestGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kNear < e) prefetch(&m.records[m.E[restores[k + kNear]].record]);
      const SplitRecord& r = m.records[m.E[restores[k]].record];
      candidates_[k] = Candidate{{r.n, r.k[0], r.k[1], r.k[2], r.k[3]}, !stamps.any_touched(r.t) && sim.can_restore(restores[k]), -1};
    }
  });
}

void RestoreWaves::scan(const std::vector<int>& restores, const Topology& m, TriangleStamps& stamps, int wave) {
  next_.clear(), wave_.clear(), claimed_.clear();
  for (std::size_t q = 0; q < pending_.size(); ++q) {
    if (q + kFar < pending_.size())
      for (int v : candidates_[pending_[q + kFar]].verts)
        if (v >= 0) prefetch(&claim_[v]);
    const int k = pending_[q];
    const std::array<int, 5>& verts = candidates_[k].verts;
    const bool waits = std::any_of(verts.begin(), verts.end(), [&](int v) { return v >= 0 && claim_[v]; });
    for (int v : verts)
      if (v >= 0 && !claim_[v]) claim_[v] = k + 1, claimed_.push_back(v);
    if (waits) {
      next_.push_back(k);
      continue;
    }
    wave_.push_back(k);
    candidates_[k].wave = wave;
    for (int t : m.records[m.E[restores[k]].record].t) stamps.mark(t);
  }
}

}  // namespace crumple::fast
