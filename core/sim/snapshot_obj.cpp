#include <cstdio>

#include "sim/simulator.h"

namespace crumple {

void write_snapshot_obj(std::FILE* f, const Snapshot& s) {
  std::vector<int> id(s.position.size(), -1);
  int next = 1;
  for (size_t k = 0; k < s.position.size(); ++k)
    if (s.vertex_alive[k]) id[k] = next++;
  std::fprintf(f, "# crumple: %d vertices; 'l' lines are auxiliary springs (broken edges)\n", next - 1);
  for (size_t k = 0; k < s.position.size(); ++k)
    if (s.vertex_alive[k]) std::fprintf(f, "v %.9g %.9g %.9g\n", s.position[k][0], s.position[k][1], s.position[k][2]);
  for (const auto& t : s.triangles)
    if (t[0] >= 0) std::fprintf(f, "f %d %d %d\n", id[t[0]], id[t[1]], id[t[2]]);
  for (const EdgeView& e : s.edges)
    if (e.a >= 0 && e.auxiliary) std::fprintf(f, "l %d %d\n", id[e.a], id[e.b]);
}

}  // namespace crumple
