// crumple: a crumpling sheet of paper for a real-time frame loop. This is the library's one
// public API header; it includes two plain-data headers installed beside it (model/params.h:
// the model's parameters, sim/manipulators.h: what the caller moves). No Eigen, no oneTBB.
//
//   #include <crumple/crumple.h>
//
//   crumple::SheetDesc desc;                       // a 64 x 64 grid, fast backend, caller's arena
//   crumple::Sheet sheet = crumple::Sheet::create(desc);  // throws crumple::Error
//   sheet.manipulators().spheres.push_back({{0.5, 0.5, -0.2}, 0.15});
//   for (;;) {
//     sheet.manipulators().spheres[0].center[2] += 0.002;  // move the hand
//     const crumple::FrameEvents ev = sheet.step(1.0 / 60);
//     upload(sheet.positions(), sheet.normals());          // zero-copy views
//     if (ev.topology_changed) upload_indices(sheet.triangles());
//   }
//
// Threads: with SheetDesc::threads = 0 (the default) the library makes no task_arena and no
// thread of its own: its parallel loops run in the oneTBB arena step() is called from (wrap the
// call in your arena's execute() to choose the workers). threads >= 1 gives the sheet its own
// arena of that many (1: plain loops). Results are bit-identical for any thread count.
//
// Errors are crumple::Error exceptions (or, from the try_ functions, values) whose what() is one
// line, the same text the `crumple` command prints after "crumple: error: ". A function that
// fails changes nothing: there is no half-built sheet. Running out of memory is std::bad_alloc.
// step() is the one exception: what fails once it has begun stepping (std::bad_alloc, or an
// exception the event callback throws) is passed on, and since the time steps and mesh events
// it applied cannot be undone, the sheet then refuses every later step() with UnstableError.
//
// The `crumple` command and the benchmarks' frame times run through this header too.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "model/params.h"
#include "sim/manipulators.h"

namespace crumple {

/// The library's version, "MAJOR.MINOR.PATCH" (CMake's project version; CHANGELOG.md).
const char* version();

/// Anything that cannot be simulated: what() is one line naming the problem.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Params for a sheet in a game rather than in the paper's scenes: the free scene (no scene
/// manipulation sphere) starting unsqueezed, every other value the command's default.
Params embedding_params();

/// What a sheet starts from.
struct SheetDesc {
  int grid = 64;                   ///< an n x n vertex grid on the unit square (z = 0) ...
  bool alternate_diagonals = true; ///< ... with alternating quad diagonals (no preferred fold)
  /// ... unless the caller passes a mesh: x, y, z per vertex and three vertex ids per
  /// triangle, copied and checked like an OBJ file (indices in range, manifold, oriented,
  /// no degenerate triangle, no unused vertex). Vertex k keeps id k.
  std::span<const float> positions;
  std::span<const std::uint32_t> triangles;
  /// The model's parameters, checked as the command checks its options; params.max_vertices
  /// (when set) must be at least the mesh's vertex count.
  Params params = embedding_params();
  std::string backend = "fast";    ///< "fast" (float, SoA, oneTBB) or "reference" (double)
  int threads = 0;                 ///< 0: the caller's oneTBB arena; n: an own arena of n
  /// Fault in at creation all the memory the sheet reserves for its growth (the fast backend:
  /// room for 4x the input's elements), so that step() takes no page fault until the sheet
  /// outgrows it: a longer load and the whole reserve resident from the start, for shorter
  /// longest frames where a first touch is slow, as on VMs that hand free memory back to their
  /// host (docs/DECISIONS.md D16 has what it saved).
  bool resident = false;
};

/// What one step() call did.
struct FrameEvents {
  int steps = 0;                ///< fixed time steps taken (see Sheet::step)
  int splits = 0;               ///< edges broken and split
  int restores = 0;             ///< creases restored
  bool topology_changed = false;///< splits + restores > 0: re-read triangles()
  double ms = 0;                ///< wall time of the call
  /// The part of ms spent inside the time steps themselves: the physics and the mesh events,
  /// without the render buffers, the totals and the callback (stats.csv's step_ms).
  double steps_ms = 0;
};

/// Thrown by step() when the state became unstable (a value not finite, a vertex gone or too
/// fast, the mesh stretched to twice its rest length on average: the command's exit 3). The
/// sheet keeps that state (stats() shows it) and refuses every further step with this error,
/// as it does after a step() that failed part way.
class UnstableError : public Error {
 public:
  UnstableError(const std::string& what, const FrameEvents& events) : Error(what), events_(events) {}
  /// What the failing call did before the check (zeros for a refused later call).
  const FrameEvents& events() const { return events_; }

