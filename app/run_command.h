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
  std::string backend = "reference";
  int threads = 1;                ///< worker threads for parallel backends
  std::string out;                ///< output folder (empty: none)
  int every = 0;                  ///< also write every K-th frame as an OBJ (0: never)
  bool quiet = false;             ///< no progress bar, no summary
  Params params;
};

/// Exit codes of the command.
enum Exit { kOk = 0, kBadInput = 2, kUnstable = 3 };

/// Runs the simulation; prints errors as one `crumple: error:` line. Returns the exit code.
int run(const RunOptions& options);

}  // namespace crumple::app
