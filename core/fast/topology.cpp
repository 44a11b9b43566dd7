#include "fast/topology.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <sstream>

#if defined(__AVX2__) && !CRUMPLE_DISABLE_SIMD
#include <immintrin.h>
#endif

namespace crumple::fast {

namespace {
template <class... A>
void grow(std::size_t n, A&... arrays) {
  (arrays.resize(n), ...);
  (arrays.keep_warm(), ...);
}

// Position of `entry` in a list of `count` items, or count. Every block holds at least kMinRoom
// entries (topology.h), so the first eight are compared at once without a bounds test: an
// event's lists hold about six, where a loop mispredicts its exit once a search.
int find_entry(const std::int32_t* list, int count, std::int32_t entry) {
  int k = 0;
#if defined(__AVX2__) && !CRUMPLE_DISABLE_SIMD
  static_assert(kMinRoom >= 8);
  const __m256i eq = _mm256_cmpeq_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(list)), _mm256_set1_epi32(entry));
  const unsigned hits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(eq))) & (count >= 8 ? 0xffu : (1u << count) - 1);
  if (hits) return __builtin_ctz(hits);
  k = 8;
#endif
  while (k < count && list[k] != entry) ++k;
  return std::min(k, count);
}

// Erases `entry` from a slot list of `count` items and the same slot of its parallel list,
// keeping the order.
void erase_slot(std::int32_t* list, std::int32_t* parallel, std::uint16_t& count, int entry) {
  const int k = find_entry(list, count, entry);
  if (k == count) return;
  // The entries after k move down one, carried from the end in one loop over both lists: the
  // lists hold a few entries, where the two library moves a plain shift compiles to cost more.
  std::int32_t carry = list[count - 1], carry_parallel = parallel[count - 1];
  for (int q = count - 2; q >= k; --q) std::swap(carry, list[q]), std::swap(carry_parallel, parallel[q]);
  --count;
}
}  // namespace

namespace {
template <class... A>
void reserve_all(std::size_t n, A&... arrays) {
  (arrays.reserve_warm(n), ...);
}
}  // namespace

void Topology::reserve(std::size_t nv, std::size_t ne, std::size_t nt) {
  reserve_all(nv, V.xm, V.vm, V.nr, V.rest, V.spring_list, V.tri_list, V.lid, V.phys);
  // Blocks of the usual room, and as much again for lists that move before a relayout repacks.
  reserve_all(nv * 2 * kMinRoom, V.springs, V.nbrs, V.tris, V.wings);
  reserve_all(ne, E.slots, E.lid, E.phys);
  reserve_all(nt, T.slots, T.alive, T.area, T.lid, T.phys);
  records.reserve_warm(nv);  // one per split vertex: refinement's new vertices
}

// A slot for a new element: the newest freed logical id and its slot (LIFO, the id policy of
// sim/simulator.h), or a new id and slot at the end (both ranges always have the same size).
// The slot of a recycled id is a random read (phys[id]), and a pass takes thousands in a row:
// each take prefetches the phys entry of the id that the take kTakeAhead + 1 from now will pop,
// so that the pops find it in cache.
constexpr std::size_t kTakeAhead = 8;  ///< enough takes between for the miss to resolve, few enough that the line stays cached
template <class Kind>
int take_slot(Kind& k) {
  const std::size_t size = k.lid.size();
  if (!k.free_ids.empty()) {
    const int id = k.free_ids.back();
    k.free_ids.pop_back();
    if (k.free_ids.size() > kTakeAhead) __builtin_prefetch(&k.phys[k.free_ids[k.free_ids.size() - 1 - kTakeAhead]]);
    return k.phys[id];
  }
  k.lid.push_back(std::int32_t(size));
  k.phys.push_back(std::int32_t(size));
  return int(size);
}

// take_slot's batch form (Topology::peek_X, take_batch): the q-th take pops the q-th newest free
// id, and the takes past the free list make new ids and slots in order.
template <class Kind>
int peek_slot(const Kind& k, int q) {
  const int free = int(k.free_ids.size());
  return q < free ? k.phys[std::size_t(k.free_ids[std::size_t(free - 1 - q)])] : int(k.lid.size()) + (q - free);
}

