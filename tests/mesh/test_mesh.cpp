// Tests for crumple_mesh: grids, OBJ loading and validation, OBJ writing.
// Expected values are worked out by hand in the comments, not taken from the implementation.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mesh/input_mesh.h"

namespace {

namespace fs = std::filesystem;
using crumple::InputError;
using crumple::InputMesh;
using Tri = std::array<int, 3>;

// A per-process scratch directory, removed at exit.
struct TempDir {
  fs::path path;  // the directory
  TempDir()
      : path(fs::temp_directory_path() / ("crumple_test_mesh_" + std::to_string(::getpid()))) {
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

const fs::path& temp_dir() {
  static TempDir dir;
  return dir.path;
}

// Writes `text` to a file `name` in the scratch directory and returns its path.
std::string write_file(const std::string& name, const std::string& text) {
  const fs::path path = temp_dir() / name;
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

// The InputError message of load_obj(path); a test failure if it loads or the message is
// not a single line.
std::string rejection(const std::string& path) {
  try {
    crumple::load_obj(path);
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    return message;
  }
  ADD_FAILURE() << path << " was accepted";
  return "";
}

// Writes an OBJ file and expects load_obj to reject it with a message that contains the file
// name and every one of `parts`.
std::string expect_rejected(const std::string& name, const std::string& text,
                            std::initializer_list<std::string> parts) {
  const std::string message = rejection(write_file(name, text));
  EXPECT_NE(message.find(name), std::string::npos) << message;
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "expected '" << part << "' in: " << message;
  }
  return message;
}

// Same for validate_mesh on an in-memory mesh.
std::string expect_invalid(const InputMesh& mesh, std::initializer_list<std::string> parts) {
  try {
    crumple::validate_mesh(mesh, "memo");
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("memo: ", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "expected '" << part << "' in: " << message;
    }
    return message;
  }
  ADD_FAILURE() << "mesh was accepted";
  return "";
}

// z component of (p1 - p0) x (p2 - p0): twice the signed area seen from +z.
double normal_z(const InputMesh& m, const Tri& t) {
  const auto& a = m.positions[t[0]];
  const auto& b = m.positions[t[1]];
  const auto& c = m.positions[t[2]];
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Does triangle t traverse the directed edge a -> b?
bool has_directed_edge(const Tri& t, int a, int b) {
  for (int k = 0; k < 3; ++k) {
    if (t[k] == a && t[(k + 1) % 3] == b) return true;
  }
  return false;
}

std::set<std::pair<int, int>> undirected_edges(const InputMesh& m) {
  std::set<std::pair<int, int>> edges;
  for (const Tri& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
    }
  }
  return edges;
}

// ---------------------------------------------------------------------------------------------
// make_grid

TEST(Grid, CountsAndPositions) {
  // n x n vertices, 2 (n-1)^2 triangles: 3 -> 9 and 8, 5 -> 25 and 32.
  const InputMesh g3 = crumple::make_grid(3);
  EXPECT_EQ(g3.positions.size(), 9u);
  EXPECT_EQ(g3.triangles.size(), 8u);
  const InputMesh g5 = crumple::make_grid(5, false);
  EXPECT_EQ(g5.positions.size(), 25u);
  EXPECT_EQ(g5.triangles.size(), 32u);
  // Vertex (ix, iy) is at index iy * n + ix and position (ix, iy) / (n - 1).
  const std::array<double, 3> v5{1.0, 0.5, 0.0};   // n = 3: index 5 = (2, 1)
  const std::array<double, 3> v7{0.5, 1.0, 0.0};   // n = 3: index 7 = (1, 2)
  const std::array<double, 3> v13{0.75, 0.5, 0.0}; // n = 5: index 13 = (3, 2)
  EXPECT_EQ(g3.positions[5], v5);
  EXPECT_EQ(g3.positions[7], v7);
  EXPECT_EQ(g5.positions[13], v13);
  EXPECT_EQ(g5.positions[24], (std::array<double, 3>{1.0, 1.0, 0.0}));
}

TEST(Grid, NormalsPointUpInBothModes) {
  for (bool alternate : {false, true}) {
    const InputMesh g = crumple::make_grid(4, alternate);
    // Each triangle is half a (1/3 x 1/3) square: twice its area is 1/9.
    for (const Tri& t : g.triangles) EXPECT_NEAR(normal_z(g, t), 1.0 / 9.0, 1e-15);
  }
}

TEST(Grid, DiagonalPatterns) {
  // n = 3, quads in order (0,0), (1,0), (0,1), (1,1) with corners a b c d counter-clockwise.
  // Fixed diagonal a-c everywhere; alternating: quads (1,0) and (0,1) use b-d instead, so all
  // diagonals meet at the centre vertex 4 (the "union jack").
  const std::vector<Tri> fixed{{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4},
                               {3, 4, 7}, {3, 7, 6}, {4, 5, 8}, {4, 8, 7}};
  const std::vector<Tri> alternating{{0, 1, 4}, {0, 4, 3}, {1, 2, 4}, {2, 5, 4},
                                     {3, 4, 6}, {4, 7, 6}, {4, 5, 8}, {4, 8, 7}};
  EXPECT_EQ(crumple::make_grid(3, false).triangles, fixed);
  EXPECT_EQ(crumple::make_grid(3, true).triangles, alternating);
}

TEST(Grid, EulerCharacteristicIsOne) {
  // A disc: V - E + F = 1. By hand for n = 3: 9 - (6 + 6 + 4) + 8 = 1.
  EXPECT_EQ(undirected_edges(crumple::make_grid(3)).size(), 16u);
  for (int n : {2, 3, 6, 11}) {
    for (bool alternate : {false, true}) {
      const InputMesh g = crumple::make_grid(n, alternate);
      const long euler = static_cast<long>(g.positions.size()) -
                         static_cast<long>(undirected_edges(g).size()) +
                         static_cast<long>(g.triangles.size());
      EXPECT_EQ(euler, 1) << "n = " << n << ", alternate = " << alternate;
    }
  }
}

TEST(Grid, PassesValidation) {
  EXPECT_NO_THROW(crumple::validate_mesh(crumple::make_grid(2), "grid"));
  EXPECT_NO_THROW(crumple::validate_mesh(crumple::make_grid(9, true), "grid"));
  EXPECT_NO_THROW(crumple::validate_mesh(crumple::make_grid(9, false), "grid"));
}

TEST(Grid, RejectsBadSizes) {
  for (int n : {-3, 0, 1, 8193}) EXPECT_THROW(crumple::make_grid(n), InputError) << n;
  EXPECT_NO_THROW(crumple::make_grid(2));
}

// ---------------------------------------------------------------------------------------------
// load_obj: polygons, unreferenced vertices, orientation

TEST(LoadObj, QuadBecomesTwoTrianglesOnTheShorterDiagonal) {
  // Convex quad (0,0) (1,0) (3,3) (0,1): diagonal 1-3 has length sqrt(18), 2-4 sqrt(2), so the
  // split is along 2-4 (0-based 1-3). Shoelace area 3 = 0.5 + 2.5.
  const std::string path = write_file("quad.obj", "v 0 0 0\nv 1 0 0\nv 3 3 0\nv 0 1 0\nf 1 2 3 4\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.positions.size(), 4u);
  double twice_area = 0.0;
  for (const Tri& t : m.triangles) {
    EXPECT_NE(std::find(t.begin(), t.end(), 1), t.end());
    EXPECT_NE(std::find(t.begin(), t.end(), 3), t.end());
    EXPECT_GT(normal_z(m, t), 0.0);  // counter-clockwise input stays counter-clockwise
    twice_area += normal_z(m, t);
  }
  EXPECT_DOUBLE_EQ(twice_area, 6.0);
}

TEST(LoadObj, ConcaveQuadIsSplitInside) {
  // Dart (0,0) (10,1) (0,2) (1,1): vertex 4 is reflex, so the shorter diagonal 1-3 (length 2)
  // lies outside; the split must use 2-4. Shoelace area 9.
  const std::string path =
      write_file("dart.obj", "v 0 0 0\nv 10 1 0\nv 0 2 0\nv 1 1 0\nf 1 2 3 4\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.triangles.size(), 2u);
  double twice_area = 0.0;
  for (const Tri& t : m.triangles) {
    EXPECT_NE(std::find(t.begin(), t.end(), 1), t.end());
    EXPECT_NE(std::find(t.begin(), t.end(), 3), t.end());
    EXPECT_GT(normal_z(m, t), 0.0);
    twice_area += normal_z(m, t);
  }
  EXPECT_DOUBLE_EQ(twice_area, 18.0);
}

TEST(LoadObj, PentagonBecomesThreeTriangles) {
  const std::string path = write_file(
      "pentagon.obj", "v 0 0 0\nv 2 0 0\nv 3 2 0\nv 1 3 0\nv -1 2 0\nf 1 2 3 4 5\n");
  const InputMesh m = crumple::load_obj(path);
  EXPECT_EQ(m.triangles.size(), 3u);
  double twice_area = 0.0;
  for (const Tri& t : m.triangles) twice_area += normal_z(m, t);
  // Shoelace: 0 + 4 + 7 + 5 + 0 = 16, area 8.
  EXPECT_DOUBLE_EQ(twice_area, 16.0);
}

TEST(LoadObj, UnreferencedVerticesAreDroppedAndIndicesRemapped) {
  // Vertices 1 and 4 are unused; 2, 3, 5 become 0, 1, 2.
  const std::string path = write_file(
      "unref.obj", "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 8 8 8\nv 0 1 0\nf 2 3 5\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0], (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(m.positions[1], (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(m.positions[2], (std::array<double, 3>{0, 1, 0}));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
}

TEST(LoadObj, RelativeIndices) {
  // -3 -2 -1 after three vertices are 1 2 3; other 'v', 'vn', 'vt' lines do not shift them.
  const std::string path = write_file(
      "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  // Second face: vertices 2 3 4 after four vertices; 2 -> 1, 4 -> 3, 3 -> 2.
  EXPECT_EQ(m.triangles[1], (Tri{1, 3, 2}));
}

TEST(LoadObj, OtherElementsAreIgnored) {
  // Materials (even missing ones), groups, objects, smoothing, normals, texture coordinates,
  // comments, blank lines and leading blanks do not change the geometry.
  const std::string path = write_file(
      "extras.obj",
      "# header\nmtllib missing.mtl\no thing\ng part\nusemtl nothing\ns 1\n\n"
      "  v 0 0 0\n\tv 1 0 0\nv 0 1 0 0.5 0.5 0.5\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[2], (std::array<double, 3>{0, 1, 0}));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
}

TEST(LoadObj, InconsistentStripIsFlipped) {
  // Square split along 1-3. Face 1 (1 2 3) is counter-clockwise, face 2 (1 4 3) clockwise:
  // both run 3 -> 1 along the shared edge. The second must be flipped so that it runs 1 -> 3
  // (0-based: the first keeps 2 -> 0, the second gets 0 -> 2).
  const std::string text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n";
  const InputMesh m = crumple::load_obj(write_file("strip.obj", text));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));  // the first triangle keeps its orientation
  EXPECT_TRUE(has_directed_edge(m.triangles[0], 2, 0));
  EXPECT_TRUE(has_directed_edge(m.triangles[1], 0, 2));
  for (const Tri& t : m.triangles) EXPECT_GT(normal_z(m, t), 0.0);
  EXPECT_NO_THROW(crumple::validate_mesh(m, "strip"));

  // Reversed order: now the clockwise triangle comes first and sets the orientation.
  const InputMesh r =
      crumple::load_obj(write_file("strip2.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 4 3\nf 1 2 3\n"));
  ASSERT_EQ(r.triangles.size(), 2u);
  EXPECT_EQ(r.triangles[0], (Tri{0, 3, 2}));
  for (const Tri& t : r.triangles) EXPECT_LT(normal_z(r, t), 0.0);
}

TEST(LoadObj, ComponentsAreOrientedSeparately) {
  // Two separate triangles, one clockwise: nothing to make consistent, both kept as written.
  const std::string path = write_file(
      "two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\nf 4 6 5\n");
  const InputMesh m = crumple::load_obj(path);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], (Tri{3, 5, 4}));
}

TEST(LoadObj, MinimalMoebiusStripIsRejectedAtTheClosingEdge) {
  // The 5-vertex Moebius strip: triangles (i, i+1, i+2) mod 5, lines 6..10. Every pair of
  // neighbors traverses its shared edge the same way, so each step of the search flips.
  // Breadth-first from T0 (1 2 3): T4 and T1 flipped, then T3 (via 5-1) kept, T2 (via 3-4)
  // kept, then T3 meets T2 across edge 4-5 wanting a flip: conflict at edge (4,5).
  std::ostringstream text;
  for (int k = 0; k < 5; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 5.0;
    text << "v " << std::cos(a) << " " << std::sin(a) << " " << 0.3 * (k % 2) << "\n";
  }
  text << "f 1 2 3\nf 2 3 4\nf 3 4 5\nf 4 5 1\nf 5 1 2\n";
  expect_rejected("moebius5.obj", text.str(), {"non-orientable", "edge (4,5)", "line 9", "line 8"});
}

TEST(LoadObj, MoebiusStripIsRejected) {
  // A twisted band of 12 quads (24 triangles); the last quad joins top to bottom.
  const int n = 12;
  std::ostringstream text;
  for (int i = 0; i < n; ++i) {
    const double u = 2.0 * std::numbers::pi * i / n;
    for (double v : {-0.3, 0.3}) {
      const double r = 1.0 + v * std::cos(u / 2);
      text << "v " << r * std::cos(u) << " " << r * std::sin(u) << " " << v * std::sin(u / 2)
           << "\n";
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = 2 * i + 2;  // bottom and top at step i
    const int c = i + 1 < n ? a + 2 : 2;     // the twist: bottom meets top of step 0
    const int d = i + 1 < n ? b + 2 : 1;
    text << "f " << a << " " << c << " " << d << "\n";
    text << "f " << a << " " << d << " " << b << "\n";
  }
  expect_rejected("moebius.obj", text.str(), {"non-orientable", "edge ("});
}

// ---------------------------------------------------------------------------------------------
// load_obj: bad input names file and line, or vertex/edge

TEST(LoadObjErrors, MissingFile) {
  const std::string path = (temp_dir() / "does-not-exist.obj").string();
  const std::string message = rejection(path);
  EXPECT_NE(message.find("does-not-exist.obj"), std::string::npos) << message;
  EXPECT_NE(message.find("cannot open"), std::string::npos) << message;
  EXPECT_THROW(crumple::load_obj(temp_dir().string()), InputError);  // a directory
}

TEST(LoadObjErrors, NonFiniteCoordinates) {
  expect_rejected("nan.obj", "v 0 0 0\nv nan 0 0\nv 1 1 0\nf 1 2 3\n", {":2:", "vertex 2", "nan"});
  expect_rejected("inf.obj", "v 0 0 0\nv 1 0 0\nv 1 -inf 0\nf 1 2 3\n", {":3:", "vertex 3"});
  // Finite as text but beyond double: the parser makes it infinite.
  expect_rejected("huge.obj", "# big\nv 1e400 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n", {":2:", "vertex 1"});

}

TEST(LoadObjErrors, MalformedCoordinates) {
  expect_rejected("word.obj", "v 0 0 0\nv 1 zero 0\nv 1 1 0\nf 1 2 3\n", {":2:", "not a number"});
  expect_rejected("short.obj", "v 0 0 0\nv 1 0 0\nv 1 1\nf 1 2 3\n", {":3:", "2 coordinates"});
}

// Each of these read as a number before (from_chars after dropping '+', or the overflow passed
// as "still a number") while tinyobjloader stored 0: a wrong mesh, exit 0.
TEST(LoadObjErrors, CoordinatesAreStrictDecimals) {
  expect_rejected("plusminus.obj", "v 0 0 0\nv 1 +-1 0\nv 1 1 0\nf 1 2 3\n", {":2:", "'+-1'", "not a number"});
  expect_rejected("overflow.obj", "v 0 0 0\nv 1 0 0\nv 1e99999999999 1 0\nf 1 2 3\n", {":3:", "not finite"});
  expect_rejected("hex.obj", "v 0 0 0\nv 0x1 0 0\nv 1 1 0\nf 1 2 3\n", {":2:", "not a number"});
  // A plain '+' sign and an underflow to 0 are numbers.
  const InputMesh m = crumple::load_obj(write_file("plus.obj", "v 0 1e-99999 0\nv +1 0 0\nv 1 +1 0\nf 1 2 3\n"));
  EXPECT_EQ(m.positions[1][0], 1.0);
  EXPECT_EQ(m.positions[0][1], 0.0);
}

// atoi read each of these as a valid index (3, 3, 3, -1 = the last vertex): exit 0, wrong mesh.
TEST(LoadObjErrors, FaceIndicesAreStrictIntegers) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  for (const char* corner : {"4294967299", "99999999999999999999", "3abc", "3.9", "+3", "3/", "3/1/1/1"}) {
    expect_rejected("index.obj", v + "f 1 2 " + corner + "\n", {":5:", std::string("'") + corner + "'"});
  }
  // The forms OBJ allows are read (vt and vn indices are checked by tinyobjloader).
  const std::string full = v + "vt 0 0\nvn 0 0 1\nf 1/1/1 2//1 -2/1\n";
  EXPECT_EQ(crumple::load_obj(write_file("forms.obj", full)).triangles.size(), 1u);
}

// The mark was read as part of line 1, so the first vertex was dropped and every index shifted.
TEST(LoadObj, Utf8ByteOrderMarkIsSkipped) {
  const InputMesh m = crumple::load_obj(write_file("bom.obj", "\xEF\xBB\xBFv 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\n"));
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0][0], 5.0);
  EXPECT_EQ(m.positions[1][0], 6.0);
}

// A FIFO blocked forever and /dev/zero was read until memory ran out; /dev/null read as empty.
TEST(LoadObjErrors, OnlyRegularFilesOfBoundedSize) {
  EXPECT_NE(rejection("/dev/null").find("not a regular file"), std::string::npos);
  const std::string big = write_file("big.obj", "");
  fs::resize_file(big, crumple::kMaxObjBytes + 1);  // sparse: no disk used
  EXPECT_NE(rejection(big).find("256 MiB"), std::string::npos);
  fs::remove(big);
}

// Coordinates float cannot simulate: these passed validation and went unstable at frame 1.
TEST(LoadObjErrors, CoordinatesBeyondFloatAreRejected) {
  const std::string tri = "\nf 1 2 3\n";
  expect_rejected("far.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0" + tri, {"vertex 2", "too large"});
  expect_rejected("offset.obj", "v 1e7 0 0\nv 1.001e7 0 0\nv 1e7 0.001 0" + tri, {"edge (", "float cannot resolve"});
  expect_rejected("tiny.obj", "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0" + tri, {"edge (", "float cannot resolve"});
  // Just inside each bound.
  EXPECT_NO_THROW(crumple::load_obj(write_file("ok_far.obj", "v 0 0 0\nv 1e9 0 0\nv 0 1e9 0" + tri)));
  EXPECT_NO_THROW(crumple::load_obj(write_file("ok_offset.obj", "v 1e4 0 0\nv 1e4 0.1 0\nv 1e4 0 0.1" + tri)));
  EXPECT_NO_THROW(crumple::load_obj(write_file("ok_tiny.obj", "v 0 0 0\nv 1e-9 0 0\nv 0 1e-9 0" + tri)));
  InputMesh grid = crumple::make_grid(3);
  for (auto& p : grid.positions) p[0] += 1e9;  // spacing 0.5 at 1e9: below 1e-5 x 1e9
  EXPECT_THROW(crumple::validate_mesh(grid, "grid"), InputError);
}

TEST(LoadObjErrors, LineNumbersFollowAnyLineEnding) {
  // CRLF and lone CR endings: the bad vertex is still on line 3.
  expect_rejected("crlf.obj", "v 0 0 0\r\nv 1 0 0\r\nv 1 nan 0\r\nf 1 2 3\r\n", {":3:"});
  expect_rejected("cr.obj", "v 0 0 0\rv 1 0 0\rv 1 1 0\r\rf 1 2 7\r", {":5:", "vertex 7"});
}

TEST(LoadObjErrors, IndexOutOfRange) {
  // tinyobjloader alone would blame the last line (7); the face is on line 5.
  const std::string m = expect_rejected(
      "oob.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n# comment\nf 1 2 4\n# end\n\n",
      {":5:", "vertex 4", "3 vertices"});
  EXPECT_EQ(m.find(":7:"), std::string::npos) << m;
  // Relative index -4 with three vertices above.
  expect_rejected("neg.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -4 -2 -1\n", {":4:", "-4"});
  // Index 0 is invalid in OBJ (reported by tinyobjloader with its line).
  expect_rejected("zero.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 0 2\n", {":5:"});
  // Normal index out of range: no line from tinyobjloader, but named.
  expect_rejected("vn.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nf 1//2 2//1 3//1\n", {"normal"});
}

TEST(LoadObjErrors, NoTriangles) {
  expect_rejected("points.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n", {"no triangles"});
  expect_rejected("lines.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\n", {"no triangles"});
  expect_rejected("empty.obj", "", {"no triangles"});
  expect_rejected("twocorners.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2\n", {":4:", "2 vertices"});
}

TEST(LoadObjErrors, DegenerateTriangles) {
  expect_rejected("repeat.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 2 2\n",
                  {":5:", "repeats vertex 2"});
  expect_rejected("collinear.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 4 2\nf 1 2 3\n",
                  {":6:", "degenerate"});
  // Threshold 1e-12 * diagonal^2: the bounding box is the unit cube, diagonal^2 = 3, so the
  // limit is 3e-12. A sliver of base 1 and height h has area h / 2.
  const std::string base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n";
  expect_rejected("sliver.obj", base + "v 0.5 2e-12 1\nf 1 2 3\nf 4 5 6\n", {":8:", "degenerate"});
  EXPECT_NO_THROW(crumple::load_obj(write_file("thin.obj", base + "v 0.5 1e-11 1\nf 1 2 3\nf 4 5 6\n")));
}

TEST(LoadObjErrors, NonManifoldEdge) {
  // Three triangles on edge 1-2 (lines 6, 7, 8).
  expect_rejected("fin.obj",
                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
                  {"edge (1,2)", "non-manifold", "3 triangles", "6, 7, 8"});
}

TEST(LoadObjErrors, NonManifoldVertex) {
  // Two triangles touching only at a vertex (a bow tie). Vertex 1 is unused and dropped; the
  // message still uses the file's numbering, so the apex is vertex 2.
  expect_rejected("bowtie.obj",
                  "v 7 7 7\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv -1 0 0\nv -1 -1 0\nf 2 3 4\nf 2 5 6\n",
                  {"vertex 2", "non-manifold", "2 fans"});
}

TEST(LoadObjErrors, PolygonLimits) {
  // tinyobjloader counts face corners in an unsigned char: 300 must be refused, 255 works.
  auto polygon = [](int n) {
    std::ostringstream text;
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * std::numbers::pi * k / n;
      text << "v " << std::cos(a) << " " << std::sin(a) << " 0\n";
    }
    text << "f";
    for (int k = 1; k <= n; ++k) text << " " << k;
    text << "\n";
    return text.str();
  };
  expect_rejected("gon300.obj", polygon(300), {":301:", "300 vertices"});
  EXPECT_EQ(crumple::load_obj(write_file("gon255.obj", polygon(255))).triangles.size(), 253u);
  // A polygon whose vertices all lie on a line cannot be split.
  expect_rejected("flatquad.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n", {":5:"});
}

// ---------------------------------------------------------------------------------------------
// validate_mesh on in-memory meshes (0-based vertex indices in messages)

InputMesh two_triangles() {
  // Unit square split along 0-2, consistently counter-clockwise.
  return {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}};
}

