// Two threads pinned to two CPUs hand one cache line back and forth: how far apart the CPUs
// are, as a round trip (BM_CoreToCore, crumple_placement_probe). Cores sharing a last-level
// cache answer in some tens of nanoseconds; cores on separate ones (two chiplets, two sockets,
// or a VM's vCPUs placed so) take hundreds.
#pragma once

#include <vector>

namespace crumple::bench {

/// The CPUs this process may run on, in order (sched_getaffinity).
std::vector<int> allowed_cpus();

/// Seconds that `trips` round trips take between a thread pinned to CPU a (the caller, timed)
/// and one pinned to CPU b; negative when either could not be pinned (unpinned, the two could
/// share a CPU and the time would be the scheduler's). The caller's affinity is restored.
double round_trip_seconds(int a, int b, long trips);

}  // namespace crumple::bench
