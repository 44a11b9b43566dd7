// The `crumple` command as a user meets it: outputs, exit codes, one-line errors, no half-written
// output folder.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

struct Result {
  int code = -1;       ///< exit status
  std::string err;     ///< stderr
  std::string out;     ///< stdout
};

Result crumple(const std::string& args) {
  static int calls = 0;  // ctest runs these tests in parallel processes: unique files each
  const fs::path dir = fs::temp_directory_path() /
                       ("crumple_cli_io_" + std::to_string(::getpid()) + "_" + std::to_string(++calls));
  fs::create_directories(dir);
  const std::string err = (dir / "stderr.txt").string(), out = (dir / "stdout.txt").string();
  const std::string cmd = std::string(CRUMPLE_EXE) + " " + args + " >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err), o(out);
  std::stringstream se, so;
  se << e.rdbuf();
  so << o.rdbuf();
  r.err = se.str();
  r.out = so.str();
  fs::remove_all(dir);
  return r;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("crumple_cli_" + name);
  fs::remove_all(d);
  return d;
}

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / name;
  std::ofstream(p) << text;
  return p;
}

// An error is exactly one line on stderr that begins "crumple: error:" and names `what`.
void expect_error(const Result& r, int code, const std::string& what) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_EQ(r.err.rfind("crumple: error:", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
}

TEST(Cli, RunWritesStatsAndFinalObj) {
  const fs::path d = fresh_dir("ok");
  const Result r = crumple("run --grid 8 --frames 30 --every 10 --seed 3 --out " + d.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream stats(d / "stats.csv");
  std::string header, line;
  std::getline(stats, header);
  EXPECT_EQ(header, "frame,time,vertices,edges,triangles,splits,restores,mass,px,py,pz,kinetic,max_strain,step_ms,substeps");
  int rows = 0;
  while (std::getline(stats, line)) ++rows;
  EXPECT_EQ(rows, 30);
  EXPECT_TRUE(fs::exists(d / "final.obj"));
  EXPECT_TRUE(fs::exists(d / "frame_00010.obj"));
  EXPECT_TRUE(fs::exists(d / "frame_00030.obj"));
  EXPECT_FALSE(fs::exists(d / "frame_00015.obj"));
}

// Catches a missing --version or one that disagrees with CMake's project version.
TEST(Cli, VersionIsTheProjectVersion) {
  const Result r = crumple("--version");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, std::string("crumple ") + CRUMPLE_EXPECTED_VERSION + "\n");
}

TEST(Cli, BadArgumentsExitTwoWithOneLine) {
  expect_error(crumple("run --grid 1"), 2, "--grid");
  expect_error(crumple("run --phi 1.5"), 2, "--phi");
  expect_error(crumple("run --kappa nan"), 2, "--kappa");
  expect_error(crumple("run --integrator magic"), 2, "--integrator");
  expect_error(crumple("run --frames 0"), 2, "--frames");
  expect_error(crumple("run --varphi 0.5"), 2, "--varphi");
  expect_error(crumple("run --no-such-option"), 2, "no-such-option");
  expect_error(crumple("run --grid 8 --mesh x.obj"), 2, "excludes");
  expect_error(crumple("run --backend nope"), 2, "--backend");
}

TEST(Cli, BadFilesExitTwoAndWriteNothing) {
  const fs::path d = fresh_dir("badfile");
  const fs::path nan_obj = write_file("crumple_nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  const fs::path range = write_file("crumple_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  const fs::path none = write_file("crumple_none.obj", "v 0 0 0\nv 1 0 0\n");
  for (const auto& [file, what] : {std::pair{nan_obj, "crumple_nan.obj:3"}, std::pair{range, "crumple_range.obj:4"},
                                   std::pair{none, "crumple_none.obj"},
                                   std::pair{fs::path("/no/such/file.obj"), "file.obj"}}) {
    expect_error(crumple("run --mesh " + file.string() + " --out " + d.string()), 2, what);
    EXPECT_FALSE(fs::exists(d)) << file;
  }
  expect_error(crumple(std::string("run --mesh ") + CRUMPLE_TEST_DATA + "/beetle.obj --out " + d.string()), 2,
               "beetle.obj");
  EXPECT_FALSE(fs::exists(d));
}

TEST(Cli, UnstableRunExitsThreeNamingTheFrame) {
  const fs::path d = fresh_dir("unstable");
  const Result r = crumple("run --grid 10 --scene free --integrator explicit --kappa 1e6 --frames 200 --out " + d.string());
  expect_error(r, 3, "unstable at frame");
  EXPECT_FALSE(fs::exists(d / "final.obj"));
}

}  // namespace