template <class Kind>
void take_slots(Kind& k, int count) {
  const int pops = std::min(count, int(k.free_ids.size()));
  k.free_ids.resize(k.free_ids.size() - std::size_t(pops));
  for (int q = pops; q < count; ++q) {
    const auto size = std::int32_t(k.lid.size());
    k.lid.push_back(size);
    k.phys.push_back(size);
  }
}

int Topology::peek_vertex(int q) const { return peek_slot(V, q); }
int Topology::peek_edge(int q) const { return peek_slot(E, q); }
int Topology::peek_triangle(int q) const { return peek_slot(T, q); }
int Topology::peek_record(int q) const {
  const int free = int(free_records.size());
  return q < free ? free_records[std::size_t(free - 1 - q)] : int(records.size()) + (q - free);
}

void Topology::take_batch(int vertices, int edges, int triangles, int records_taken) {
  V.created += vertices;
  take_slots(V, vertices);
  take_slots(E, edges);
  take_slots(T, triangles);
  const int pops = std::min(records_taken, int(free_records.size()));
  free_records.resize(free_records.size() - std::size_t(pops));
  records.resize(records.size() + std::size_t(records_taken - pops));
  records.keep_warm();
}

int Topology::new_vertex() {
  const int v = take_vertex();
  fit();
  init_vertex(v);
  return v;
}

// A vertex slot keeps its blocks when it is released and reused: only new slots get blocks (fit).
void Topology::init_vertex(int v) { V.spring_list[v].count = V.tri_list[v].count = 0; }

int Topology::take_vertex() {
  ++V.created;
  return take_slot(V);
}
int Topology::take_edge() { return take_slot(E); }

int Topology::take_triangle() { return take_slot(T); }

namespace {
/// Appends a block of `room` entries to a pool and its parallel pool; returns its start.
std::int32_t append_block(Array<std::int32_t>& list, Array<std::int32_t>& parallel, std::size_t room) {
  const std::size_t at = list.size();
  if (at + room > std::size_t(INT32_MAX)) throw std::length_error("adjacency pool exceeds 2^31 entries");
  grow(at + room, list, parallel);
  return std::int32_t(at);
}
}  // namespace

void Topology::fit() {
  if (const std::size_t n = V.lid.size(), old = V.xm.size(); n != old) {
    grow(n, V.xm, V.vm, V.nr, V.rest, V.spring_list, V.tri_list);
    // One block of the least room per new slot, in slot order.
    const std::int32_t at_e = append_block(V.springs, V.nbrs, (n - old) * kMinRoom);
    const std::int32_t at_t = append_block(V.tris, V.wings, (n - old) * kMinRoom);
    for (std::size_t v = old; v < n; ++v) {
      const std::int32_t offset = std::int32_t((v - old) * kMinRoom);
      V.spring_list[v] = ListHead{at_e + offset, 0, kMinRoom};
      V.tri_list[v] = ListHead{at_t + offset, 0, kMinRoom};
    }
  }
  for (Array<std::int32_t>* ids : {&V.lid, &V.phys, &E.lid, &E.phys, &T.lid, &T.phys}) ids->keep_warm();
  if (const std::size_t n = E.lid.size(); n != E.slots.size()) grow(n, E.slots);
  if (const std::size_t n = T.lid.size(), old = T.slots.size(); n != old) {
    grow(n, T.slots, T.alive, T.area);
    std::fill(T.slots.begin() + std::ptrdiff_t(old), T.slots.end(), kNoFace);
  }
}

void Topology::release_vertex(int v) {
  V.xm[v] = V.vm[v] = V.nr[v] = Float4{};
  V.rest[v] = Float4{};
  V.spring_list[v].count = V.tri_list[v].count = 0;
}

int Topology::new_edge(int a, int b, float l0) {
  const int e = take_edge();
  fit();
  init_edge(e, a, b, l0);
  return e;
}