 private:
  FrameEvents events_;
};

/// Totals over the sheet's state after the last step() (or creation): what the command writes
/// to stats.csv. step() computes them for its instability check, so reading them is free.
struct SheetStats {
  int vertices = 0;                  ///< live vertices
  int edges = 0;                     ///< live mesh edges (a crease's auxiliary spring is not one)
  int triangles = 0;                 ///< live triangles
  double mass = 0;                   ///< sum of the vertex masses
  std::array<double, 3> momentum{};  ///< sum of m v
  double kinetic = 0;                ///< sum of m |v|^2 / 2
  double max_strain = 0;             ///< max over mesh edges of |l / l0 - 1|
};

/// The events of one fixed time step, for the event callback. The spans are valid during the
/// call only.
struct StepEventIds {
  std::uint64_t step = 0;                 ///< 1-based step number
  std::span<const int> split_edges;       ///< ids of the edges split in that step, ascending
  std::span<const int> restored_edges;    ///< ids of the creases restored in it, ascending
};

class Sheet {
 public:
  /// Builds a sheet; throws Error (bad parameter, bad mesh, unknown backend, bad thread count,
  /// params.max_vertices below the mesh's vertex count).
  static Sheet create(const SheetDesc& desc);
  /// The same, the error as a value: an empty optional and `error` set to the line.
  static std::optional<Sheet> try_create(const SheetDesc& desc, std::string& error) noexcept;

  Sheet(Sheet&&) noexcept;
  Sheet& operator=(Sheet&&) noexcept;
  ~Sheet();

  /// Advances simulated time by frame_dt in fixed steps h = params.frame_dt / params.substeps
  /// (the remainder is carried to the next call, so a varying frame_dt never changes h and the
  /// run stays deterministic). With params.auto_substeps the count is chosen as the command's
  /// `--substeps auto` chooses it: from the current mesh's stiffest mode (and params.max_step),
  /// at creation and again after every params.frame_dt of simulated time (every call when
  /// frame_dt equals params.frame_dt). Reads manipulators() first. Throws Error for a frame_dt
  /// that is negative, not finite or over 1 s, or an invalid manipulator (nothing is done), and
  /// UnstableError for a state that became unstable or a sheet whose earlier step() failed
  /// part way (std::bad_alloc or the callback's exception, passed on at the time).
  FrameEvents step(double frame_dt);
  /// step() with the error as a value (empty when it succeeded; a callback's exception not
  /// derived from std::exception gives step()'s "a step failed part way" line; "out of memory"
  /// when no memory is left to copy the line itself). `events`
  /// receives what the call did, also when it failed (UnstableError::events; zeros when refused
  /// before stepping).
  std::string try_step(double frame_dt, FrameEvents* events = nullptr) noexcept;

  /// Totals over the current state (see SheetStats).
  const SheetStats& stats() const;
  /// Writes the current state as an OBJ, byte for byte the command's final.obj: a comment
  /// line, the live vertices renumbered densely in id order (`v x y z`, %.9g), the live
  /// triangles (`f a b c`, 1-based) and each crease's auxiliary spring as `l a b`. Write errors
  /// are left in std::ferror(file) for the caller, who checks it before closing. Throws Error
  /// after a step() that failed part way (its state is half stepped: D34).
  void write_obj(std::FILE* file) const;

  /// The caller's spheres, planes, pins and grabs (sim/manipulators.h): edit them freely
  /// between steps; each step() checks them and applies them to every one of its time steps.
  Manipulators& manipulators();
  const Manipulators& manipulators() const;
  /// The live vertex nearest to p (for pins and grabs); -1 for no live vertex.
  int nearest_vertex(const std::array<double, 3>& p) const;

  /// Called after every time step that split or restored something (empty: none).
  void on_events(std::function<void(const StepEventIds&)> callback);

  // --- rendering: views into the sheet's own buffers, valid until the next step() ---
  /// x, y, z per vertex id (vertex_ids() of them); a dead id holds zeros and is in no triangle.
  std::span<const float> positions() const;
  /// Unit area-weighted vertex normal per vertex id (MODEL.md §1), same layout.
  std::span<const float> normals() const;
  /// Three vertex ids per live triangle, counter-clockwise about the normal. Repacked only
  /// when the topology changes: same topology_generation(), same contents.
  std::span<const std::uint32_t> triangles() const;
  int vertex_ids() const;      ///< positions().size() / 3: live and dead ids
  int live_vertices() const;   ///< vertices in use (all referenced by triangles())
  int live_triangles() const;  ///< triangles().size() / 3
  /// Changes exactly when a step() split or restored something (starts at 0).
  std::uint64_t topology_generation() const;

  double time() const;          ///< simulated seconds in whole time steps
  std::uint64_t steps() const;  ///< time steps taken
  const char* backend() const;  ///< "fast" or "reference"

 private:
  struct Impl;
  friend struct SheetAccess;  // the library's own tools (api/sheet_access.h); not API
  explicit Sheet(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace crumple
