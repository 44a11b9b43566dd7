// How much memory a run needs and how much the process may still take: `crumple run` refuses a
// run up front that cannot fit, instead of dying of std::bad_alloc partway.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace crumple::app {

/// Resident bytes a run of a mesh with `vertices` vertices is expected to need at most: the
/// backend's bytes per vertex, measured on a 256 x 256 grid less a 64 x 64 one (reference 0.97 KB,
/// fast 1.56 KB), rounded up, times 2 for refinement (the sphere crumple grows a sheet 1.75x),
/// plus 64 MiB for the program itself. `resident` (--resident with fracture on): the fast
/// backend's whole reserve for growth faulted in from the start, 7,000 bytes a vertex (measured
/// 6.8 KB on 256 x 256 less 64 x 64, 6.6 KB at 1024 x 1024), which the sheet grows into.
std::uint64_t estimate_run_bytes(const std::string& backend, std::size_t vertices, bool resident);

/// Bytes this process may still allocate: the least of the system's MemAvailable and what the
/// address-space and data limits (ulimit -v, -d) leave.
std::uint64_t available_bytes();

}  // namespace crumple::app
