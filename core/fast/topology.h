// The fast backend's mesh: topology and state in per-slot arrays of small records (Jolt's split
// of immutable-ish topology from per-step state, Box2D's hot/cold split), and the serial
// topology edits. What only one step's passes read (per-edge outputs, forces, guesses) is not
// here but in step_scratch.h.
//
// Vertices, edges and triangles are *slots* in parallel arrays, each array one record per slot
// that a pass or an event reads in one load or line: a vertex's state in 16-byte rows
// (position, velocity, normal, rest position) and its two list heads, an edge's topology in an
// EdgeRecord, a triangle's in a Face. Each slot carries a logical
// id (`lid`) with its inverse map (`phys`). Logical ids follow the id policy of sim/simulator.h,
// identical to the reference's (removed ids on LIFO free lists), so the random stream keyed by
// edge id gives the same decisions and snapshots list elements in the same order; slots are
// where the data lives, and layout.h reorders them in space for cache locality without changing
// any logical id. Everything inside the backend (kernels, adjacency, records) speaks slots; only
// the random stream, the event order and the Simulator interface speak logical ids. A freed slot
// keeps its logical id, so reusing the id reuses the slot. A dead element keeps harmless values:
// mass 0, no adjacency, an edge in no list joining vertex 0 to itself (zero length, no force),
// a triangle with corners 0 and no edges (kNoFace).
//
// Adjacency is what makes every force pass a race-free *gather*: each vertex lists its springs
// and its triangles, each list in a block of its own in a pool shared by all vertices (a block
// holds at least kMinRoom entries, so a kernel may read the first kMinRoom of any list without a
// bounds test). A list that outgrows its block moves to a new block, twice as large, at the end
// of its pool, leaving the old one as garbage until relayout() repacks the pools in vertex order,
// every block sized to its list: memory follows each vertex's own valence (one vertex of valence
// 10,000 costs its own list, not a stride for every vertex), and neighbouring vertices' lists
// share cache lines. Blocks move only in serial code (the split rounds reserve room first).
// List order only changes by appending, by order-preserving erase and by overwriting an entry
// in place (an event's triangle that changes hands), each in event order at a vertex, so every
// sum over a list has one order on any thread count.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fast/aligned.h"

