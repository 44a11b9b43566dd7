// Input meshes: what a simulation starts from, before any backend builds its own structures.
//
// An InputMesh is a plain indexed triangle mesh that has passed validation: finite coordinates,
// at least one triangle, indices in range, no degenerate (zero-area) triangle, every edge in one
// or two triangles, every vertex a single fan (manifold), triangles consistently oriented, and no
// unreferenced vertex, coordinates and edge lengths that float can resolve. Anything else is rejected with an InputError whose message is one line
// naming the problem and where it is (file and line, vertex or edge).
#pragma once

#include <array>
#include <cstdint>
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

/// Largest OBJ file load_obj reads (256 MiB, about 8 million vertices).
inline constexpr std::uint64_t kMaxObjBytes = std::uint64_t{256} << 20;

/// Reads an OBJ file (tinyobjloader), triangulates polygons, drops unreferenced vertices,
/// orients triangles consistently (flipping whole components as needed), and validates.
/// Refuses anything but a regular file of at most kMaxObjBytes. Coordinates are decimal numbers,
/// face indices non-zero integers that fit an int; a leading UTF-8 byte-order mark is skipped.
/// Throws InputError naming the file and line (or vertex/edge) of the first problem.
InputMesh load_obj(const std::string& path);

/// load_obj on the text of a file; `path` names it in messages.
InputMesh parse_obj(std::string text, const std::string& path);

/// Largest coordinate magnitude accepted, and the smallest edge length relative to the largest
/// coordinate magnitude: the fast backend computes in float (24-bit significand; squared
/// lengths and cross products must neither overflow nor lose the edge), see D20.
inline constexpr double kMaxCoordinate = 1e9;
inline constexpr double kMinEdgeLength = 1e-9;
inline constexpr double kMinEdgeRelative = 1e-5;

/// Checks every property listed at the top of this file, and kMaxCoordinate /
/// kMinEdgeLength / kMinEdgeRelative; `where` prefixes messages
/// (e.g. the file name). Throws InputError on the first violation.
void validate_mesh(const InputMesh& mesh, const std::string& where);

/// Writes vertices and triangles as an OBJ (1-based indices, %.9g). Throws std::runtime_error
/// if the file cannot be written.
void write_obj(const std::string& path, const std::vector<std::array<double, 3>>& positions,
               const std::vector<std::array<int, 3>>& triangles);

}  // namespace crumple
