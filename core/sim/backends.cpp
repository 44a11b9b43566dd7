#include "sim/backends.h"

#include <stdexcept>

#include "fast/fast_sim.h"
#include "reference/reference_sim.h"

namespace crumple {

const std::vector<std::string>& backend_names() {
  static const std::vector<std::string> names = {"reference", "fast"};
  return names;
}

std::unique_ptr<Simulator> make_simulator(const std::string& backend, const InputMesh& mesh,
                                          const Params& params, int threads) {
  if (backend == "reference") return std::make_unique<ref::ReferenceSimulator>(mesh, params);
  if (backend == "fast") return std::make_unique<fast::FastSimulator>(mesh, params, threads);
  throw std::invalid_argument("unknown backend '" + backend + "'");
}

}  // namespace crumple