namespace crumple::fast {

/// Every adjacency block holds at least this many entries (kernels read this many unguarded).
constexpr int kMinRoom = 8;
/// The most entries one list may hold (the counts are 16-bit).
constexpr int kMaxRoom = 65535;
/// The block a list of `count` entries gets when the pools are repacked: at least kMinRoom, two
/// entries to grow into, a multiple of four entries (16 bytes).
inline int room_for(int count) { return std::min(kMaxRoom, std::max(kMinRoom, (count + 5) & ~3)); }

/// Edge flags.
enum : std::uint8_t {
  kAlive = 1,      ///< the id is in use
  kMesh = 2,       ///< a mesh edge (in 1-2 triangles); otherwise an auxiliary spring
  kBreakable = 4,  ///< may break [Eq 6]
};

/// What a split remembers for restoration (MODEL.md §5, §7); cold data, one per auxiliary edge.
struct SplitRecord {
  int n = -1;                            ///< the inserted vertex
  std::array<int, 4> k{-1, -1, -1, -1};  ///< N = {i, j, l, r}; -1 where a wing does not exist
  std::array<int, 4> e{-1, -1, -1, -1};  ///< e_in, e_nj, e_ln, e_nr
  std::array<int, 4> t{-1, -1, -1, -1};  ///< (i,n,l), (n,j,l), (j,n,r), (n,i,r)
  std::array<double, 4> dm{};            ///< mass each k gave to n
  std::array<double, 4> delta{};         ///< delta_k of [Eq 3], for the paper's [Eq 11]
  double l0 = 0;                         ///< rest length before the break
};

/// The slots one restore frees, in the order it frees them (-1: none): Topology::free_ids puts
/// them on the free lists, after the restores of a wave ran in parallel (restore_waves.h).
struct Freed {
  std::array<int, 4> edges{-1, -1, -1, -1};  ///< e_in, e_nj, e_ln, e_nr
  std::array<int, 2> tris{-1, -1};           ///< (n,j,l), (n,i,r)
  int vertex = -1;                           ///< n
  int record = -1;                           ///< the split record
};

/// A triangle: corners counter-clockwise about the normal, and the mesh edge of each side, e[k]
/// joining v[k] and v[(k + 1) % 3]. What attach() links, and each triangle slot's record (24
/// bytes: an event reads a triangle's topology in one or two lines).
struct Face {
  std::array<std::int32_t, 3> v{-1, -1, -1};
  std::array<std::int32_t, 3> e{-1, -1, -1};
};
static_assert(sizeof(Face) == 24);
/// A dead (or not yet linked) triangle slot: corners 0, no edges (harmless values, topology.h).
constexpr Face kNoFace{{0, 0, 0}, {-1, -1, -1}};

/// Where one vertex's list lives in its pool (see the file comment): 8 bytes, so that a pass
/// reads a list's head with one load and an event edits it in one line.
struct ListHead {
  std::int32_t at = 0;      ///< start of the vertex's block in the pool
  std::uint16_t count = 0;  ///< entries used
  std::uint16_t room = 0;   ///< entries of the block (>= kMinRoom)
};

/// A 3-vector padded to 16 bytes: state that the kernels gather at random (one load, one line).
struct alignas(16) Float4 {
  float x = 0, y = 0, z = 0, w = 0;
};

struct Vertices {
  // hot, per step (float: the fast backend's precision), in 16-byte rows that every pass reads
  // natively: a random neighbour costs one load per quantity, not one line per attribute.
  Array<Float4> xm;          ///< position x_k in x, y, z; mass m_k in w (0: dead)
  Array<Float4> vm;          ///< velocity v_k in x, y, z; m_k again in w (set_mass keeps both)
  Array<Float4> nr;          ///< vertex normal n_k (MODEL.md §1) in x, y, z; w = 0
  // cold
  Array<Float4> rest;        ///< rest position X_k in x, y, z; w = 0
  // adjacency (see the file comment): two pools of blocks, each with a parallel pool
  Array<std::int32_t> springs;    ///< pool of spring lists: (edge << 1 | vertex is b)
  Array<std::int32_t> nbrs;       ///< parallel to springs: the other endpoint
  Array<std::int32_t> tris;       ///< pool of triangle lists: (triangle << 2 | corner)
  Array<std::int32_t> wings;      ///< parallel to tris: the edge opposite the vertex
  Array<ListHead> spring_list;    ///< each vertex's block in springs (and nbrs)
  Array<ListHead> tri_list;       ///< each vertex's block in tris (and wings)
  Array<std::int32_t> lid;        ///< logical id of each slot
  Array<std::int32_t> phys;       ///< slot of each logical id (the inverse of lid)
  std::int64_t garbage_e = 0;     ///< springs pool entries in blocks a list moved out of
  std::int64_t garbage_t = 0;     ///< the same for the tris pool
  std::vector<int> free_ids;      ///< LIFO free list of logical ids
  std::int64_t created = 0;       ///< vertices taken since the last relayout (layout_stale)

