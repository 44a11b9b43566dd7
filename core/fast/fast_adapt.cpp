// The adaptive mesh of the fast backend (MODEL.md §4, §5, §7), the topology pass: decisions by
// the adapt_test kernel in parallel, then the events in the order of the reference backend
// (splits in parallel rounds, split_rounds.h; restores in parallel waves, restore_waves.h; each
// with the serial result of serial_events.h), then the areas and normals renewed where
// triangles changed. One event's edits are in fast_edits.cpp.
#include <algorithm>
#include <bit>
#include <cmath>

#include "fast/event_prefetch.h"
#include "fast/fast_sim.h"
#include "fast/pass_timer.h"
#include "fast/radix.h"
#include "fast/serial_events.h"
#include "model/random.h"

namespace crumple::fast {

namespace {
constexpr double kReferenceStep = 1.0 / 60.0;  ///< h_ref of P_step (MODEL.md §4)

/// adapt_test streams cheaply over every edge: large blocks, each a whole number of the
/// vector lanes of Parallel::run_lanes, so every edge takes the same code path on any thread count.
constexpr int kTestBlock = 4096;
static_assert(kTestBlock % Parallel::kLanes == 0);
/// The renewal scans every vertex's stamp for the few it renews: chunks of many slots, each
/// in parts of kRenewPart slots whose marked vertices are listed on the stack.
constexpr int kRenewGrain = 8192;
constexpr int kRenewPart = 512;

/// Sorts keys (id << 32 | slot, ids unique and below 2^id_bits) by id, in least-significant-
/// digit radix passes (radix.h) between keys and spare: a few streaming passes where a
/// comparison sort of the step's thousands of keys costs a dozen compares a key.
void sort_by_id(const Parallel& par, std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& spare,
                std::vector<int>& count, int id_bits) {
  const RadixDigits d = radix_digits(id_bits);
  const std::uint64_t mask = (std::uint64_t(1) << d.bits) - 1;
  spare.resize(keys.size());
  for (int shift = 32; shift < 32 + d.passes * d.bits; shift += d.bits) {
    const std::uint64_t* from = keys.data();
    std::uint64_t* to = spare.data();
    stable_pass(par, count, int(keys.size()), 1 << d.bits, [&](int k) { return int((from[k] >> shift) & mask); },
                [&](int k, int at) { to[at] = from[k]; });
    keys.swap(spare);
  }
}
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
  const int n = topo_.E.size();
  decisions_.resize(std::size_t(n));
  events_.found.resize(2 * std::size_t(Parallel::blocks_of(n, kTestBlock)));
  par_.run_blocks(n, kTestBlock, [&](int b, int begin, int end) {
    adapt_test(topo_, c, decisions_.data(), begin, end);
    list_events(b, begin, end);
  });
}

// Block b's events, listed while its decisions and its edges' ids are still in cache from the
// test (the pass would otherwise read them again, each at random, to order the events).
void FastSimulator::list_events(int b, int begin, int end) {
  std::vector<std::uint64_t>& splits = events_.found[2 * std::size_t(b)];
  std::vector<std::uint64_t>& restores = events_.found[2 * std::size_t(b) + 1];
  splits.clear(), restores.clear();
  const std::int32_t* lid = topo_.E.lid.data();
  for_each_byte<false>(decisions_.data(), 0, begin, end, [&](int e) {
    const std::uint64_t key = std::uint64_t(std::uint32_t(lid[e])) << 32 | std::uint32_t(e);
    (decisions_[e] == 1 ? splits : restores).push_back(key);
  });
}

StepEvents FastSimulator::adapt_apply() {
  stamps_.begin_pass();
  collect_events();
  std::vector<int>& splits = events_.splits;
  if (params_.max_vertices > 0)  // the hard guard, as the reference: the budget's first candidates
    splits.resize(std::min<std::size_t>(splits.size(), std::max(0, params_.max_vertices - topo_.live_vertices())));
  StepEvents ev;
  touched_.clear();
  if (serial_edits_) {
    ev.splits = SerialEvents::splits(*this, splits, stamps_, touched_);
    ev.restores = SerialEvents::restores(*this, events_.restores, stamps_, touched_);
  } else {
    ev.splits = rounds_.apply(*this, splits, stamps_);
    ev.restores = waves_.apply(*this, events_.restores, stamps_);
  }
  // What is left touches two disjoint sets of data, so the serial parts run side by side: the
  // freed ids onto the free lists and the events' ids for the caller on one thread; the
  // vertices to renew listed, then their normals renewed, on the other (a parallel loop the
  // first thread joins when it is done).
  par_.invoke(
      [&] {
        if (!serial_edits_) waves_.free_ids(topo_);
        list_event_ids(ev);
      },
      [&] {
        if (!serial_edits_) rounds_.touched(touched_), waves_.touched(touched_);
        renew_normals();
      });
  return ev;
}

// The ids of the applied events, in event order. The rounds and waves know which they applied,
// so only those edges' ids are read: most restore candidates are not restorable (they wait on a
// later split at their vertex n, can_restore), and a scan of every candidate's edge would read a
// line at random for each.
void FastSimulator::list_event_ids(StepEvents& ev) const {
  if (serial_edits_) return list_event_ids_by_flags(ev);
  rounds_.applied_edges(ev.split_edges);
  waves_.applied_edges(events_.restores, ev.restored_edges);
  for (std::vector<int>* ids : {&ev.split_edges, &ev.restored_edges})
    for (int& e : *ids) e = topo_.E.lid[e];
}

// The same ids read off every candidate's flags (the serial edits' form, which the tests
// compare with the rounds' and waves' lists): a split leaves its edge auxiliary, a restore makes its auxiliary
// edge a mesh edge again, and nothing else changes either flag. (A restore may free a candidate
// that did not split: hence the alive bit in the test.)
void FastSimulator::list_event_ids_by_flags(StepEvents& ev) const {
  for (int e : events_.splits)
    if ((topo_.E[e].flags & (kAlive | kMesh)) == kAlive) ev.split_edges.push_back(topo_.E.lid[e]);
  for (int e : events_.restores)
    if (topo_.E[e].flags & kMesh) ev.restored_edges.push_back(topo_.E.lid[e]);
}

void FastSimulator::collect_events() {
  // The events apply in ascending logical edge id (the order of MODEL.md §4 and of the
  // reference): each kind's keys from every block, sorted by id (ids are unique, so the order is
  // total). A pending event's edge keeps its slot through the pass: splits free no edge, and
  // restores free only mesh edges, never a pending (auxiliary) one.
  EventLists& s = events_;
  const int id_bits = std::bit_width(unsigned(topo_.E.phys.size()));
  for (int kind : {0, 1}) {
    s.keys.clear();
    for (std::size_t b = std::size_t(kind); b < s.found.size(); b += 2)
      s.keys.insert(s.keys.end(), s.found[b].begin(), s.found[b].end());
    sort_by_id(par_, s.keys, s.spare, s.count, id_bits);
    std::vector<int>& slots = kind == 0 ? s.splits : s.restores;
    slots.resize(s.keys.size());
    for (std::size_t k = 0; k < s.keys.size(); ++k) slots[k] = int(std::uint32_t(s.keys[k]));
  }
}

void FastSimulator::renew_normals() {
  // Bring the normals computed for the decisions up to date where the topology changed, so the
  // next step need not recompute them all: the normal of each corner of a live changed triangle,
  // once (each normal is a function of the areas alone, so the order changes nothing). The
  // changed triangles' areas are current: each split and restore computed its own.
  mark_renewed_vertices();
  // In slot order, a scan of the stamps: the layout keeps a vertex's list and its triangles'
  // areas near its neighbours' (layout.h), so the renewed vertices share lines that in event
  // order each would miss alone. A part's marked vertices are listed first, so that the loop
  // can prefetch kNear on: the vertex's list head and its list (not the areas the list names:
  // prefetching them too made the renewal slower, docs/PERFORMANCE.md).
  const Vertices& V = topo_.V;
  Float4* normals = topo_.V.nr.data();
  par_.run(V.size(), kRenewGrain, [&](int b, int e) {
    int marked[kRenewPart];
    for (int first = b; first < e; first += kRenewPart) {
      int n = 0;
      vertex_stamps_.for_each_marked(first, std::min(e, first + kRenewPart), [&](int v) { marked[n++] = v; });
      for (int k = 0; k < n; ++k) {
        if (k + kNear < n) prefetch_read(&V.tri_list[marked[k + kNear]]), prefetch_read(topo_.tris_of(marked[k + kNear]));
        vertex_normals(topo_, normals, marked[k], marked[k] + 1);
      }
    }
  });
  normals_valid_ = true;
}

// The vertices of the pass's applied events: the corners of its live changed triangles (a
// split's i, j, l, r and n; a restore's i, j, l, r), listed by the events from their own compact
// records rather than read back from each changed triangle, marked in the vertex stamps
// (serial: a vertex of several events is marked by each, where a parallel mark would race).
void FastSimulator::mark_renewed_vertices() {
  vertex_stamps_.begin_pass();
  vertex_stamps_.cover(std::size_t(topo_.V.size()));
  for (int v : touched_) vertex_stamps_.mark(v);  // one byte a vertex: the stamps stay in L2
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
  if (ev.splits > 0 || ev.restores > 0) colors_.invalidate();
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
  const std::uint8_t f = E[e].flags;
  auto dot_n = [&](int a, int b) {
    const Float4 na = V.nr[a], nb = V.nr[b];
    return double(na.x) * nb.x + double(na.y) * nb.y + double(na.z) * nb.z;
  };
  if (!(f & kAlive)) return 0;  // a dead slot's indices may be stale
  const int a = E[e].a, b = E[e].b, l = E[e].wl, r = E[e].wr;
  const double n_rl = (l >= 0 && r >= 0) ? dot_n(r, l) : 1.0;
  if (!(f & kMesh)) return (params_.restoration && E[e].record >= 0) ? (1.0 - n_rl) / 2.0 - budget * params_.epsilon : 0;
  if (!params_.fracture) return 0;
  const double u = uniform(params_.seed, steps_, std::uint32_t(E.lid[e]), Draw::Fracture);
  const Float4 pa = V.xm[a], pb = V.xm[b];
  const double dx = double(pa.x) - pb.x, dy = double(pa.y) - pb.y, dz = double(pa.z) - pb.z;
  const double lt = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(f & kBreakable) || E[e].l0 < scene_.floor_length || !(lt < E[e].l0)) return -u;
  const double c = 1.0 - lt / E[e].l0;
  const double P = std::clamp(0.25 * c * (1 - params_.phi * dot_n(a, b)) * (1 + params_.phi * n_rl), 0.0, 1.0);
  return budget * (1.0 - std::pow(1.0 - P, params_.adapt_interval() / kReferenceStep)) - u;
}

bool FastSimulator::split(int id) {
  if (id < 0 || id >= topo_.E.size()) return false;
  compute_normals();
  normals_valid_ = false;
  colors_.invalidate();
  return split_edge(topo_.E.phys[id]);
}

bool FastSimulator::restore(int id) {
  if (id < 0 || id >= topo_.E.size()) return false;
  const int e = topo_.E.phys[id];
  if (!can_restore(e)) return false;
  normals_valid_ = false;
  colors_.invalidate();
  restore_edge(e);
  return true;
}

}  // namespace crumple::fast
