// The embedding API (crumple/crumple.h) over the backend interface (sim/simulator.h): the
// fixed-step clock (with --substeps auto's choice, sim/run.h), the checks, the render buffers,
// the totals and the topology generation.
#include <chrono>
#include <cmath>

#include "api/api_checks.h"
#include "api/sheet_access.h"
#include "crumple/crumple.h"
#include "sim/backends.h"
#include "sim/run.h"

#ifndef CRUMPLE_VERSION_STRING
#error "CRUMPLE_VERSION_STRING comes from CMake's project version"
#endif

namespace crumple {

const char* version() { return CRUMPLE_VERSION_STRING; }

Params embedding_params() {
  Params p = default_params();
  p.scene = Scene::Free;
  p.squeeze = 1.0;
  return p;
}

struct Sheet::Impl {
  std::unique_ptr<Simulator> sim;
  Params params;
  Manipulators manip;
  RenderBuffers buffers;
  SheetStats stats;            ///< of the current state (computed with the instability check)
  std::function<void(const StepEventIds&)> callback;
  double h = 0;                ///< the time step (auto_substeps: fixed within a block)
  double carry = 0;            ///< simulated time owed to the next step() (< h)
  double size = 0;             ///< sheet size, for the instability test (sim/run.h)
  int block_left = 0;          ///< auto_substeps: steps left before the count is chosen again
  int frames = 0;              ///< step() calls
  std::uint64_t generation = 0;
  /// Whether step() may run: not once the state became unstable, nor after a step() that
  /// failed part way (the backend's state is then not whole: D34).
  enum class Health { Fine, Unstable, HalfStepped } health = Health::Fine;
  std::string broken;          ///< why it is not Fine (best effort: building it may fail)

