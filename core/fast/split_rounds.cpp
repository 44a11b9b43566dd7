#include "fast/split_rounds.h"

#include <algorithm>
#include <stdexcept>

#include "fast/event_prefetch.h"
#include "fast/fast_sim.h"

namespace crumple::fast {

namespace {
constexpr int kRoundGrain = 64;       ///< smaller rounds run inline: too few splits to repay a parallel loop's start
constexpr int kCandidateGrain = 256;  ///< a candidate read misses several lines: smaller chunks repay
constexpr int kTakeGrain = 512;       ///< a plan's takes miss a line or two (the free ids' slots)
}  // namespace

void SplitRounds::reserve(std::size_t vertices) { tally_.reserve_warm(vertices); }

int SplitRounds::apply(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps) {
  const int rounds = plan(sim, splits, stamps);
  // Both follow from the acceptance alone and touch disjoint data (make_room: the tallies and
  // the existing vertices' list heads and pools; take_ids: the free lists, ids, records, plans
  // and stamps), so the serial room runs beside the ids' parallel loop. fit comes after both:
  // it sizes the arrays for the slots take_ids took, and make_room needs none of them (a split's
  // ends existed before the pass).
  sim.par_.invoke([&] { make_room(sim); }, [&] { take_ids(sim, stamps); });
  sim.topo_.fit();
  // A list that outgrew its block during the rounds would have moved it to its pool's end from
  // two threads at once (list_spring's serial fallback): make_room must have given every list
  // its room. Two size tests a pass make that a loud failure rather than a rare race.
  const std::size_t springs = sim.topo_.V.springs.size(), tris = sim.topo_.V.tris.size();
  const int applied = run_rounds(sim, rounds);
  if (sim.topo_.V.springs.size() != springs || sim.topo_.V.tris.size() != tris)
    throw std::logic_error("split rounds: an adjacency list moved its block while rounds ran");
  return applied;
}

// The pre-pass: acceptance and rounds serially in event order. What the serial loop needs of
// each candidate is read in parallel first into a compact array, so that it touches only that
// array, the stamps and the rounds; it counts the ids each accepted split takes, so that the
// plans can look theirs up in parallel and take them all at once after (take_ids). Returns the
// number of rounds.
int SplitRounds::plan(FastSimulator& sim, const std::vector<int>& splits, PassStamps& stamps) {
  const Topology& m = sim.topo_;
  tally_.resize(std::size_t(m.V.size()), Tally{});
  accepted_.clear(), round_of_.clear(), involved_.clear();
  candidates_.resize(splits.size());
  sim.par_.run(int(splits.size()), kCandidateGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      if (k + kFar < e) prefetch_edge(m, splits[k + kFar]);
      candidates_[k] = sim.split_candidate(splits[k]);
    }
  });
  return accept(stamps);
}

// Acceptance (D13) and rounds, serially in event order.
int SplitRounds::accept(PassStamps& stamps) {
  int rounds = 0, edges = 0, tris = 0;
  for (std::size_t k = 0; k < candidates_.size(); ++k) {
    if (k + kNear < candidates_.size()) {
      const SplitCandidate& f = candidates_[k + kNear];
      for (int t : f.tris)
        if (const std::uint8_t* line = stamps.line_of(t)) prefetch(line);
      for (int v : f.ends)
        if (v >= 0) prefetch(&tally_[v]);
    }
    const SplitCandidate& c = candidates_[k];
    if (c.e < 0 || stamps.touched(c.tris[0]) || stamps.touched(c.tris[1])) continue;
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
    for (int t : c.tris) stamps.mark(t);
    accepted_.push_back(Accepted{int(k), edges, tris});
    edges += 2 + (c.ends[2] >= 0) + (c.ends[3] >= 0);  // plan_split's takes
    tris += (c.tris[0] >= 0) + (c.tris[1] >= 0);
    round_of_.push_back(round);
  }
  edges_taken_ = edges, tris_taken_ = tris;
  return rounds;
}

