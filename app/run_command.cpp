#include "run_command.h"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>
#include <optional>
#include <oneapi/tbb/global_control.h>

#include "api/sheet_access.h"
#include "crumple/crumple.h"
#include "interrupt.h"
#include "memory.h"
#include "mesh/input_mesh.h"
#include "output.h"

namespace crumple::app {

namespace fs = std::filesystem;

namespace {

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

// Empty if the command's own options are valid (Params::validate checks the model's).
std::string check_options(const RunOptions& o) {
  if (std::string m = o.params.validate(); !m.empty()) return m;
  if (o.frames < 1 || o.frames > 10000000) return "--frames must be in [1, 10000000]";
  if (o.threads < 1 || o.threads > 256) return "--threads must be in [1, 256]";
  if (o.every < 0) return "--every must be >= 0";
  if (o.mesh.empty() && (o.grid < 2 || o.grid > 8192)) return "--grid must be in [2, 8192]";
  return {};
}

// Empty if the run fits in the memory this process may take; otherwise why not.
std::string check_memory(const RunOptions& o, std::size_t vertices) {
  // Without fracture the fast backend reserves no room to grow: resident, it holds what it uses.
  const bool resident = o.resident && o.backend == "fast" && o.params.fracture;
  const std::uint64_t need = estimate_run_bytes(o.backend, vertices, resident), have = available_bytes();
  if (need <= have) return {};
  char text[200];
  std::snprintf(text, sizeof text,
                "the run needs about %.2f GB of memory (%zu vertices, %s backend, room to refine%s) but "
                "%.2f GB are available",
                need * 1e-9, vertices, o.backend.c_str(), resident ? ", resident" : "", have * 1e-9);
  return text;
}

// What the frame loop ended with.
struct Outcome {
  int frames_done = 0;
  int code = kOk;        // kOk, kUnstable, or 128 + the signal
  std::string why;       // the instability, the API's line (the command's words)
  long splits = 0, restores = 0;
  double total_ms = 0;
};

// Writes the sheet's current state to dir/name, complete or not at all.
void write_frame(const fs::path& dir, const std::string& name, const Sheet& sheet) {
  AtomicFile file(dir / name);
  sheet.write_obj(file.get());
  file.commit();
}

// The frame loop: stats rows as frames finish (the unstable frame's too), a frame OBJ every
// `every` frames; stops at an instability or an interrupt after the frame in progress.
Outcome simulate(Sheet& sheet, const RunOptions& o, AtomicFile* stats) {
  Progress progress(o.frames, !o.quiet);
  Outcome r;
  for (int frame = 1; frame <= o.frames; ++frame) {
    FrameEvents ev;
    try {
      ev = sheet.step(o.params.frame_dt);
    } catch (const UnstableError& e) {
      ev = e.events();
      r.why = e.what();
      r.code = kUnstable;
    }
    r.frames_done = frame;
    r.splits += ev.splits;
    r.restores += ev.restores;
    r.total_ms += ev.steps_ms;  // the summary's ms/frame: the steps, as stats.csv's step_ms
    if (stats) {
      std::fprintf(stats->get(), "%s\n", stats_row(frame, sheet, ev).c_str());
      stats->flush();
    }
    if (r.code == kUnstable) return r;
    if (o.every > 0 && frame % o.every == 0 && stats) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05d.obj", frame);
      write_frame(o.out, name, sheet);
    }
    if (const int signal = interrupt_signal()) {
      r.code = 128 + signal;
      return r;
    }
    progress.update(frame, r.total_ms / frame);
  }
  return r;
}

/// The process's peak resident memory so far, in MiB (getrusage's ru_maxrss, KiB on Linux).
double peak_resident_mib() {
  rusage u{};
  return getrusage(RUSAGE_SELF, &u) == 0 ? double(u.ru_maxrss) / 1024.0 : 0.0;
}

void report(const Outcome& r, const RunOptions& o, const Sheet& sheet) {
  if (r.code > 128) {
    std::fprintf(stderr, "crumple: interrupted by %s after frame %d of %d%s\n",
                 r.code == 128 + SIGINT ? "SIGINT" : "SIGTERM", r.frames_done, o.frames,
                 o.out.empty() ? "" : "; stats.csv and final.obj hold the frames done");
  } else if (r.code == kOk && !o.quiet) {
    std::printf("crumple: %d frames, %s backend: %d vertices, %d triangles, %ld splits, %ld restores, %.3f ms/frame, "
                "peak memory %.0f MiB\n",
                o.frames, sheet.backend(), sheet.stats().vertices, sheet.stats().triangles, r.splits, r.restores,
                r.total_ms / o.frames, peak_resident_mib());
  }
}

// The sheet of a checked run: the mesh read here (an OBJ in double precision) goes to the API,
// which checks the rest (the vertex budget against the mesh) as it does for any engine.
std::optional<Sheet> make_sheet(const RunOptions& o, const InputMesh& mesh, std::string& error) {
  SheetDesc desc;
  desc.grid = o.grid;
  desc.alternate_diagonals = !o.fixed_diagonals;
  desc.params = o.params;
  desc.backend = o.backend;
  desc.threads = o.threads;
  desc.resident = o.resident;
  try {
    return SheetAccess::create(mesh, desc);
  } catch (const Error& e) {
    error = e.what();
  }
  return std::nullopt;
}

// Runs the frame loop with its outputs; returns the exit code.
int simulate_and_write(Sheet& sheet, const RunOptions& o) {
  catch_interrupts();
  Outcome r;
  try {
    std::optional<AtomicFile> stats;
    if (!o.out.empty()) {
      stats.emplace(fs::path(o.out) / "stats.csv");
      std::fprintf(stats->get(), "%s\n", stats_header());
    }
    r = simulate(sheet, o, stats ? &*stats : nullptr);
    if (stats) stats->commit();
    if (r.code != kUnstable && !o.out.empty()) write_frame(o.out, "final.obj", sheet);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {  // a write failed
    return fail(kBadInput, e.what());
  }
  if (r.code == kUnstable) return fail(kUnstable, r.why);
  report(r, o, sheet);
  return r.code;
}

int run_checked(const RunOptions& o) {
  // Everything is checked before anything is written.
  if (std::string m = check_options(o); !m.empty()) return fail(kBadInput, m);
  const std::size_t grid_vertices = o.mesh.empty() ? std::size_t(o.grid) * std::size_t(o.grid) : 0;
  if (std::string m = check_memory(o, grid_vertices); !m.empty()) return fail(kBadInput, m);  // before allocating it
  InputMesh mesh;
  try {
    mesh = o.mesh.empty() ? make_grid(o.grid, !o.fixed_diagonals) : load_obj(o.mesh);
  } catch (const InputError& e) {
    return fail(kBadInput, e.what());
  }
  if (std::string m = check_memory(o, mesh.positions.size()); !m.empty()) return fail(kBadInput, m);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
  std::string error;
  std::optional<Sheet> sheet = make_sheet(o, mesh, error);
  if (!sheet) return fail(kBadInput, error);
  mesh = InputMesh();  // the sheet has its own copy
  if (!o.out.empty()) {
    if (std::string m = prepare_out(o.out, o.force); !m.empty()) return fail(kBadInput, m);
  }
  return simulate_and_write(*sheet, o);
}

}  // namespace

int fail(int code, const std::string& message) {
  std::string line;
  for (unsigned char c : message) {
    if (c >= 0x20 && c != 0x7f) {
      line += static_cast<char>(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      line += hex;
    }
  }
  std::fprintf(stderr, "crumple: error: %s\n", line.c_str());
  return code;
}

int run(const RunOptions& o) {
  try {
    return run_checked(o);
  } catch (const std::bad_alloc&) {
    return fail(kBadInput, "out of memory: the run needs more memory than this process may take");
  }
}

}  // namespace crumple::app