TEST(ValidateMesh, AcceptsAGoodMesh) { EXPECT_NO_THROW(crumple::validate_mesh(two_triangles(), "memo")); }

TEST(ValidateMesh, RejectsEachViolation) {
  expect_invalid({{{0, 0, 0}}, {}}, {"no triangles"});

  InputMesh m = two_triangles();
  m.triangles[1][2] = 4;
  expect_invalid(m, {"triangle 1", "vertex 4", "4 vertices"});
  m.triangles[1][2] = -1;
  expect_invalid(m, {"triangle 1", "-1"});

  m = two_triangles();
  m.positions[3][1] = std::nan("");
  expect_invalid(m, {"vertex 3", "not finite"});

  m = two_triangles();
  m.positions.push_back({5, 5, 5});
  expect_invalid(m, {"vertex 4", "not used"});

  m = two_triangles();
  m.positions[3] = {2, 2, 0};  // on the line through 0 and 2
  expect_invalid(m, {"triangle 1", "degenerate"});
  m = two_triangles();
  m.triangles[1] = {0, 3, 3};
  expect_invalid(m, {"triangle 1", "repeats vertex 3"});

  // Second triangle clockwise: both run 2 -> 0.
  m = two_triangles();
  m.triangles[1] = {0, 3, 2};
  expect_invalid(m, {"edge (0,2)", "inconsistent orientation"});

  // A third triangle on edge 0-2.
  m = two_triangles();
  m.positions.push_back({0.5, 0.5, 1});
  m.triangles.push_back({0, 4, 2});
  expect_invalid(m, {"edge (0,2)", "non-manifold", "3 triangles"});

  // Bow tie at vertex 0.
  InputMesh bow{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}}};
  expect_invalid(bow, {"vertex 0", "non-manifold"});
}

