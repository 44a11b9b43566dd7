// The registry of backends: one name each, so the command, the tests and the benchmarks iterate
// the same list (SpringLab's idea: every simulator behind one interface).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sim/simulator.h"

namespace crumple {

/// Names of every backend built into this binary, the default first.
const std::vector<std::string>& backend_names();

/// A new simulator of the named backend; throws std::invalid_argument for an unknown name.
/// `threads` is the worker count a parallel backend uses (the reference ignores it).
std::unique_ptr<Simulator> make_simulator(const std::string& backend, const InputMesh& mesh,
                                          const Params& params, int threads = 1);

}  // namespace crumple
