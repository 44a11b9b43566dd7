// Internal to crumple_mesh: the checks behind validate_mesh, split in steps so that load_obj can
// run the orientation fix between them and name vertices and lines of the file in messages.
#pragma once

#include <string>
#include <vector>

#include "mesh/input_mesh.h"

namespace crumple::mesh_detail {

/// How error messages name things.
struct MeshLabels {
  std::string where;               ///< message prefix: the file name or the caller's label
  std::vector<int> vertex_number;  ///< printed number of each vertex; empty: its 0-based index
  std::vector<int> triangle_line;  ///< file line of each triangle; empty: "triangle t" (0-based)
};

/// At least one triangle, indices in range, finite coordinates, every vertex used, no triangle
/// repeating a vertex or with area below 1e-12 * (bounding-box diagonal)^2.
void check_triangles(const InputMesh& mesh, const MeshLabels& labels);

/// Every coordinate within +-kMaxCoordinate, every edge at least kMinEdgeLength long and at
/// least kMinEdgeRelative times the largest coordinate magnitude.
/// Expects check_triangles to have passed.
void check_float_range(const InputMesh& mesh, const MeshLabels& labels);

/// Flips triangles so that each edge-connected component is consistently oriented, keeping the
/// orientation of the component's lowest-numbered triangle (breadth-first over shared edges).
/// Throws for an edge in more than two triangles, or if a component is non-orientable.
/// Expects check_triangles to have passed.
void orient_consistently(InputMesh& mesh, const MeshLabels& labels);

/// Every edge in one or two triangles, which traverse it in opposite directions, and the
/// triangles around each vertex forming a single edge-connected fan.
/// Expects check_triangles to have passed.
void check_manifold(const InputMesh& mesh, const MeshLabels& labels);

}  // namespace crumple::mesh_detail