TEST(ValidateMesh, ClosedFanAroundAVertexIsManifold) {
  // An octahedron: every vertex has a closed fan of four triangles.
  const InputMesh oct{{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
                      {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}}};
  EXPECT_NO_THROW(crumple::validate_mesh(oct, "octahedron"));
}

// ---------------------------------------------------------------------------------------------
// write_obj

TEST(WriteObj, FormatIsNineSignificantDigitsAndOneBasedFaces) {
  const std::string path = (temp_dir() / "format.obj").string();
  crumple::write_obj(path, {{0.1, 1.0 / 3.0, 1e-20}, {2, 0, 0}, {0, 2, 0}}, {{0, 1, 2}});
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "v 0.1 0.333333333 1e-20\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
}

TEST(WriteObj, RoundTripsThroughLoadObj) {
  const InputMesh g = crumple::make_grid(7, true);
  const std::string path = (temp_dir() / "grid7.obj").string();
  crumple::write_obj(path, g.positions, g.triangles);
  const InputMesh back = crumple::load_obj(path);
  ASSERT_EQ(back.positions.size(), g.positions.size());
  EXPECT_EQ(back.triangles, g.triangles);
  // write_obj prints 9 significant digits: agreement to that precision.
  for (std::size_t k = 0; k < g.positions.size(); ++k) {
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(back.positions[k][d], g.positions[k][d], 1e-7);
  }
}