void Topology::init_edge(int e, int a, int b, float l0) {
  E[e].a = a;
  E[e].b = b;
  E[e].wl = E[e].wr = E[e].tri0 = E[e].tri1 = E[e].record = -1;
  E[e].l0 = l0;
  E[e].flags = kAlive | kMesh | kBreakable;
  list_spring(a, e << 1, b);
  list_spring(b, (e << 1) | 1, a);
}

void Topology::release_edge(int e) {
  unlist_spring(E[e].a, e << 1);
  unlist_spring(E[e].b, (e << 1) | 1);
  E[e].a = E[e].b = 0;
  E[e].wl = E[e].wr = E[e].tri0 = E[e].tri1 = E[e].record = -1;
  E[e].l0 = 1;
  E[e].flags = 0;
}

int Topology::new_triangle() {
  const int t = take_triangle();
  fit();
  init_triangle(t);
  return t;
}

void Topology::init_triangle(int t) {
  T[t] = kNoFace;
  T.alive[t] = 1;
  T.area[t] = Float4{};
}

void Topology::release_triangle(int t) {
  T[t] = kNoFace;
  T.alive[t] = 0;
  T.area[t] = Float4{};
}

void Topology::free_ids(const Freed& f) {
  for (int e : f.edges)
    if (e >= 0) E.free_ids.push_back(E.lid[e]);
  for (int t : f.tris)
    if (t >= 0) T.free_ids.push_back(T.lid[t]);
  if (f.vertex >= 0) V.free_ids.push_back(V.lid[f.vertex]);
  if (f.record >= 0) free_records.push_back(f.record);
}

int Topology::take_record() {
  if (!free_records.empty()) {
    const int id = free_records.back();
    free_records.pop_back();
    return id;
  }
  records.emplace_back();
  records.keep_warm();
  return int(records.size()) - 1;
}

void Topology::make_room(int v, int springs, int tris) {
  if (springs > V.spring_list[v].room) move_block(v, true, springs);
  if (tris > V.tri_list[v].room) move_block(v, false, tris);
}

void Topology::move_block(int v, bool springs, int need) {
  if (need > kMaxRoom)
    throw std::length_error("a vertex has more than " + std::to_string(kMaxRoom) + (springs ? " springs" : " triangles"));
  Array<std::int32_t>& list = springs ? V.springs : V.tris;
  Array<std::int32_t>& parallel = springs ? V.nbrs : V.wings;
  ListHead& head = springs ? V.spring_list[v] : V.tri_list[v];
  std::int32_t& at = head.at;
  std::uint16_t& room = head.room;
  const int count = head.count;
  // Doubling: a list that grows one entry at a time moves O(log valence) times.
  const int wider = std::min(kMaxRoom, std::max(room_for(need), 2 * int(room)));
  const std::int32_t to = append_block(list, parallel, std::size_t(wider));
  std::copy_n(&list[std::size_t(at)], count, &list[std::size_t(to)]);
  std::copy_n(&parallel[std::size_t(at)], count, &parallel[std::size_t(to)]);
  (springs ? V.garbage_e : V.garbage_t) += room;
  at = to;
  room = std::uint16_t(wider);
}

int Topology::mesh_edge(int a, int b) const {
  const std::int32_t *s = springs_of(a), *nb = nbrs_of(a);
  for (int k = 0; k < V.spring_list[a].count; ++k)
    if (nb[k] == b && (E[s[k] >> 1].flags & kMesh)) return s[k] >> 1;
  return -1;
}

bool Topology::attach(int t, int a, int b, int c) {
  Face f{{a, b, c}, {}};
  for (int k = 0; k < 3; ++k)
    if ((f.e[k] = mesh_edge(f.v[k], f.v[(k + 1) % 3])) < 0) return false;
  return attach(t, f);
}

bool Topology::attach(int t, const Face& f) {
  for (int k = 0; k < 3; ++k) {
    const int p = f.v[k], q = f.v[(k + 1) % 3], w = f.v[(k + 2) % 3], e = f.e[k];
    if (e < 0 || !(E[e].flags & kMesh)) return false;
    const bool forward = E[e].a == p && E[e].b == q;
    if (!forward && !(E[e].a == q && E[e].b == p)) return false;
    std::int32_t& slot = forward ? E[e].tri0 : E[e].tri1;
    if (slot >= 0) return false;
    slot = t;
    (forward ? E[e].wl : E[e].wr) = w;
  }
  T[t] = f;
  for (int k = 0; k < 3; ++k) list_tri(f.v[k], (t << 2) | k, f.e[(k + 1) % 3]);  // opposite edge
  return true;
}

