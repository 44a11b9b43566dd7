// `crumple run`: options, validation and the frame loop with its outputs.
#pragma once

#include <string>

#include "model/params.h"

namespace crumple::app {

/// Everything `crumple run` was asked to do.
struct RunOptions {
  int grid = 32;                  ///< N x N sheet when no mesh is given
  bool fixed_diagonals = false;   ///< grid diagonals all one way instead of alternating
  std::string mesh;               ///< OBJ file (overrides grid)
  int frames = 180;               ///< frames of params.frame_dt
  std::string backend = "fast";
  int threads = 1;                ///< worker threads for parallel backends
  bool resident = false;          ///< SheetDesc::resident
  std::string out;                ///< output folder (empty: none)
  bool force = false;             ///< --out may be a non-empty folder: replace crumple's files in it
  int every = 0;                  ///< also write every K-th frame as an OBJ (0: never)
  bool quiet = false;             ///< no progress bar, no summary
  Params params = default_params();
};

/// Exit codes of the command; an interrupted run exits 128 + the signal (130 SIGINT, 143 SIGTERM).
enum Exit { kOk = 0, kBadInput = 2, kUnstable = 3 };

/// Prints `message` as one line "crumple: error: ..." on stderr (control bytes escaped as \xNN,
/// so that a file's bytes cannot drive the terminal) and returns `code`.
int fail(int code, const std::string& message);

/// Runs the simulation; prints errors as one `crumple: error:` line. Returns the exit code.
int run(const RunOptions& options);

}  // namespace crumple::app
