// bench/bytes_moved.h on a known small state: the 4 x 4 grid (16 vertices, 33 edges: 12 + 12
// sides and 9 diagonals, 18 triangles, every adjacency block of the least room, 8), whose counts
// are worked out here
// by hand from the formulas of bytes_moved.cpp. A formula that counts an array twice (the
// EdgeOut records once per list entry rather than once per edge, say), drops one (the
// neighbours' guesses in a sweep), or ignores the sweep count, gives another number.
#include <gtest/gtest.h>

#include "bytes_moved.h"
#include "fast/fast_sim.h"
#include "mesh/input_mesh.h"

namespace crumple::bench {
namespace {

LayoutSizes grid4() {
  const fast::FastSimulator sim(make_grid(4), Params{}, 1);
  return layout_sizes(sim.topology());
}

TEST(BytesMoved, SizesOfTheGrid) {
  const LayoutSizes s = grid4();
  EXPECT_EQ(s.vertices, 16);
  EXPECT_EQ(s.edges, 33);
  EXPECT_EQ(s.triangles, 18);
  EXPECT_EQ(s.room_e, 8);
  EXPECT_EQ(s.room_t, 8);
}

TEST(BytesMoved, PassesOfTheGridByHand) {
  const LayoutSizes s = grid4();
  // A list walked: its 8-byte head and its 8-entry block, 40 bytes.
  // normals: 18 (24 + 1 + 16) + 16 * 16 for the areas; 16 (40 + 16) + 18 * 16 for the sums.
  EXPECT_EQ(pass_bytes("normals", s, 1, 0), 738 + 256 + 896 + 288);
  // edge_forces: 33 (36 + 32) + 16 * 32 (no packing: the passes read the vertex rows; no
  // velocities without damping).
  EXPECT_EQ(pass_bytes("edge_forces", s, 1, 0), 2244 + 512);
  // gather: 16 (40 + 32 + 40 + 16 + 16 + 16 + 16) + 33 * 32.
  EXPECT_EQ(pass_bytes("gather", s, 1, 0), 2816 + 1056);
  // integrate, one sweep: 16 (40 + 4 + 16 + 12 + 16 + 16); drift 16 * 44; advance 16 * 64.
  EXPECT_EQ(pass_bytes("integrate", s, 1, 0), 1664 + 704 + 1024);
  EXPECT_EQ(pass_bytes("integrate", s, 3, 0) - pass_bytes("integrate", s, 1, 0), 2 * 1664);
  // adapt_test: the normals, 33 (36 + 4 + 1) and 16 * 32.
  EXPECT_EQ(pass_bytes("adapt_test", s, 1, 0), 2178 + 1353 + 512);
  EXPECT_EQ(pass_bytes("no_such_pass", s, 1, 0), 0);
}

TEST(BytesMoved, FrozenStepIsItsFourPasses) {
  const LayoutSizes s = grid4();
  EXPECT_EQ(frozen_step_bytes(s, 1), 2178 + 2756 + 3872 + 3392);
}

TEST(BytesMoved, EventsCountTheLinesOfTheirRows) {
  const LayoutSizes s = grid4();
  // 5 vertices of 4 rows + lid + phys + 2 list heads + 4 blocks of one line, 5 edges of 4
  // (record at most 2, lid, phys), 4 triangles of 6 (record at most 2, alive, area, lid, phys),
  // a 128-byte split record: 106 lines.
  const double per_event = 64 * (5 * 12 + 5 * 4 + 4 * 6 + 2);
  EXPECT_EQ(pass_bytes("topology_apply", s, 1, 0), pass_bytes("adapt_test", s, 1, 0) + 2 * 33);
  EXPECT_EQ(pass_bytes("topology_apply", s, 1, 3) - pass_bytes("topology_apply", s, 1, 0), 3 * per_event);
}

}  // namespace
}  // namespace crumple::bench
