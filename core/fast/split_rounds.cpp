#include "fast/split_rounds.h"

#include <algorithm>

#include "fast/event_prefetch.h"
#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
constexpr int kRoundGrain = 64;       ///< smaller rounds run inline: too few splits to repay a parallel loop's start
constexpr int kCandidateGrain = 256;  ///< a candidate read misses several lines: smaller chunks repay
}  // namespace

void SplitRounds::reserve(std::size_t vertices) { tally_.reserve_warm(vertices); }

int SplitRounds::apply(FastSimulator& sim, const std::vector<int>& splits, TriangleStamps& stamps) {
  const int rounds = plan(sim, splits, stamps);
  sim.topo_.fit();  // the slots plan_split took
  make_room(sim);
  return run_rounds(sim, rounds);
}

// The serial pre-pass: acceptance, new ids and rounds, in event order. What it needs of each
// candidate is read in parallel first into a compact array, so that the serial loop touches only
// that array, the stamps and the rounds. Returns the number of rounds.
int SplitRounds::plan(FastSimulator& sim, const std::vector<int>& splits, TriangleStamps& stamps) {
  const Topology& m = sim.topo_;
  tally_.resize(std::size_t(m.V.size()), Tally{});
  plans_.clear(), round_of_.clear(), involved_.clear();
  candidates_.resize(splits.size());
  sim.par_.run(int(splits.size()), kCandidateGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kFar < e) prefetch_edge(m, splits[k + kFar]);
      candidates_[k] = sim.split_candidate(splits[k]);
    }
  });
  int rounds = 0;
  for (std::size_t k = 0; k < candidates_.size(); ++k) {
    if (k + kNear < candidates_.size()) {
      const SplitCandidate& f = candidates_[k + kNear];
      for (int t : f.tris)
        if (const std::uint64_t* line = stamps.line_of(t)) prefetch(line);
      for (int v : f.ends)
        if (v >= 0) prefetch(&tally_[v]);
    }
    const SplitCandidate& c = candidates_[k];
    if (stamps.touched(c.tris[0]) || stamps.touched(c.tris[1])) continue;
    const SplitPlan p = sim.plan_split(c);
    if (p.e < 0) continue;
    int round = 0;
    for (int v : c.ends)
      if (v >= 0) round = std::max(round, tally_[v].round_last);
    ++round;
    // Room in the adjacency lists for every append (make_room): a split adds one spring at each
    // of i, j, l, r and, net, one triangle at l and at r (the entries of i and j change in
    // place: fast_edits.cpp).
    for (int q = 0; q < 4; ++q) {
      const int v = c.ends[q];
      if (v < 0) continue;
      Tally& t = tally_[v];
      if (t.round_last == 0) involved_.push_back(v);  // its first split of the pass
      t.round_last = round;
      ++t.spring_adds;
      t.tri_adds += q >= 2;
    }
    rounds = std::max(rounds, round);
    for (int t : {c.tris[0], c.tris[1], p.tris[0], p.tris[1]}) stamps.mark(t);
    plans_.push_back(p);
    round_of_.push_back(round);
  }
  return rounds;
}

// Room in the adjacency lists for every append the plan counted, so that no block moves while
// rounds run (serial: a moved block is appended at the list arrays' end).
void SplitRounds::make_room(FastSimulator& sim) {
  Topology& m = sim.topo_;
  const std::size_t n = involved_.size();
  for (std::size_t k = 0; k < n; ++k) {
    if (k + kNear < n) {
      const int w = involved_[k + kNear];
      prefetch_read(&m.V.spring_list[w]), prefetch_read(&m.V.tri_list[w]);
    }
    const int v = involved_[k];
    Tally& t = tally_[v];
    m.make_room(v, m.V.spring_list[v].count + t.spring_adds, m.V.tri_list[v].count + t.tri_adds);
    t = Tally{};
  }
}

void SplitRounds::touched(std::vector<int>& out) const {
  for (std::size_t k = 0; k < plans_.size(); ++k) {
    if (!applied_[k]) continue;
    append_live(plans_[k].ends.begin(), plans_[k].ends.end(), out);
    out.push_back(plans_[k].n);
  }
}

// The rounds, each a parallel loop over its splits (in event order within the round).
int SplitRounds::run_rounds(FastSimulator& sim, int rounds) {
  const Topology& m = sim.topo_;
  by_round_.resize(plans_.size());
  start_.assign(std::size_t(rounds) + 2, 0);
  for (int r : round_of_) ++start_[r + 1];
  for (int r = 1; r <= rounds; ++r) start_[r + 1] += start_[r];
  fill_.assign(start_.begin(), start_.end());
  for (std::size_t k = 0; k < plans_.size(); ++k) by_round_[fill_[round_of_[k]]++] = int(k);
  applied_.assign(plans_.size(), 0);
  for (int r = 1; r <= rounds; ++r) {
    large_rounds_ += start_[r + 1] - start_[r] > kRoundGrain;
    sim.par_.run(start_[r + 1] - start_[r], kRoundGrain, [&](int b, int e) {
      for (int k = start_[r] + b; k < start_[r] + e; ++k) {
        if (k + kNear < start_[r] + e) prefetch_split(m, plans_[by_round_[k + kNear]].e);
        const int i = by_round_[k];
        applied_[i] = sim.apply_split(plans_[i]);
      }
    });
  }
  return int(std::count(applied_.begin(), applied_.end(), std::uint8_t(1)));
}

}  // namespace crumple::fast