TEST(WriteObj, FailureIsReported) {
  const std::string path = (temp_dir() / "no-such-dir" / "x.obj").string();
  try {
    crumple::write_obj(path, {{0, 0, 0}}, {});
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write " + path + ": No such file or directory");
  }
}

// ---------------------------------------------------------------------------------------------
// Real meshes (tests/data, see its README.md)

struct RealMesh {
  const char* file;         // name in tests/data
  int vertices;             // expected after dropping unreferenced vertices; 0 if rejected
  int triangles;            // expected triangles; 0 if rejected
  const char* rejection;    // expected part of the message if rejected, else nullptr
};

// Counts from the data README: the bunny has 35947 vertices of which 1113 are unreferenced.
// The rejections were found in the files by hand: beetle's faces on lines 2448, 3917 and 3918
// all have the edge 57-63; suzanne's quads on lines 1170 (71 197 139 138) and 1171
// (71 138 139 198) both have 71 and 139 as opposite corners and both split on that diagonal.
const RealMesh kRealMeshes[] = {
    {"woody.obj", 694, 1267, nullptr},
    {"alligator.obj", 3208, 5981, nullptr},
    {"spot.obj", 2930, 5856, nullptr},
    {"stanford-bunny.obj", 35947 - 1113, 69451, nullptr},
    {"beetle.obj", 0, 0, "edge (57,63) is non-manifold: shared by 3 triangles (lines 2448, 3917, 3918)"},
    {"suzanne.obj", 0, 0, "edge (71,139) is non-manifold: shared by 4 triangles (lines 1170, 1170, 1171, 1171)"},
};

