// The embedding API (crumple/crumple.h) over the backend interface (sim/simulator.h): the
// fixed-step clock, the checks, the render buffers and the topology generation.
#include <chrono>
#include <cmath>

#include "api/api_checks.h"
#include "crumple/crumple.h"
#include "sim/backends.h"
#include "sim/run.h"

#ifndef CRUMPLE_VERSION_STRING
#error "CRUMPLE_VERSION_STRING comes from CMake's project version"
#endif

namespace crumple {

const char* version() { return CRUMPLE_VERSION_STRING; }

Params embedding_params() {
  Params p;
  p.scene = Scene::Free;
  p.squeeze = 1.0;
  return p;
}

struct Sheet::Impl {
  std::unique_ptr<Simulator> sim;
  Manipulators manip;
  RenderBuffers buffers;
  std::function<void(const StepEventIds&)> callback;
  double h = 0;                ///< the fixed time step
  double carry = 0;            ///< simulated time owed to the next step() (< h)
  double size = 0;             ///< sheet size, for the instability test (sim/run.h)
  int live_vertices = 0;       ///< input vertices + splits - restores (one vertex each)
  int frames = 0;              ///< step() calls
  std::uint64_t generation = 0;
  std::string broken;          ///< why the state is unusable (empty: it is fine)

  void take_step(FrameEvents& out);
};

Sheet::Sheet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Sheet::Sheet(Sheet&&) noexcept = default;
Sheet& Sheet::operator=(Sheet&&) noexcept = default;
Sheet::~Sheet() = default;

Sheet Sheet::create(const SheetDesc& desc) {
  if (std::string m = api::check_desc(desc); !m.empty()) throw Error(m);
  auto impl = std::make_unique<Impl>();
  try {
    const InputMesh mesh = api::input_mesh(desc);
    impl->sim = make_simulator(desc.backend, mesh, desc.params, desc.threads);
    impl->size = make_scene(mesh, desc.params).size;
    impl->live_vertices = int(mesh.positions.size());
  } catch (const std::exception& e) {  // InputError, the fast backend's missing integrator
    throw Error(e.what());
  }
  impl->h = desc.params.h();
  impl->sim->render(impl->buffers, true);
  return Sheet(std::move(impl));
}

std::optional<Sheet> Sheet::try_create(const SheetDesc& desc, std::string& error) noexcept {
  try {
    return create(desc);
  } catch (const std::exception& e) {
    error = e.what();
  }
  return std::nullopt;
}

void Sheet::Impl::take_step(FrameEvents& out) {
  StepEvents ev = sim->step();
  ++out.steps;
  out.splits += ev.splits;
  out.restores += ev.restores;
  live_vertices += ev.splits - ev.restores;
  if (callback && ev.splits + ev.restores > 0)
    callback(StepEventIds{sim->steps(), ev.split_edges, ev.restored_edges});
}

// Steps while at least one whole h is owed. The tolerance of a millionth of h absorbs the
// rounding of frame_dt / substeps, so a frame_dt equal to params.frame_dt takes exactly
// `substeps` steps every call.
FrameEvents Sheet::step(double frame_dt) {
  Impl& s = *impl_;
  if (!s.broken.empty()) throw Error(s.broken);
  if (!std::isfinite(frame_dt) || frame_dt < 0 || frame_dt > 1)
    throw Error("frame_dt must be a finite number in [0, 1] seconds");
  if (std::string m = api::check_manipulators(s.manip, vertex_ids()); !m.empty()) throw Error(m);
  const auto t0 = std::chrono::steady_clock::now();
  s.sim->set_manipulators(s.manip);
  FrameEvents out;
  s.carry += frame_dt;
  while (s.carry > s.h * (1 - 1e-6)) {
    s.take_step(out);
    s.carry = std::max(0.0, s.carry - s.h);
  }
  ++s.frames;
  out.topology_changed = out.splits + out.restores > 0;
  if (out.topology_changed) ++s.generation;
  s.sim->render(s.buffers, out.topology_changed);
  if (std::string why = instability(s.sim->totals(), s.size); !why.empty()) {
    s.broken = "simulation became unstable at frame " + std::to_string(s.frames) + ": " + why;
    throw Error(s.broken);
  }
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::string Sheet::try_step(double frame_dt, FrameEvents* events) noexcept {
  try {
    const FrameEvents ev = step(frame_dt);
    if (events) *events = ev;
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
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
int Sheet::live_vertices() const { return impl_->live_vertices; }
int Sheet::live_triangles() const { return int(impl_->buffers.triangles.size() / 3); }
std::uint64_t Sheet::topology_generation() const { return impl_->generation; }
double Sheet::time() const { return impl_->sim->time(); }
std::uint64_t Sheet::steps() const { return impl_->sim->steps(); }
const char* Sheet::backend() const { return impl_->sim->name(); }

}  // namespace crumple