// Appends move a full list first, which only serial code may do: parallel edits reserve room
// beforehand (make_room), so that an append never moves a block while another thread reads.
void Topology::list_spring(int v, int entry, int other) {
  if (V.spring_list[v].count == V.spring_list[v].room) move_block(v, true, V.spring_list[v].count + 1);
  ListHead& head = V.spring_list[v];
  const std::size_t slot = std::size_t(head.at) + head.count++;
  V.springs[slot] = entry;
  V.nbrs[slot] = other;
}
void Topology::unlist_spring(int v, int entry) {
  const std::size_t base = std::size_t(V.spring_list[v].at);
  erase_slot(&V.springs[base], &V.nbrs[base], V.spring_list[v].count, entry);
}
void Topology::list_tri(int v, int entry, int wing_edge) {
  if (V.tri_list[v].count == V.tri_list[v].room) move_block(v, false, V.tri_list[v].count + 1);
  ListHead& head = V.tri_list[v];
  const std::size_t slot = std::size_t(head.at) + head.count++;
  V.tris[slot] = entry;
  V.wings[slot] = wing_edge;
}
void Topology::list_tris(int v, const std::int32_t* entries, const std::int32_t* wing_edges, int count) {
  if (V.tri_list[v].count + count > V.tri_list[v].room) move_block(v, false, V.tri_list[v].count + count);
  ListHead& head = V.tri_list[v];
  const std::size_t slot = std::size_t(head.at) + head.count;
  std::copy_n(entries, count, &V.tris[slot]);
  std::copy_n(wing_edges, count, &V.wings[slot]);
  head.count = std::uint16_t(head.count + count);
}
void Topology::relist_tri(int v, int entry, int to, int wing_edge) {
  const std::size_t base = std::size_t(V.tri_list[v].at);
  std::int32_t* list = &V.tris[base];
  const int k = find_entry(list, V.tri_list[v].count, entry);
  if (k == V.tri_list[v].count) return;  // not listed: an inconsistent mesh, which check() reports
  list[k] = to;
  V.wings[base + std::size_t(k)] = wing_edge;
}
void Topology::unlist_tri(int v, int entry) {
  const std::size_t base = std::size_t(V.tri_list[v].at);
  erase_slot(&V.tris[base], &V.wings[base], V.tri_list[v].count, entry);
}

int Topology::live_vertices() const {
  return V.size() - int(V.free_ids.size());
}
int Topology::live_mesh_edges() const {
  return int(std::count_if(E.slots.begin(), E.slots.end(), [](const EdgeRecord& r) { return (r.flags & (kAlive | kMesh)) == (kAlive | kMesh); }));
}
int Topology::live_auxiliary() const {
  return int(std::count_if(E.slots.begin(), E.slots.end(), [](const EdgeRecord& r) { return (r.flags & (kAlive | kMesh)) == kAlive; }));
}
int Topology::live_triangles() const { return T.size() - int(T.free_ids.size()); }

std::string Topology::check_blocks() const {
  const char* names[2] = {"springs", "tris"};
  for (int which = 0; which < 2; ++which) {
    const bool springs = which == 0;
    const Array<ListHead>& heads = springs ? V.spring_list : V.tri_list;
    const std::size_t pool = springs ? V.springs.size() : V.tris.size();
    const std::size_t parallel = springs ? V.nbrs.size() : V.wings.size();
    const std::string name = names[which];
    if (parallel != pool) return "the " + name + " pool and its parallel pool differ in size";
    if (heads.size() != std::size_t(V.size())) return "the " + name + " blocks are not one per vertex slot";
    std::vector<std::pair<std::int64_t, int>> blocks;
    std::int64_t total = springs ? V.garbage_e : V.garbage_t;
    for (int v = 0; v < V.size(); ++v) {
      const ListHead h = heads[v];
      if (h.room < kMinRoom || h.count > h.room || h.at < 0 || std::size_t(h.at) + h.room > pool)
        return "vertex " + std::to_string(v) + "'s " + name + " block is out of bounds or too small";
      blocks.emplace_back(h.at, h.room);
      total += h.room;
    }
    if (std::size_t(total) != pool)
      return "the " + name + " pool holds " + std::to_string(pool) + " entries, its blocks and garbage " +
             std::to_string(total);
    std::sort(blocks.begin(), blocks.end());
    for (std::size_t k = 1; k < blocks.size(); ++k)
      if (blocks[k - 1].first + blocks[k - 1].second > blocks[k].first) return "two " + name + " blocks overlap";
  }
  return {};
}

