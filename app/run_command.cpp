#include "run_command.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <oneapi/tbb/global_control.h>

#include "mesh/input_mesh.h"
#include "sim/backends.h"
#include "sim/run.h"

namespace crumple::app {

namespace fs = std::filesystem;

namespace {

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "crumple: error: %s\n", message.c_str());
  return code;
}

// A one-line progress bar on stderr, only on a terminal and only once a run passes a second.
class Progress {
 public:
  Progress(int total, bool enabled) : total_(total), enabled_(enabled && isatty(STDERR_FILENO)) {}
  void update(int frame, double ms) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    shown_ = true;
    const int width = 30, filled = int(double(width) * frame / total_);
    std::fprintf(stderr, "\rcrumple: [%s%s] frame %d/%d  %.2f ms/frame ", std::string(filled, '#').c_str(),
                 std::string(width - filled, '.').c_str(), frame, total_, ms);
    std::fflush(stderr);
  }
  ~Progress() {
    if (shown_) std::fprintf(stderr, "\n");
  }

 private:
  int total_;
  bool enabled_, shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

}  // namespace

int run(const RunOptions& o) {
  // Validate everything before anything is written.
  if (std::string m = o.params.validate(); !m.empty()) return fail(kBadInput, m);
  if (o.frames < 1 || o.frames > 10000000) return fail(kBadInput, "--frames must be in [1, 10000000]");
  if (o.threads < 1 || o.threads > 256) return fail(kBadInput, "--threads must be in [1, 256]");
  if (o.every < 0) return fail(kBadInput, "--every must be >= 0");
  if (o.mesh.empty() && (o.grid < 2 || o.grid > 8192)) return fail(kBadInput, "--grid must be in [2, 8192]");

  InputMesh mesh;
  try {
    mesh = o.mesh.empty() ? make_grid(o.grid, !o.fixed_diagonals) : load_obj(o.mesh);
  } catch (const InputError& e) {
    return fail(kBadInput, e.what());
  }
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
  std::unique_ptr<Simulator> sim;
  try {
    sim = make_simulator(o.backend, mesh, o.params, o.threads);
  } catch (const std::exception& e) {
    return fail(kBadInput, e.what());
  }
  const double size = make_scene(mesh, o.params).size;

  std::ofstream stats;
  const fs::path dir(o.out), stats_tmp = dir / "stats.csv.partial";
  if (!o.out.empty()) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return fail(kBadInput, "cannot create --out folder " + o.out + ": " + ec.message());
    stats.open(stats_tmp);
    if (!stats) return fail(kBadInput, "cannot write " + stats_tmp.string());
    stats << stats_header() << '\n';
  }

  Progress progress(o.frames, !o.quiet);
  long splits = 0, restores = 0;
  double total_ms = 0;
  int code = kOk;
  std::string why;
  int frame = 1;
  try {
    for (; frame <= o.frames; ++frame) {
      const FrameStats s = run_frame(*sim, o.params, frame);
      splits += s.splits;
      restores += s.restores;
      total_ms += s.step_ms;
      if (stats.is_open()) stats << stats_row(s) << '\n';
      if (why = instability(s.totals, size); !why.empty()) {
        code = kUnstable;
        break;
      }
      if (o.every > 0 && frame % o.every == 0 && !o.out.empty()) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.obj", frame);
        write_snapshot_obj((dir / name).string(), sim->snapshot());
      }
      progress.update(frame, total_ms / frame);
    }
    if (stats.is_open()) {
      stats.close();
      fs::rename(stats_tmp, dir / "stats.csv");
    }
    if (code == kOk && !o.out.empty()) write_snapshot_obj((dir / "final.obj").string(), sim->snapshot());
  } catch (const std::exception& e) {
    return fail(kBadInput, e.what());
  }
  if (code == kUnstable)
    return fail(kUnstable, "simulation became unstable at frame " + std::to_string(frame) + ": " + why);

  if (!o.quiet) {
    const Totals t = sim->totals();
    std::printf("crumple: %d frames, %s backend: %d vertices, %d triangles, %ld splits, %ld restores, %.3f ms/frame\n",
                o.frames, sim->name(), t.vertices, t.triangles, splits, restores, total_ms / o.frames);
  }
  return kOk;
}

}  // namespace crumple::app