  int size() const { return int(xm.size()); }
  float mass(int v) const { return xm[std::size_t(v)].w; }
  /// The mass lives in both rows' w (a pass reads it from whichever row it loads).
  void set_mass(int v, float m) { xm[std::size_t(v)].w = vm[std::size_t(v)].w = m; }
};

/// One edge slot's topology and rest state in one record (36 bytes): an event reads or writes
/// an edge in one or two cache lines instead of a line per attribute, and the per-step passes
/// (edge_forces, adapt_test) read all their per-edge inputs from it.
struct EdgeRecord {
  std::int32_t a = 0, b = 0;        ///< endpoints
  std::int32_t wl = 0, wr = 0;      ///< wings: third vertex of tri0 / tri1 (-1: none); for an
                                    ///< auxiliary edge, l and r of its split record (the crease's
                                    ///< wings, which [Eq 10] reads: the test needs no record)
  std::int32_t tri0 = 0, tri1 = 0;  ///< triangle traversing a->b / b->a (-1: none)
  float l0 = 0;                     ///< rest length
  std::int32_t record = 0;          ///< index into Topology::records for auxiliary edges, else -1
  std::uint8_t flags = 0;           ///< kAlive | kMesh | kBreakable
};
// An event prefetches a record's first and last byte (event_prefetch.h): at most two lines.
static_assert(sizeof(EdgeRecord) <= 64);

struct Edges {
  Array<EdgeRecord> slots;       ///< the record of each slot (a new slot is all zero until init_edge)
  Array<std::int32_t> lid;       ///< logical id of each slot (keys the random stream [Eq 6])
  Array<std::int32_t> phys;      ///< slot of each logical id
  std::vector<int> free_ids;     ///< LIFO free list of logical ids

  EdgeRecord& operator[](int e) { return slots[std::size_t(e)]; }
  const EdgeRecord& operator[](int e) const { return slots[std::size_t(e)]; }
  int size() const { return int(slots.size()); }
};

struct Triangles {
  Array<Face> slots;               ///< corners and sides of each slot (kNoFace when dead)
  Array<std::uint8_t> alive;       ///< 1: in use
  Array<Float4> area;              ///< per-step area vector (twice the area times the normal); compute_normals
                                   ///< writes every slot's before a read, so relayout leaves it where it is
  Array<std::int32_t> lid;         ///< logical id of each slot
  Array<std::int32_t> phys;        ///< slot of each logical id
  std::vector<int> free_ids;       ///< LIFO free list of logical ids

  Face& operator[](int t) { return slots[std::size_t(t)]; }
  const Face& operator[](int t) const { return slots[std::size_t(t)]; }
  int size() const { return int(slots.size()); }
  std::array<int, 3> corners(int t) const { return slots[std::size_t(t)].v; }
};

/// The whole mesh and the serial edits of its topology.
class Topology {
 public:
  Vertices V;
  Edges E;
  Triangles T;
  Array<SplitRecord> records;        ///< split records (ids recycled through free_records)
  std::vector<int> free_records;     ///< LIFO free list of record ids
  int euler = 0;                     ///< V - E + F of the input, kept by splits and restores

  /// Reserves room for this many elements of each kind, so refinement appends without
  /// reallocating (growth past it is geometric, as for any vector).
  void reserve(std::size_t vertices, std::size_t edges, std::size_t triangles);

  // Element edits take and return slots; the logical id follows the id policy. new_X is
  // take_X (allocates the id and slot: serial, in event order), fit (sizes the arrays to the
  // slots taken: once for a whole batch of takes) then init_X (fills the slot and lists it: may
  // run in parallel for elements of disjoint vertices).
  int new_vertex();
  int new_edge(int a, int b, float l0);  ///< a breakable mesh edge, listed at a and b
  int new_triangle();
  int take_vertex();
  int take_edge();
  int take_triangle();
  int take_record();  ///< a split record id (LIFO free list, else a new one)
  // A batch of takes decided in advance (the split plan, split_rounds.h): peek_X(q) is the slot
  // that the q-th take_X from now would return (q = 0: the next one), without taking it, so the
  // batch's slots can be looked up in parallel; take_batch then takes that many of each kind,
  // as that many take_X calls would.
  int peek_vertex(int q) const;
  int peek_edge(int q) const;
  int peek_triangle(int q) const;
  int peek_record(int q) const;
  void take_batch(int vertices, int edges, int triangles, int records);
  void fit();         ///< grows every array to the slots taken (new slots value-initialized)
  void init_vertex(int v);
  void init_edge(int e, int a, int b, float l0);
  void init_triangle(int t);
  /// Moves v's lists to larger blocks if they cannot hold this many springs / triangles
  /// (serial: a move appends to a pool). Throws std::length_error past kMaxRoom.
  void make_room(int v, int springs, int tris);
  // Freeing is release_X (clears the slot: may run in parallel for elements of disjoint
  // vertices), then free_ids, which puts the released ids on the free lists (serial, in event
  // order).
  void release_vertex(int v);
  void release_edge(int e);  ///< unlists it from its endpoints
  void release_triangle(int t);
  void free_ids(const Freed& f);

