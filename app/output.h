// The --out folder of `crumple run`: checked and cleared before simulating, files that appear
// only complete (written under a temporary name, checked, then renamed into place), and the
// rows of stats.csv.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "crumple/crumple.h"

namespace crumple::app {

/// The stats.csv header (exactly as documented in README.md).
const char* stats_header();
/// One stats.csv line (no newline) for frame `frame`, which took `ev` and left `sheet` as it is:
/// step_ms is the wall time of the frame's time steps (FrameEvents::steps_ms).
std::string stats_row(int frame, const Sheet& sheet, const FrameEvents& ev);

/// True for the names `crumple run` writes in --out (stats.csv, final.obj, frame_NNNNN.obj)
/// and their temporaries (the same with ".partial").
bool owned_name(const std::string& name);

/// Makes `dir` ready before anything is simulated: path lengths within the system's limits, the
/// folder created if missing, and writable. An existing folder that is not empty is refused
/// unless `force`; with `force` the files crumple owns in it are removed (symbolic links
/// themselves, never what they point to) and everything else is left. Returns an error message,
/// or empty when ready. Lengths and a non-empty folder are checked before anything is created or
/// removed.
std::string prepare_out(const std::filesystem::path& dir, bool force);

/// A file that appears under its name only complete: written to "<name>.partial" (created
/// afresh, never through a symbolic link planted there), renamed into place by commit() once
/// every write, the flush and the close succeeded. A write error throws std::runtime_error
/// naming the file and the reason; the temporary is removed unless the file was committed.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::FILE* get() const { return file_; }
  /// Hands what was written so far to the system (a killed run leaves whole rows in the
  /// temporary); throws on a write error.
  void flush();
  /// Closes and renames into place; throws if anything written was lost.
  void commit();

 private:
  [[noreturn]] void fail(int error);
  std::filesystem::path path_, temp_;
  std::FILE* file_ = nullptr;
};

}  // namespace crumple::app