// The accepted splits' plans, in parallel: each looks its new ids up at its place in the pass's
// takes, and marks its new triangles (slots no candidate of the pass had, so the acceptance did
// not read their stamps); then every id is taken at once.
void SplitRounds::take_ids(FastSimulator& sim, PassStamps& stamps) {
  Topology& m = sim.topo_;
  const int n = int(accepted_.size());
  plans_.resize(accepted_.size());
  const int fresh_tris = std::max(0, tris_taken_ - int(m.T.free_ids.size()));  // takes past the free list
  stamps.cover(m.T.lid.size() + std::size_t(fresh_tris));
  sim.par_.run(n, kTakeGrain, [&](int b, int e) {
    for (int j = b; j < e; ++j) {
      const Accepted& a = accepted_[j];
      plans_[j] = sim.plan_split_at(candidates_[a.candidate], j, a.edge_at, a.tri_at);
      for (int t : plans_[j].tris) stamps.mark(t);
    }
  });
  m.take_batch(n, edges_taken_, tris_taken_, n);
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
    t.spring_adds = t.tri_adds = 0;  // the rounds read the rest (renew_normals)
  }
}

void SplitRounds::applied_edges(std::vector<int>& out) const {
  for (const SplitPlan& p : plans_) out.push_back(p.e);
}

std::vector<SplitRounds::Applied> SplitRounds::applied() const {
  std::vector<Applied> out;
  for (std::size_t k = 0; k < plans_.size(); ++k) {
    const SplitPlan& p = plans_[k];
    out.push_back({accepted_[k].candidate, round_of_[k], {p.ends[0], p.ends[1], p.ends[2], p.ends[3], p.n}});
  }
  return out;
}

// The rounds, each a parallel loop over its splits (in event order within the round).
int SplitRounds::run_rounds(FastSimulator& sim, int rounds) {
  const Topology& m = sim.topo_;
  order_by_group(int(plans_.size()), rounds + 1, [&](int k) { return round_of_[k]; }, start_, by_round_);  // rounds from 1
  for (int r = 1; r <= rounds; ++r) {
    large_rounds_ += start_[r + 1] - start_[r] > kRoundGrain;
    sim.par_.run(start_[r + 1] - start_[r], kRoundGrain, [&](int b, int e) {
      const int end = start_[r] + e;
      for (int k = start_[r] + b; k < end; ++k) {
        if (k + kFar < end) prefetch_edge(m, plans_[by_round_[k + kFar]].e);
        if (k + kNear < end) {
          const int ahead = by_round_[k + kNear];
          prefetch_split(m, plans_[ahead].ends, candidates_[accepted_[ahead].candidate].tris);
        }
        const int i = by_round_[k];
        sim.apply_split(plans_[i]);
        renew_normals(sim, plans_[i], r);
      }
    });
  }
  return int(plans_.size());  // every accepted split applies
}

// The normals of a split's vertices, renewed while their lists and the split's areas are in
// cache. A later split of the pass reads the normals of its edge's ends as the decisions saw them
// (apply_split, [Eq 7]), so a vertex is renewed at its last split of the pass only (after that
// split's own read), once; a later restore at it renews it again. n is no split's end (the
// pass's split edges existed before it), and no later split changes its triangles. The renewal
// reads the vertex's list and the areas of its triangles, which only the events at the vertex
// write: the splits of a round, vertex-disjoint, neither race nor depend on their order.
void SplitRounds::renew_normals(FastSimulator& sim, const SplitPlan& plan, int round) {
  Topology& m = sim.topo_;
  for (int v : plan.ends) {
    if (v < 0 || tally_[v].round_last != round) continue;
    vertex_normal(m, m.V.nr.data(), v);
    tally_[v] = Tally{};  // the vertex's last split of the pass
  }
  vertex_normal(m, m.V.nr.data(), plan.n);
}

}  // namespace crumple::fast
