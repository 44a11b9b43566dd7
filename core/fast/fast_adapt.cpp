// The adaptive mesh of the fast backend (MODEL.md §4, §5, §7), the topology pass: decisions by
// the adapt_test kernel in parallel, then the events in the order of the reference backend
// (splits in parallel rounds, split_rounds.h; restores in parallel waves, restore_waves.h; each
// with the serial result of serial_events.h); each event computes its triangles' areas, and
// the rounds and waves renew the normals event by event (the serial edits after all events).
// One event's edits are in fast_edits.cpp.
#include <algorithm>
#include <bit>
#include <cmath>

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
/// Sorts keys (id << 32 | a payload, ids unique and below 2^id_bits) by id, in least-significant-
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
  events_.found_records.resize(events_.found.size() / 2);
  par_.run_blocks(n, kTestBlock, [&](int b, int begin, int end) {
    adapt_test(topo_, c, decisions_.data(), begin, end);
    list_events(b, begin, end);
  });
}

// Block b's events, listed while its decisions and its edges' ids and records are still in
// cache from the test (the pass would otherwise read them again, each at random, to order the
// events; and the restores' pre-test, to find each candidate's split record).
void FastSimulator::list_events(int b, int begin, int end) {
  std::vector<std::uint64_t>& splits = events_.found[2 * std::size_t(b)];
  std::vector<std::uint64_t>& restores = events_.found[2 * std::size_t(b) + 1];
  std::vector<int>& records = events_.found_records[std::size_t(b)];
  splits.clear(), restores.clear(), records.clear();
  const std::int32_t* lid = topo_.E.lid.data();
  for_each_byte<false>(decisions_.data(), 0, begin, end, [&](int e) {
    const std::uint64_t key = std::uint64_t(std::uint32_t(lid[e])) << 32 | std::uint32_t(e);
    if (decisions_[e] == 1) {
      splits.push_back(key);
    } else {
      restores.push_back(key);
      records.push_back(topo_.E[e].record);
    }
  });
}

StepEvents FastSimulator::adapt_apply() {
  stamps_.begin_pass();
  collect_events();
  std::vector<int>& splits = events_.splits;
  if (params_.max_vertices > 0)  // the hard guard, as the reference: the budget's first candidates
    splits.resize(std::min<std::size_t>(splits.size(), std::max(0, params_.max_vertices - topo_.live_vertices())));
  StepEvents ev;
  if (serial_edits_) {
    touched_.clear();
    ev.splits = SerialEvents::splits(*this, splits, stamps_, touched_);
    ev.restores = SerialEvents::restores(*this, events_.restores, stamps_, touched_);
    renew_normals_of_touched();
    list_event_ids_by_flags(ev);
  } else {
    // The rounds and waves renewed the normals event by event. What is left touches two
    // disjoint sets of data, so it runs side by side: the freed ids onto the free lists, and
    // the events' ids for the caller.
    ev.splits = rounds_.apply(*this, splits, stamps_);
    ev.restores = waves_.apply(*this, events_.restores, events_.restore_records, stamps_);
    par_.invoke([&] { waves_.free_ids(topo_); }, [&] { list_event_ids(ev); });
  }
  normals_valid_ = true;
  return ev;
}

// The ids of the applied events, in event order. The rounds and waves know which they applied,
// so only those edges' ids are read: most restore candidates are not restorable (they wait on a
// later split at their vertex n, can_restore), and a scan of every candidate's edge would read a
// line at random for each.
void FastSimulator::list_event_ids(StepEvents& ev) const {
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
  s.keys.clear();
  for (std::size_t b = 0; b < s.found.size(); b += 2) s.keys.insert(s.keys.end(), s.found[b].begin(), s.found[b].end());
  sort_by_id(par_, s.keys, s.spare, s.count, id_bits);
  s.splits.resize(s.keys.size());
  for (std::size_t k = 0; k < s.keys.size(); ++k) s.splits[k] = int(std::uint32_t(s.keys[k]));
  // A restore's key carries its place in `carried` below its id instead of its slot, so that
  // its split record follows it through the sort to the waves' pre-test.
  s.keys.clear(), s.carried.clear();
  for (std::size_t b = 1; b < s.found.size(); b += 2) {
    const std::vector<std::uint64_t>& keys = s.found[b];
    const std::vector<int>& records = s.found_records[b / 2];
    for (std::size_t k = 0; k < keys.size(); ++k) {
      s.keys.push_back((keys[k] & ~std::uint64_t(0xffffffffu)) | s.carried.size());
      s.carried.push_back({int(std::uint32_t(keys[k])), records[k]});
    }
  }
  sort_by_id(par_, s.keys, s.spare, s.count, id_bits);
  s.restores.resize(s.keys.size()), s.restore_records.resize(s.keys.size());
  for (std::size_t k = 0; k < s.keys.size(); ++k) {
    const std::array<int, 2>& c = s.carried[std::uint32_t(s.keys[k])];
    s.restores[k] = c[0], s.restore_records[k] = c[1];
  }
}

// The serial edits' renewal (the oracle of the rounds' and waves' renewal event by event): after
// all the events, the normal of each vertex an event changed a triangle at, once or more (each
// normal is a function of its final list and areas alone, so repeats and order change nothing).
// Each split and restore computed its own triangles' areas. Through the pass's kernel rather
// than the events' vertex_normal, so that the comparison also checks that the two agree.
void FastSimulator::renew_normals_of_touched() {
  for (int v : touched_) vertex_normals(topo_, topo_.V.nr.data(), v, v + 1);
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
