// Running the `crumple` command from tests: exit status, stderr and stdout of one invocation.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace cli_test {

namespace fs = std::filesystem;

struct Result {
  int code = -1;       ///< exit status (-1: killed by a signal)
  std::string err;     ///< stderr
  std::string out;     ///< stdout
};

inline std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `before` (shell commands such as "ulimit -v 100000;") then crumple with `args` in /bin/sh.
inline Result crumple(const std::string& args, const std::string& before = "") {
  static int calls = 0;  // ctest runs these tests in parallel processes: unique files each
  const fs::path dir = fs::temp_directory_path() /
                       ("crumple_cli_io_" + std::to_string(::getpid()) + "_" + std::to_string(++calls));
  fs::create_directories(dir);
  const std::string err = (dir / "stderr.txt").string(), out = (dir / "stdout.txt").string();
  const std::string cmd = before + " " + std::string(CRUMPLE_EXE) + " " + args + " >" + out + " 2>" + err + " </dev/null";
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_all(err);
  r.out = read_all(out);
  fs::remove_all(dir);
  return r;
}

/// A path in the temporary folder, removed (with anything under it) if it exists.
inline fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("crumple_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

inline fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

/// An error is exactly one line on stderr that begins "crumple: error:" and names `what`.
inline void expect_error(const Result& r, int code, const std::string& what) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_EQ(r.err.rfind("crumple: error:", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
}

}  // namespace cli_test
