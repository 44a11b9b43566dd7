// make_grid: the n x n unit-square sheet every benchmark starts from.
#include <cstddef>

#include "mesh/input_mesh.h"

namespace crumple {

InputMesh make_grid(int n, bool alternate) {
  if (n < 2 || n > 8192) {
    throw InputError("grid: n = " + std::to_string(n) + " is out of range [2, 8192]");
  }
  const std::size_t side = static_cast<std::size_t>(n);
  InputMesh mesh;
  mesh.positions.reserve(side * side);
  for (int iy = 0; iy < n; ++iy) {
    for (int ix = 0; ix < n; ++ix) {
      mesh.positions.push_back({static_cast<double>(ix) / (n - 1),
                                static_cast<double>(iy) / (n - 1), 0.0});
    }
  }
  mesh.triangles.reserve(2 * (side - 1) * (side - 1));
  for (int iy = 0; iy + 1 < n; ++iy) {
    for (int ix = 0; ix + 1 < n; ++ix) {
      // Quad corners counter-clockwise seen from +z.
      const int a = iy * n + ix;  // (ix,     iy)
      const int b = a + 1;        // (ix + 1, iy)
      const int c = b + n;        // (ix + 1, iy + 1)
      const int d = a + n;        // (ix,     iy + 1)
      if (alternate && (ix + iy) % 2 == 1) {  // diagonal b-d
        mesh.triangles.push_back({a, b, d});
        mesh.triangles.push_back({b, c, d});
      } else {  // diagonal a-c
        mesh.triangles.push_back({a, b, c});
        mesh.triangles.push_back({a, c, d});
      }
    }
  }
  return mesh;
}

}  // namespace crumple
