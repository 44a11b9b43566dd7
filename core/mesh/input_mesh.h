// Input meshes: what a simulation starts from, before any backend builds its own structures.
//
// An InputMesh is a plain indexed triangle mesh that has passed validation: finite coordinates,
// at least one triangle, indices in range, no degenerate (zero-area) triangle, every edge in one
// or two triangles, every vertex a single fan (manifold), triangles consistently oriented, and no
// unreferenced vertex. Anything else is rejected with an InputError whose message is one line
// naming the problem and where it is (file and line, vertex or edge).
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace crumple {

/// Thrown for input that cannot be simulated; what() is one line, e.g.
/// "mesh.obj:12: face refers to vertex 40 but the file has 38 vertices".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A validated triangle mesh. Positions are the rest (material) positions X_k of MODEL.md §1.
struct InputMesh {
  std::vector<std::array<double, 3>> positions;  ///< vertex positions, any unit
  std::vector<std::array<int, 3>> triangles;     ///< 0-based, consistently oriented
};

/// An n x n grid of vertices spanning the unit square [0,1]^2 in the z = 0 plane
/// ((n-1)^2 quads, 2 (n-1)^2 triangles, normals +z). alternate = true flips the diagonal of
/// every other quad (a "union jack" pattern, no preferred fold direction); false keeps one
/// diagonal everywhere. Throws InputError for n < 2 or n > 8192.
InputMesh make_grid(int n, bool alternate = true);

/// Reads an OBJ file (tinyobjloader), triangulates polygons, drops unreferenced vertices,
/// orients triangles consistently (flipping whole components as needed), and validates.
/// Throws InputError naming the file and line (or vertex/edge) of the first problem.
InputMesh load_obj(const std::string& path);

/// Checks every property listed at the top of this file; `where` prefixes messages
/// (e.g. the file name). Throws InputError on the first violation.
void validate_mesh(const InputMesh& mesh, const std::string& where);

/// Writes vertices and triangles as an OBJ (1-based indices, %.9g). Throws std::runtime_error
/// if the file cannot be written.
void write_obj(const std::string& path, const std::vector<std::array<double, 3>>& positions,
               const std::vector<std::array<int, 3>>& triangles);

}  // namespace crumple