namespace {
/// The parts written one after the other: a check's one-line finding.
template <class... P>
std::string describe(const P&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}
}  // namespace

std::string Topology::check() const {
  // In this order: each part reads only what the parts before it found consistent.
  std::vector<char> dead_v, free_e;
  std::string found = check_blocks();
  if (found.empty()) found = check_ids(dead_v, free_e);
  if (found.empty()) found = check_triangles(dead_v);
  if (found.empty()) found = check_edges(dead_v, free_e);
  if (found.empty()) found = check_vertices(dead_v);
  if (!found.empty()) return found;
  const int chi = live_vertices() - live_mesh_edges() + live_triangles();
  if (chi != euler) return describe("Euler characteristic ", chi, " differs from the input's ", euler);
  return {};
}

// Logical ids and slots are inverse maps of each other, over the same range; the free lists.
std::string Topology::check_ids(std::vector<char>& dead_v, std::vector<char>& free_e) const {
  auto bijective = [](const auto& lid, const auto& phys) {
    if (lid.size() != phys.size()) return false;
    for (std::size_t k = 0; k < lid.size(); ++k)
      if (lid[k] < 0 || std::size_t(lid[k]) >= phys.size() || phys[std::size_t(lid[k])] != std::int32_t(k)) return false;
    return true;
  };
  if (!bijective(V.lid, V.phys) || V.lid.size() != V.xm.size()) return "vertex logical ids are not a bijection";
  if (!bijective(E.lid, E.phys) || E.lid.size() != E.slots.size()) return "edge logical ids are not a bijection";
  if (!bijective(T.lid, T.phys) || T.lid.size() != T.slots.size()) return "triangle logical ids are not a bijection";
  dead_v.assign(std::size_t(V.size()), 0), free_e.assign(std::size_t(E.size()), 0);
  std::vector<char> free_t(std::size_t(T.size()), 0);
  for (int v : V.free_ids) dead_v[V.phys[v]] = 1;
  for (int e : E.free_ids) free_e[E.phys[e]] = 1;
  // The free triangle ids are exactly the dead slots', each once, and a dead slot is kNoFace
  // (the render buffers count live triangles from the free list and skip faces without sides).
  for (int id : T.free_ids) {
    if (id < 0 || id >= T.size() || free_t[T.phys[id]]) return describe("triangle free list holds bad id ", id);
    free_t[T.phys[id]] = 1;
  }
  for (int t = 0; t < T.size(); ++t) {
    if (bool(free_t[t]) == bool(T.alive[t])) return describe("triangle ", t, " is ", T.alive[t] ? "live on" : "dead off", " the free list");
    if (!T.alive[t] && T[t].e != kNoFace.e) return describe("dead triangle ", t, " is not kNoFace");
  }
  return {};
}

