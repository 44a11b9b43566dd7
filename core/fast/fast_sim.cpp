#include "fast/fast_sim.h"

#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "fast/pass_timer.h"
#include "model/random.h"

namespace crumple::fast {

const char* to_string(Pass p) {
  static const char* names[] = {"normals", "edge_forces", "gather", "integrate", "adapt_test", "topology_apply", "layout"};
  return names[int(p)];
}

namespace {
// The power of two nearest 1/sheet size (1 for a sheet of no size): the kernels that multiply
// or square lengths scale them by it first. Exact (a power of two changes no significand), so
// results do not change; a mesh of size 1e-12 then computes its areas and lengths as one of
// size 1 would, where float's subnormals (below 1.2e-38, so areas of edges below ~1e-10) would
// lose them (D20, issue 14).
float unit_of_length(double size) { return size > 0 ? std::ldexp(1.0f, -std::ilogb(size)) : 1.0f; }
}  // namespace

FastSimulator::FastSimulator(const InputMesh& input, const Params& params, int threads)
    : params_(params), scene_(make_scene(input, params)), length_unit_(unit_of_length(scene_.size)), par_(threads) {
  if (params_.integrator == Integrator::Implicit)
    throw std::invalid_argument("the fast backend has no Baraff-Witkin integrator; use --backend reference");
  const int nv = int(input.positions.size());
  const std::size_t nt = input.triangles.size();
  // Refinement grows a mesh about 4x at the default floor: room for that up front.
  const std::size_t room = (params_.fracture ? 4 : 1);
  topo_.reserve(room * nv, room * 2 * nt, room * nt);
  step_.reserve(room * nv, room * 2 * nt);
  if (axial()) step_.wsum.reserve_warm(room * nv);  // fit_blocks sizes it: room, as the others'
  decisions_.reserve_warm(room * 2 * nt);
  stamps_.reserve(room * nt);
  rounds_.reserve(room * nv);
  waves_.reserve(room * nv);
  layout_scratch_.reserve(room * nv, room * 2 * nt, room * nt, par_.threads());
  for (int k = 0; k < nv; ++k) {
    const int v = topo_.new_vertex();
    topo_.V.rest[v] = Float4{float(scene_.rest[k][0]), float(scene_.rest[k][1]), float(scene_.rest[k][2]), 0.0f};
    topo_.V.xm[v] = Float4{float(scene_.position[k][0]), float(scene_.position[k][1]), float(scene_.position[k][2]), 0.0f};
    topo_.V.set_mass(v, float(scene_.mass[k]));
  }
  // Edges in order of first appearance over triangles and their sides (sim/simulator.h).
  std::map<std::pair<int, int>, int> seen;
  for (const auto& tri : input.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int p = tri[k], q = tri[(k + 1) % 3];
      const auto key = std::make_pair(std::min(p, q), std::max(p, q));
      if (seen.count(key)) continue;
      const double dx = scene_.rest[p][0] - scene_.rest[q][0], dy = scene_.rest[p][1] - scene_.rest[q][1],
                   dz = scene_.rest[p][2] - scene_.rest[q][2];
      seen[key] = topo_.new_edge(p, q, float(std::sqrt(dx * dx + dy * dy + dz * dz)));
    }
    const int t = topo_.new_triangle();
    if (!topo_.attach(t, tri[0], tri[1], tri[2]))
      throw InputError("mesh is not an oriented manifold at triangle " + std::to_string(t));
  }
  topo_.euler = topo_.live_vertices() - topo_.live_mesh_edges() + topo_.live_triangles();
  layout_scratch_.warm(topo_, par_, SIZE_MAX);  // the first relayout's memory, at load time
}

StepConstants FastSimulator::step_constants() const {
  StepConstants c;
  c.h = float(params_.h());
  c.h2 = c.h * c.h;
  // XPBD's springs are constraints (integrate_xpbd), not forces of the edge pass.
  const bool xpbd = params_.integrator == Integrator::Xpbd;
  c.kappa = xpbd ? 0.0f : float(params_.kappa);
  const double h = params_.h(), stiff = params_.integrator == Integrator::Approx ? h * h * params_.kappa : 0.0;
  c.implicit = float(stiff + h * params_.viscosity);
  if (axial()) {
    c.axial = float(h * h * params_.kappa);
    c.viscous = float(h * params_.viscosity);
  }
  c.bend = float(params_.bend);
  c.damping = xpbd ? 0.0f : float(params_.damping);
  c.gravity = float(params_.gravity);
  c.balanced = params_.bending == BendingForm::Balanced;
  c.bounded = params_.predictor == Predictor::Bounded;
  return c;
}

void FastSimulator::compute_normals() {
  const float unit = length_unit();
  Float4* area = topo_.T.area.data();
  par_.run(topo_.T.size(), kPassGrain, [&](int b, int e) { triangle_areas(topo_, unit, area, b, e); });
  Float4* normals = topo_.V.nr.data();
  par_.run(topo_.V.size(), kPassGrain, [&](int b, int e) { vertex_normals(topo_, normals, b, e); });
}