void PrintTo(const RealMesh& mesh, std::ostream* out) { *out << mesh.file; }

class RealMeshTest : public ::testing::TestWithParam<RealMesh> {};

TEST_P(RealMeshTest, LoadsOrIsRejectedWithInputError) {
  const RealMesh& expected = GetParam();
  const std::string path = std::string(CRUMPLE_TEST_DATA) + "/" + expected.file;
  InputMesh mesh;
  try {
    mesh = crumple::load_obj(path);
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(expected.file), std::string::npos) << message;
    ASSERT_NE(expected.rejection, nullptr) << "unexpected rejection: " << message;
    EXPECT_NE(message.find(expected.rejection), std::string::npos) << message;
    return;
  }
  ASSERT_EQ(expected.rejection, nullptr) << expected.file << " was accepted";
  EXPECT_EQ(mesh.positions.size(), static_cast<std::size_t>(expected.vertices));
  EXPECT_EQ(mesh.triangles.size(), static_cast<std::size_t>(expected.triangles));
  EXPECT_NO_THROW(crumple::validate_mesh(mesh, expected.file));
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, RealMeshTest, ::testing::ValuesIn(kRealMeshes),
                         [](const ::testing::TestParamInfo<RealMesh>& info) {
                           std::string name = info.param.file;
                           name = name.substr(0, name.find('.'));
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(RealMeshes, FlatCutOutsFaceOneWay) {
  // woody and alligator lie in z = 0: consistent orientation means every normal has the same
  // sign of z.
  for (const char* file : {"woody.obj", "alligator.obj"}) {
    const InputMesh m = crumple::load_obj(std::string(CRUMPLE_TEST_DATA) + "/" + file);
    int up = 0, down = 0;
    for (const Tri& t : m.triangles) (normal_z(m, t) > 0 ? up : down)++;
    EXPECT_TRUE(up == 0 || down == 0) << file << ": " << up << " up, " << down << " down";
  }
}

TEST(RealMeshes, SpotIsAClosedSphere) {
  // Genus 0 and closed: V - E + F = 2 and every edge in exactly two triangles (E = 3F/2).
  const InputMesh m = crumple::load_obj(std::string(CRUMPLE_TEST_DATA) + "/spot.obj");
  const long edges = static_cast<long>(undirected_edges(m).size());
  EXPECT_EQ(2 * edges, 3 * static_cast<long>(m.triangles.size()));
  EXPECT_EQ(static_cast<long>(m.positions.size()) - edges + static_cast<long>(m.triangles.size()), 2);
}

}  // namespace