// Each live triangle's sides are live mesh edges that link back to it with the right wing, and
// each corner lists it with the right opposite edge.
std::string Topology::check_triangles(const std::vector<char>& dead_v) const {
  for (int t = 0; t < T.size(); ++t) {
    if (!T.alive[t]) continue;
    const auto v = T.corners(t);
    const std::array<int, 3>& es = T[t].e;
    for (int k = 0; k < 3; ++k) {
      const int p = v[k], q = v[(k + 1) % 3], e = es[k];
      if (dead_v[p]) return describe("triangle ", t, " uses dead vertex ", p);
      if (p == q || p == v[(k + 2) % 3]) return describe("triangle ", t, " repeats vertex ", p);
      if (e < 0 || !(E[e].flags & kAlive) || !(E[e].flags & kMesh)) return describe("triangle ", t, " side ", k, " has no mesh edge");
      const bool fwd = E[e].a == p && E[e].b == q, back = E[e].a == q && E[e].b == p;
      if (!fwd && !back) return describe("edge ", e, " does not join triangle ", t, "'s side ", k);
      if ((fwd ? E[e].tri0 : E[e].tri1) != t) return describe("edge ", e, " does not link back to triangle ", t);
      if ((fwd ? E[e].wl : E[e].wr) != v[(k + 2) % 3]) return describe("edge ", e, " has a stale wing");
      bool listed = false;
      const std::int32_t *s = tris_of(p), *w = wings_of(p);
      const int opposite = es[(k + 1) % 3];
      for (int j = 0; j < V.tri_list[p].count; ++j) listed |= s[j] == ((t << 2) | k) && w[j] == opposite;
      if (!listed) return describe("triangle ", t, " is not listed at vertex ", p);
    }
  }
  return {};
}

// Each live edge joins two live vertices that list it once; an auxiliary edge has a record and
// no triangle; a mesh edge has a live triangle, and no two join the same vertices.
std::string Topology::check_edges(const std::vector<char>& dead_v, const std::vector<char>& free_e) const {
  std::set<std::pair<int, int>> pairs;
  for (int e = 0; e < E.size(); ++e) {
    const std::uint8_t f = E[e].flags;
    if (!(f & kAlive)) {
      if (!free_e[e]) return describe("dead edge ", e, " is not on the free list");
      continue;
    }
    const int a = E[e].a, b = E[e].b;
    if (a == b || dead_v[a] || dead_v[b]) return describe("edge ", e, " has a bad endpoint");
    if (!(E[e].l0 > 0)) return describe("edge ", e, " has rest length ", E[e].l0);
    for (int end : {a, b}) {
      const std::int32_t* s = springs_of(end);
      const int want = (e << 1) | (end == b);
      if (std::count(s, s + V.spring_list[end].count, want) != 1) return describe("edge ", e, " is not listed once at ", end);
    }
    if (!(f & kMesh)) {
      if ((f & kBreakable) || E[e].tri0 >= 0 || E[e].tri1 >= 0 || E[e].record < 0)
        return describe("auxiliary edge ", e, " is breakable, in a triangle or has no record");
      continue;
    }
    if (E[e].tri0 < 0 && E[e].tri1 < 0) return describe("mesh edge ", e, " is in no triangle");
    for (int t : {E[e].tri0, E[e].tri1})
      if (t >= 0 && !T.alive[t]) return describe("edge ", e, " links dead triangle ", t);
    if (!pairs.insert({std::min(a, b), std::max(a, b)}).second) return describe("two mesh edges join ", a, " and ", b);
  }
  return {};
}

// Each vertex's two mass copies agree; a live one has a positive mass, a triangle, and springs
// that name it and their other end.
std::string Topology::check_vertices(const std::vector<char>& dead_v) const {
  for (int v = 0; v < V.size(); ++v) {
    if (!(V.vm[v].w == V.xm[v].w)) return describe("vertex ", v, " has two masses ", V.xm[v].w, " and ", V.vm[v].w);
    if (dead_v[v]) continue;
    if (!(V.mass(v) > 0) || !std::isfinite(V.mass(v))) return describe("vertex ", v, " has mass ", V.mass(v));
    if (V.tri_list[v].count == 0) return describe("vertex ", v, " is in no triangle");
    const std::int32_t *s = springs_of(v), *nb = nbrs_of(v);
    for (int k = 0; k < V.spring_list[v].count; ++k) {
      const int e = s[k] >> 1;
      if (!(E[e].flags & kAlive) || (s[k] & 1 ? E[e].b : E[e].a) != v || (s[k] & 1 ? E[e].a : E[e].b) != nb[k])
        return describe("vertex ", v, " lists a bad spring");
    }
  }
  return {};
}

}  // namespace crumple::fast
