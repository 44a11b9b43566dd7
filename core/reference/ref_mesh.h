// The scalar reference's mesh: array-of-structures, double precision, plain and checkable.
// Deliberately independent of the fast core; it shares only the id policy of sim/simulator.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace crumple::ref {

using V3 = Eigen::Vector3d;

struct Vertex {
  V3 X = V3::Zero();       ///< rest position X_k
  V3 x = V3::Zero();       ///< position x_k
  V3 v = V3::Zero();       ///< velocity v_k
  double m = 0;            ///< mass m_k
  std::vector<int> edges;  ///< every live spring (mesh or auxiliary) touching this vertex
  bool alive = false;      ///< false: the id is on the free list
};

/// What a split remembers for restoration (MODEL.md §5, §7), kept on the auxiliary edge.
struct SplitRecord {
  int n = -1;                              ///< the inserted vertex
  std::array<int, 4> k{-1, -1, -1, -1};    ///< N = {i, j, l, r}; -1 where a wing does not exist
  std::array<int, 4> e{-1, -1, -1, -1};    ///< e_in, e_nj, e_ln, e_nr (-1 where no wing)
  std::array<int, 4> t{-1, -1, -1, -1};    ///< (i,n,l), (n,j,l), (j,n,r), (n,i,r)
  std::array<double, 4> dm{};              ///< mass each k gave to n (m_k - m_k')
  std::array<double, 4> delta{};           ///< delta_k of [Eq 3] (for the paper's [Eq 11])
  double l0 = 0;                           ///< the edge's rest length before it broke
};

struct Edge {
  int a = -1, b = -1;        ///< endpoints
  std::array<int, 2> tri{-1, -1};  ///< triangle traversing a->b, and b->a (-1: none)
  double l0 = 0;             ///< rest length
  double kappa = 0;          ///< kappa_e = kappa (m_a + m_b)                    [Eq 5]
  bool breakable = false;    ///< mesh edge that may break                       [Eq 6]
  bool auxiliary = false;    ///< broken edge kept as a crease spring, in no triangle
  bool alive = false;        ///< false: the id is on the free list
  SplitRecord split;         ///< valid when auxiliary
};

struct Triangle {
  std::array<int, 3> v{-1, -1, -1};  ///< vertices, counter-clockwise about the normal
  std::array<int, 3> e{-1, -1, -1};  ///< e[k] joins v[k] and v[(k+1)%3]
  bool alive = false;                ///< false: the id is on the free list
};

/// Vertices, springs and triangles with free lists; every topology edit goes through
/// attach/detach so the helper links (edge->triangles, vertex->edges) stay consistent.
struct Mesh {
  std::vector<Vertex> verts;
  std::vector<Edge> edges;
  std::vector<Triangle> tris;
  std::vector<int> free_verts, free_edges, free_tris;  ///< LIFO free lists (simulator.h)
  int euler = 0;  ///< V - E + F of the input, preserved by every split and restore

  int new_vertex();
  int new_edge(int a, int b, double l0);  ///< a breakable mesh edge, linked into a and b
  int new_triangle();
  void free_vertex(int v);
  void free_edge(int e);                  ///< unlinks it from its endpoints
  void free_triangle(int t);

  /// The live mesh (non-auxiliary) edge joining a and b, or -1. O(valence).
  int mesh_edge(int a, int b) const;
  /// Sets triangle t to (a, b, c), creating missing mesh edges with rest length from X,
  /// and links each edge's tri slot. Returns false if a slot is taken (would be non-manifold).
  bool attach(int t, int a, int b, int c);
  /// Unlinks triangle t from its edges (it stays allocated).
  void detach(int t);
  /// Third vertex of the triangle on side s of edge e, or -1.
  int wing(int e, int s) const;

  int live_vertices() const;
  int live_mesh_edges() const;
  int live_triangles() const;
  /// Empty if consistent; else the first problem found.
  std::string check() const;
};

}  // namespace crumple::ref
