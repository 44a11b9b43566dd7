// The `crumple` command: parses options (CLI11) and dispatches to the run command.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>

#include "crumple/crumple.h"
#include "run_command.h"
#include "sim/backends.h"

using namespace crumple;

namespace {
template <class E>
CLI::Transformer choice(const std::map<std::string, E>& names) {
  return CLI::Transformer(names, CLI::ignore_case);
}

// An empty value would otherwise convert to 0 (numbers) or mean "not given" (--mesh, --out).
const CLI::Validator kNotEmpty(
    [](std::string& value) { return value.empty() ? std::string("the value is empty") : std::string(); }, "");

// Digits only, within 64 bits: strtoull, under CLI11, wraps "-1" and saturates 2^64.
const CLI::Validator kSeed(
    [](std::string& value) {
      std::uint64_t seed = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), seed);
      const bool ok = !value.empty() && value[0] != '-' && ec == std::errc() && end == value.data() + value.size();
      return ok ? std::string() : std::string("must be an integer in [0, 18446744073709551615]");
    },
    "");

// The sheet and the scene.
void add_input_options(CLI::App* run, app::RunOptions& o) {
  Params& p = o.params;
  auto* grid = run->add_option("--grid", o.grid, "N x N vertex grid on the unit square")->capture_default_str();
  run->add_option("--mesh", o.mesh, "triangle mesh to crumple (OBJ)")->excludes(grid);
  run->add_flag("--fixed-diagonals", o.fixed_diagonals, "grid: one diagonal direction everywhere");
  run->add_option("--scene", p.scene, "sphere | free | hang (two top corners pinned; add --gravity)")
      ->transform(choice<Scene>({{"sphere", Scene::Sphere}, {"free", Scene::Free}, {"hang", Scene::Hang}}));
  run->add_option("--frame-dt", p.frame_dt, "seconds per frame (h = frame-dt / substeps)")->capture_default_str();
  run->add_option("--squeeze", p.squeeze, "free scene: initial scale about the centroid")->capture_default_str();
  run->add_option("--frames", o.frames, "frames of 1/60 s")->capture_default_str();
}

// How a step is taken, and where.
void add_step_options(CLI::App* run, app::RunOptions& o) {
  Params& p = o.params;
  run->add_option_function<std::string>(
         "--substeps",
         [&p = o.params](const std::string& s) {
           int n = 0;
           const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), n);
           p.auto_substeps = s == "auto";
           if (p.auto_substeps) return;
           if (ec != std::errc() || end != s.data() + s.size())
             throw CLI::ValidationError("--substeps", "must be a whole number or auto, got '" + s + "'");
           p.substeps = n;
         },
         "steps per frame, or auto: chosen each frame from the mesh's stiffest mode and --max-step "
         "(default auto; --paper: 1)");
  run->add_option("--max-step", p.max_step, "--substeps auto: largest step in seconds (0: stability only)")
      ->capture_default_str();
  run->add_option_function<std::string>(
         "--adapt",
         [&p = o.params](const std::string& s) {
           if (s != "step" && s != "frame") throw CLI::ValidationError("--adapt", "must be step or frame, got '" + s + "'");
           p.adapt_per_frame = s == "frame";
         },
         "fracture and restoration after every step (the paper's) or once per frame (default frame; --paper: step)");
  run->add_option("--adapt-every", p.adapt_every,
                  "--adapt frame: the pass once per this many seconds instead of once per frame (0)")
      ->capture_default_str();
  run->add_option("--integrator", p.integrator, "approx | explicit | implicit | xpbd")
      ->transform(choice<Integrator>({{"approx", Integrator::Approx},
                                      {"explicit", Integrator::Explicit},
                                      {"implicit", Integrator::Implicit},
                                      {"xpbd", Integrator::Xpbd}}));
  run->add_option("--sweeps", p.sweeps, "K, Jacobi sweeps of the approximate implicit method")->capture_default_str();
  run->add_option("--predictor", p.predictor, "approx: bounded | explicit (the paper's, unstable when stiff)")
      ->transform(choice<Predictor>({{"bounded", Predictor::Bounded}, {"explicit", Predictor::Explicit}}));
  run->add_option("--jacobian", p.jacobian, "approx: isotropic (the paper's) | axial (kappa_e u u^T)")
      ->transform(choice<Jacobian>({{"isotropic", Jacobian::Isotropic}, {"axial", Jacobian::Axial}}));
  run->add_option("--cg-tolerance", p.cg_tolerance, "implicit: CG relative tolerance")->capture_default_str();
  run->add_option("--backend", o.backend, "backend")->check(CLI::IsMember(backend_names()))->capture_default_str();
  run->add_option("--threads", o.threads, "worker threads")->capture_default_str();
  run->add_flag("--resident", o.resident,
                "fault in the memory reserved for the sheet's growth at load: no page fault in a frame until outgrown");
}