  void begin_block();
  void take_step(FrameEvents& out);
  void advance(double frame_dt, FrameEvents& out);  ///< the steps of a frame and its render buffers
  void fail_part_way(int frame, const char* what) noexcept;  ///< what (nullptr: not a std::exception)
  std::string check_state();
  std::string refusal() const { return broken.empty() ? "a step failed part way" : broken; }
  void step(double frame_dt, FrameEvents& out);
};

namespace {
/// try_step's line when no memory is left to copy the step's own: short enough for an empty
/// std::string's own buffer (the small-string room), so assigning it allocates nothing.
constexpr char kNoMemoryLine[] = "out of memory";
static_assert(sizeof(kNoMemoryLine) - 1 <= std::string().capacity());

SheetStats to_stats(const Totals& t) {
  SheetStats s;
  s.vertices = t.vertices;
  s.edges = t.edges;
  s.triangles = t.triangles;
  s.mass = t.mass;
  s.momentum = t.momentum;
  s.kinetic = t.kinetic;
  s.max_strain = t.max_strain;
  return s;
}
}  // namespace

Sheet::Sheet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Sheet::Sheet(Sheet&&) noexcept = default;
Sheet& Sheet::operator=(Sheet&&) noexcept = default;
Sheet::~Sheet() = default;

Sheet SheetAccess::adopt(std::unique_ptr<Simulator> sim, const Params& params, double size) {
  auto impl = std::make_unique<Sheet::Impl>();
  impl->sim = std::move(sim);
  impl->params = params;
  impl->size = size;
  impl->stats = to_stats(impl->sim->totals());
  impl->h = params.h();
  if (params.auto_substeps) impl->begin_block();
  impl->sim->render(impl->buffers, true);
  return Sheet(std::move(impl));
}

Sheet SheetAccess::create(const InputMesh& mesh, const SheetDesc& desc) {
  if (std::string m = api::check_desc(desc); !m.empty()) throw Error(m);
  const int max = desc.params.max_vertices;
  if (max > 0 && std::size_t(max) < mesh.positions.size())  // the command's check and words
    throw Error("--max-vertices " + std::to_string(max) + " is below the mesh's " +
                std::to_string(mesh.positions.size()) + " vertices");
  std::unique_ptr<Simulator> sim;
  try {
    sim = make_simulator(desc.backend, mesh, desc.params, desc.threads);
    if (desc.resident) sim->make_resident();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {  // what a backend refuses (the fast one's integrators)
    throw Error(e.what());
  }
  return adopt(std::move(sim), desc.params, make_scene(mesh, desc.params).size);
}

Sheet Sheet::create(const SheetDesc& desc) {
  if (std::string m = api::check_desc(desc); !m.empty()) throw Error(m);
  InputMesh mesh;
  try {
    mesh = api::input_mesh(desc);
  } catch (const InputError& e) {
    throw Error(e.what());
  }
  return SheetAccess::create(mesh, desc);
}

std::optional<Sheet> Sheet::try_create(const SheetDesc& desc, std::string& error) noexcept {
  try {
    return create(desc);
  } catch (const std::exception& e) {
    error = e.what();
  }
  return std::nullopt;
}

// --substeps auto (D18): the count for the next params.frame_dt of simulated time, chosen on
// the state the command's run_frame would choose it on (the start of its frame).
void Sheet::Impl::begin_block() {
  const int n = choose_substeps(params, sim->stiffness_bound());
  sim->set_substeps(n);
  h = params.frame_dt / n;
  block_left = n;
}

void Sheet::Impl::take_step(FrameEvents& out) {
  const auto t0 = std::chrono::steady_clock::now();
  StepEvents ev = sim->step();
  out.steps_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ++out.steps;
  out.splits += ev.splits;
  out.restores += ev.restores;
  if (callback && ev.splits + ev.restores > 0)
    callback(StepEventIds{sim->steps(), ev.split_edges, ev.restored_edges});
  if (params.auto_substeps && --block_left == 0) begin_block();
}

// Updates stats and returns why the state is unstable (empty: it is fine).
std::string Sheet::Impl::check_state() {
  const Totals t = sim->totals();
  stats = to_stats(t);
  return instability(t, size);
}

void Sheet::Impl::step(double frame_dt, FrameEvents& out) {
  if (health != Health::Fine) throw UnstableError(refusal(), out);
  if (!std::isfinite(frame_dt) || frame_dt < 0 || frame_dt > 1)
    throw Error("frame_dt must be a finite number in [0, 1] seconds");
  if (std::string m = api::check_manipulators(manip, int(buffers.positions.size() / 3)); !m.empty())
    throw Error(m);
  const auto t0 = std::chrono::steady_clock::now();
  // From here on a failure (std::bad_alloc, an exception from the event callback) comes after
  // state has changed: time steps and mesh events cannot be undone, and a pass stopped part way
  // leaves the backend's mesh half edited, so the sheet refuses every later step (D34). The
  // instability check is inside too: a frame whose check threw was never checked.
  const int frame = frames + 1;
  std::string why;
  try {
    advance(frame_dt, out);
    why = check_state();
  } catch (const std::exception& e) {
    fail_part_way(frame, e.what());
    throw;
  } catch (...) {  // the callback may throw anything
    fail_part_way(frame, nullptr);
    throw;
  }
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!why.empty()) {
    health = Health::Unstable;
    broken = "simulation became unstable at frame " + std::to_string(frames) + ": " + why;
    throw UnstableError(broken, out);
  }
}

// Steps while at least one whole h is owed. The tolerance of a millionth of h absorbs the
// rounding of frame_dt / substeps, so a frame_dt equal to params.frame_dt takes exactly
// `substeps` steps every call.
void Sheet::Impl::advance(double frame_dt, FrameEvents& out) {
  sim->set_manipulators(manip);
  carry += frame_dt;
  while (carry > h * (1 - 1e-6)) {
    take_step(out);
    carry = std::max(0.0, carry - h);
  }
  ++frames;
  out.topology_changed = out.splits + out.restores > 0;
  if (out.topology_changed) ++generation;
  sim->render(buffers, out.topology_changed);
}

// Marks the sheet before its message is built: building it allocates, which may fail as the step
// did, and must not replace the exception in flight (its caller rethrows that one).
void Sheet::Impl::fail_part_way(int frame, const char* what) noexcept {
  health = Health::HalfStepped;
  try {
    broken = "a step failed part way at frame " + std::to_string(frame) + (what ? std::string(": ") + what : "");
  } catch (const std::exception&) {  // no memory for the line: the refusal has its short form
  }
}

FrameEvents Sheet::step(double frame_dt) {
  FrameEvents out;
  impl_->step(frame_dt, out);
  return out;
}

std::string Sheet::try_step(double frame_dt, FrameEvents* events) noexcept {
  FrameEvents out;
  std::string error;
  try {
    try {
      impl_->step(frame_dt, out);
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {  // the event callback's own exception type, which step() recorded
      error = impl_->refusal();
    }
  } catch (...) {  // no memory for a copy of the line: a failed assignment left `error` empty,
    error = kNoMemoryLine;  // and this line fits in its own buffer (no allocation)
  }
  if (events) *events = out;
  return error;
}

const SheetStats& Sheet::stats() const { return impl_->stats; }
void Sheet::write_obj(std::FILE* file) const {
  if (impl_->health == Impl::Health::HalfStepped) throw Error(impl_->refusal());
  write_snapshot_obj(file, impl_->sim->snapshot());
}

Manipulators& Sheet::manipulators() { return impl_->manip; }
const Manipulators& Sheet::manipulators() const { return impl_->manip; }

int Sheet::nearest_vertex(const std::array<double, 3>& p) const {
  const std::vector<float>& x = impl_->buffers.positions;
  std::vector<char> live(x.size() / 3, 0);
  for (std::uint32_t v : impl_->buffers.triangles) live[v] = 1;
  int best = -1;
  double best_d2 = 0;
  for (std::size_t k = 0; k < live.size(); ++k) {
    if (!live[k]) continue;
    const double dx = x[3 * k] - p[0], dy = x[3 * k + 1] - p[1], dz = x[3 * k + 2] - p[2];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (best < 0 || d2 < best_d2) best = int(k), best_d2 = d2;
  }
  return best;
}

void Sheet::on_events(std::function<void(const StepEventIds&)> callback) { impl_->callback = std::move(callback); }

std::span<const float> Sheet::positions() const { return impl_->buffers.positions; }
std::span<const float> Sheet::normals() const { return impl_->buffers.normals; }
std::span<const std::uint32_t> Sheet::triangles() const { return impl_->buffers.triangles; }
int Sheet::vertex_ids() const { return int(impl_->buffers.positions.size() / 3); }
int Sheet::live_vertices() const { return impl_->stats.vertices; }
int Sheet::live_triangles() const { return int(impl_->buffers.triangles.size() / 3); }
std::uint64_t Sheet::topology_generation() const { return impl_->generation; }
double Sheet::time() const { return impl_->sim->time(); }
std::uint64_t Sheet::steps() const { return impl_->sim->steps(); }
const char* Sheet::backend() const { return impl_->sim->name(); }

}  // namespace crumple