void FastSimulator::edge_pass(const StepConstants& c) {
  step_.fit(topo_);
  EdgeOut* out = step_.edge_out.data();
  par_.run(topo_.E.size(), kPassGrain, [&](int b, int e) { edge_forces(topo_.E, topo_.V, c, out, b, e); });
}

void FastSimulator::gather_pass(const StepConstants& c) {
  step_.fit(topo_);  // a no-op after edge_pass; run_pass may time this pass alone
  const EdgeOut* records = step_.edge_out.data();
  Float4* g = step_.g.data();
  par_.run(topo_.V.size(), kPassGrain,
           [&](int b, int e) { gather_forces(topo_, records, c, step_.forces, g, b, e); });
}

void FastSimulator::compute_forces() {
  const StepConstants c = step_constants();
  {
    PassTimer t(pass_seconds_, int(Pass::EdgeForces));
    edge_pass(c);
  }
  PassTimer t(pass_seconds_, int(Pass::Gather));
  gather_pass(c);
}

void FastSimulator::pin_guesses() {
  for (int k : scene_.pinned) step_.g[topo_.V.phys[k]] = Float4{0, 0, 0, topo_.V.mass(topo_.V.phys[k])};
}

void FastSimulator::integrate() {
  PassTimer timer(pass_seconds_, int(Pass::Integrate));
  if (params_.integrator == Integrator::Xpbd) return integrate_xpbd();
  const StepConstants c = step_constants();
  const int n = topo_.V.size();
  step_.fit(topo_);  // a no-op after the force passes; run_pass may time this pass alone
  float corr[3] = {0, 0, 0};
  if (params_.integrator == Integrator::Explicit && params_.viscosity == 0) {
    par_.run_lanes(n, kPassGrain,
                   [&](int b, int e) { explicit_velocity(topo_.V, step_.forces, c, step_.g.data(), b, e); });
    pin_guesses();
  } else {
    if (axial()) {  // the 3 x 3 rows, and the first guess from them
      step_.fit_blocks(topo_);
      par_.run(n, kPassGrain, [&](int b, int e) {
        axial_blocks(topo_, step_.forces, c, step_.wsum.data(), step_.g.data(), b, e);
      });
    }
    sweep_rows(c, corr);
  }
  advance_state(c, corr);
}

void FastSimulator::sweep_rows(const StepConstants& c, float corr[3]) {
  const int n = topo_.V.size();
  pin_guesses();  // pinned vertices (hang scene) are fixed neighbours in every sweep
  for (int sweep = 0; sweep < params_.sweeps; ++sweep) {
    const Float4* g = step_.g.data();
    Float4* g_next = step_.g_next.data();
    if (axial())
      par_.run(n, kPassGrain, [&](int b, int e) {
        axial_sweep(topo_, step_.forces, step_.wsum.data(), c, g, g_next, b, e);
      });
    else
      par_.run(n, kPassGrain, [&](int b, int e) { jacobi_sweep(topo_, step_.forces, c, g, g_next, b, e); });
    step_.g.swap(step_.g_next);
    pin_guesses();
  }
  // Remove the net momentum a finite sweep count adds (DECISIONS.md D2).
  double drift[4];  // momentum in 0..2, the total mass in 3
  const Float4* g = step_.g.data();
  par_.sum<4>(
      n, kReduceBlock, [&](int b, int e, double* out) { momentum_drift(topo_.V, step_.forces, g, c, b, e, out); },
      drift);
  for (int d = 0; d < 3; ++d) corr[d] = scene_.pinned.empty() ? float(drift[d] / drift[3]) : 0.0f;
}

void FastSimulator::advance_state(const StepConstants& c, const float corr[3]) {
  const int n = topo_.V.size();
  const float center[3] = {float(scene_.center[0]), float(scene_.center[1]), float(scene_.center[2])};
  const float radius = scene_.sphere ? float(scene_.sphere_radius(time_ + params_.h())) : 0.0f;
  const Float4* g = step_.g.data();
  par_.run_lanes(n, kPassGrain, [&](int b, int e) { advance(g, c, corr, center, radius, topo_.V, b, e); });
  for (int k : scene_.pinned) {  // input vertex k has logical id k
    const int v = topo_.V.phys[k];
    const float m = topo_.V.mass(v);
    topo_.V.xm[v] = Float4{float(scene_.position[k][0]), float(scene_.position[k][1]), float(scene_.position[k][2]), m};
    topo_.V.vm[v] = Float4{0, 0, 0, m};
  }
}

StepEvents FastSimulator::step() {
  if (!normals_valid_) {  // else the adapt pass of the last step left them current
    PassTimer t(pass_seconds_, int(Pass::Normals));
    compute_normals();
  }
  normals_valid_ = false;
  compute_forces();
  add_grab_forces();
  integrate();
  time_ += params_.h();
  apply_manipulators();
  StepEvents ev;
  if (adapt_clock_.tick(params_)) {
    ev = adapt();
    if (!manip_.empty()) {  // a split's new vertex may land inside an obstacle
      apply_manipulators();
      normals_valid_ = false;
    }
  }
  update_layout();
  ++steps_;
  return ev;
}