// The model's coefficients and switches (MODEL.md), the seed and the scene's sphere.
void add_model_options(CLI::App* run, Params& p) {
  run->add_option("--seed", p.seed, "seed of the random stream")->check(kSeed)->capture_default_str();
  run->add_option("--kappa", p.kappa, "stiffness per unit mass [Eq 5]")->capture_default_str();
  run->add_option("--bend", p.bend, "bending coefficient per unit mass [Eq 9]")->capture_default_str();
  run->add_option("--damping", p.damping, "spring damping per unit mass")->capture_default_str();
  run->add_option("--viscosity", p.viscosity, "implicit viscosity between neighbours per unit mass")
      ->capture_default_str();
  run->add_option("--phi", p.phi, "curvature sensitivity of fracture [Eq 6]")->capture_default_str();
  run->add_option("--psi", p.psi, "new-vertex offset scale [Eq 7]")->capture_default_str();
  run->add_option("--epsilon", p.epsilon, "restoration threshold [Eq 10]")->capture_default_str();
  run->add_option("--varphi", p.varphi, "mass-split exponent [Eq 3]")->capture_default_str();
  run->add_option("--floor", p.floor, "refinement floor, fraction of the mean edge length")->capture_default_str();
  run->add_option("--perturb", p.perturb, "initial dome height / sheet reach (0: start flat)")->capture_default_str();
  run->add_option("--gravity", p.gravity, "gravity along -z, m/s^2")->capture_default_str();
  run->add_option("--mass", p.total_mass, "total sheet mass")->capture_default_str();
  run->add_option("--restore", p.restore, "exact | paper")
      ->transform(choice<RestoreForm>({{"exact", RestoreForm::Exact}, {"paper", RestoreForm::Paper}}));
  run->add_option("--bending", p.bending, "balanced | paper")
      ->transform(choice<BendingForm>({{"balanced", BendingForm::Balanced}, {"paper", BendingForm::Paper}}));
  run->add_flag("!--no-fracture", p.fracture, "turn the stochastic fracture off");
  run->add_flag("!--no-restoration", p.restoration, "turn restoration off");
  run->add_option("--max-vertices", p.max_vertices, "vertex budget: no split beyond it (0: unlimited)")
      ->capture_default_str();
  run->add_option("--sphere-start", p.sphere_start, "R0 / distance of the farthest vertex")->capture_default_str();
  run->add_option("--sphere-end", p.sphere_end, "R1 / distance of the farthest vertex")->capture_default_str();
  run->add_option("--sphere-time", p.sphere_time, "seconds to shrink from R0 to R1")->capture_default_str();
}

void add_output_options(CLI::App* run, app::RunOptions& o) {
  run->add_option("--out", o.out, "output folder: stats.csv, final.obj");
  run->add_flag("--force", o.force, "--out may be a non-empty folder: replace crumple's files in it");
  run->add_option("--every", o.every, "also write every K-th frame as frame_NNNNN.obj")->capture_default_str();
  run->add_flag("--quiet", o.quiet, "no progress bar and no summary");
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"crumple: real-time paper crumpling on an adaptive mass-spring mesh"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", std::string("crumple ") + version());
  app::RunOptions o;
  // --paper chooses the base that the other options change. It is found before parsing so that
  // an option given with it wins in any order.
  const bool paper = std::any_of(argv + 1, argv + argc, [](const char* a) { return std::strcmp(a, "--paper") == 0; });
  o.params = paper ? paper_params() : default_params();
  Params& p = o.params;
  CLI::App* run = cli.add_subcommand("run", "Simulate a sheet; optionally write stats.csv and OBJ frames");

  add_input_options(run, o);
  add_step_options(run, o);
  add_model_options(run, p);
  add_output_options(run, o);
  bool paper_given = false;  // read before parsing (above); declared so that --help lists it
  run->add_flag("--paper", paper_given, "start from the paper's configuration (approx, one step per frame, no viscosity, "
                "fracture after every step) instead of the default (docs/DECISIONS.md D28)");

  for (CLI::Option* option : run->get_options()) {
    if (option->get_type_size() > 0) option->check(kNotEmpty);
  }

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e);  // --help, --version
    return app::fail(app::kBadInput, e.what());
  }
  const int code = app::run(o);
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {  // the summary line was lost (e.g. >/dev/full)
    return app::fail(app::kBadInput, std::string("cannot write to standard output: ") + std::strerror(errno));
  }
  return code;
}