  int mesh_edge(int a, int b) const;  ///< live mesh edge joining a and b, or -1
  /// Sets triangle t to f, links its edges' slots and wings and lists t at its corners.
  /// Returns false if a side's edge is not a mesh edge joining its corners or its slot is taken.
  bool attach(int t, const Face& f);
  /// The same with each side's edge looked up (mesh_edge, a scan of a's list per side): for
  /// building a mesh; an event knows its edges and names them.
  bool attach(int t, int a, int b, int c);
  /// Appends `entry` (triangle << 2 | corner) with the edge opposite v to v's triangle list:
  /// room first (make_room) where this runs in parallel.
  void list_tri(int v, int entry, int wing_edge);
  /// Appends `count` entries and their opposite edges at once (a new vertex's whole list).
  void list_tris(int v, const std::int32_t* entries, const std::int32_t* wing_edges, int count);
  /// Overwrites `entry` in v's triangle list, in place, with `to` and its opposite edge (a
  /// triangle that keeps its corner at v, or one that takes another's place there).
  void relist_tri(int v, int entry, int to, int wing_edge);
  void unlist_tri(int v, int entry);  ///< erases `entry` from v's triangle list, keeping the order

  /// Calls f(array) for each of the arrays that grow with the mesh: every kind of slot's
  /// attributes, the pools and the split records (FastSimulator::make_resident, warm_ahead).
  template <class F>
  void for_each_array(F&& f) { each_array(*this, f); }
  template <class F>
  void for_each_array(F&& f) const { each_array(*this, f); }

  int live_vertices() const;
  int live_mesh_edges() const;
  int live_auxiliary() const;
  int live_triangles() const;
  std::string check() const;  ///< empty if consistent

  // Adjacency access.
  const std::int32_t* springs_of(int v) const { return &V.springs[std::size_t(V.spring_list[v].at)]; }
  const std::int32_t* tris_of(int v) const { return &V.tris[std::size_t(V.tri_list[v].at)]; }
  const std::int32_t* nbrs_of(int v) const { return &V.nbrs[std::size_t(V.spring_list[v].at)]; }
  const std::int32_t* wings_of(int v) const { return &V.wings[std::size_t(V.tri_list[v].at)]; }

 private:
  template <class Self, class F>
  static void each_array(Self& m, F& f) {
    f(m.V.xm), f(m.V.vm), f(m.V.nr), f(m.V.rest), f(m.V.spring_list), f(m.V.tri_list), f(m.V.lid), f(m.V.phys);
    f(m.V.springs), f(m.V.nbrs), f(m.V.tris), f(m.V.wings);
    f(m.E.slots), f(m.E.lid), f(m.E.phys);
    f(m.T.slots), f(m.T.alive), f(m.T.area), f(m.T.lid), f(m.T.phys);
    f(m.records);
  }
  void list_spring(int v, int entry, int other);
  void unlist_spring(int v, int entry);
  void move_block(int v, bool springs, int need);  ///< v's list to a new block of room >= need
  // The parts of check(), each empty if its part is consistent. dead_v and free_e mark the dead
  // vertex slots and the edge slots on the free list (check_ids fills them).
  std::string check_blocks() const;
  std::string check_ids(std::vector<char>& dead_v, std::vector<char>& free_e) const;
  std::string check_triangles(const std::vector<char>& dead_v) const;
  std::string check_edges(const std::vector<char>& dead_v, const std::vector<char>& free_e) const;
  std::string check_vertices(const std::vector<char>& dead_v) const;
};

}  // namespace crumple::fast