// A relayout's phases in consecutive steps (layout.h): a stale layout starts one, and the
// steps after finish it before another can start.
void FastSimulator::update_layout() {
  if (layout_phase_ == 0 && !layout_stale(topo_, layout_fraction_)) return warm_ahead();
  PassTimer t(pass_seconds_, int(Pass::Layout));
  relayout_phase(layout_phase_, topo_, par_, layout_scratch_);
  layout_phase_ = (layout_phase_ + 1) % kLayoutPhases;
  ++relayout_phases_;
  colors_.invalidate();
}

// A step between relayouts faults in memory that later steps will write, on all threads
// (touch_pages), so that no step takes those first touches in a burst on one thread:
// - the room the state's arrays grow into, as far as Array::keep_warm keeps it (warm_target: an
//   eighth of each array's capacity ahead of its elements), where keep_warm would fault in a
//   whole eighth at once when growth reached its end;
// - a part of what the next relayout will write, so that the faults of the state's growth since
//   the last one are spread over the steps in between (LayoutScratch::claim_cold).
// Each kind claims a kWarmParts-th of what is left of it, and at least a huge page: the growth
// room lags most after a relayout, whose phases' steps claim none of it, and the budget spreads
// that lag over the next steps. The budget goes to the arrays in a fixed order, so where a
// step's growth exceeds it the last arrays would lag for good: each array's warm_floor (half
// the eighth) is claimed first, whatever the budget.
void FastSimulator::warm_ahead() {
  std::size_t growth = 0;  // the growth room's cold bytes
  auto count = [&](const auto& a) { growth += a.cold_bytes(a.warm_target()); };
  topo_.for_each_array(count);
  step_.for_each_array(count);
  const std::size_t next = layout_fraction_ < 0 ? 0 : layout_scratch_.cold_bytes(topo_, par_.threads());
  if (growth == 0 && next == 0) return;
  std::vector<ColdRange> cold;
  ColdClaims needed(cold), budgeted(cold, std::max(kHugePage, growth / kWarmParts));
  auto soon = [&](auto& a) { needed.claim(a, a.warm_floor()); };
  auto ahead = [&](auto& a) { budgeted.claim(a, a.warm_target()); };
  topo_.for_each_array(soon);
  step_.for_each_array(soon);
  topo_.for_each_array(ahead);
  step_.for_each_array(ahead);
  PassTimer t(pass_seconds_, int(Pass::Layout));
  // The claim may reallocate a spare (timed with the layout pass, as its touch is).
  if (next > 0) layout_scratch_.claim_cold(topo_, par_.threads(), std::max(kHugePage, next / kWarmParts), cold);
  touch_pages(par_, cold);  // one loop over both kinds of cold room
}

// Every Array's whole room: the topology's and the step's (reserved for 4x the input in the
// constructor), the topology pass's and the relayout's scratch. Array::keep_warm then never
// touches memory (it finds the room touched), and a copy touches what its original has. Within
// a relayout too: the scratch keeps the edges' order that the next phase reads.
// Claimed first and touched in one loop on all threads: a first touch is the kernel's work on
// the touching core.
void FastSimulator::make_resident() {
  std::vector<ColdRange> cold;
  ColdClaims claims(cold);
  auto whole = [&](auto& a) { claims.whole(a); };
  topo_.for_each_array(whole);
  step_.for_each_array(whole);
  whole(decisions_);
  stamps_.claim_whole(claims);
  rounds_.claim_whole(claims);
  waves_.claim_whole(claims);
  layout_scratch_.claim_whole(topo_, par_.threads(), claims);
  touch_pages(par_, cold);
}

std::vector<std::string> FastSimulator::pass_names() const {
  std::vector<std::string> names;
  for (int k = 0; k < int(Pass::kCount); ++k) names.push_back(to_string(Pass(k)));
  return names;
}

void FastSimulator::run_pass(const std::string& name) {
  for (int k = 0; k < int(Pass::kCount); ++k)
    if (name == to_string(Pass(k))) return run_pass(Pass(k));
  throw std::invalid_argument("unknown pass '" + name + "'");
}

void FastSimulator::run_pass(Pass p) {
  const StepConstants c = step_constants();
  switch (p) {
    case Pass::Normals: compute_normals(); break;
    case Pass::EdgeForces: edge_pass(c); break;
    case Pass::Gather: gather_pass(c); break;
    case Pass::Integrate: integrate(); break;
    case Pass::AdaptTest: adapt_decide(); break;
    case Pass::TopologyApply: adapt(); break;
    case Pass::Layout:
      relayout(topo_, par_, layout_scratch_);
      layout_phase_ = 0;
      colors_.invalidate();
      break;
    case Pass::kCount: break;
  }
}

}  // namespace crumple::fast
