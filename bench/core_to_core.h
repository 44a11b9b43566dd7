// Two threads pinned to two CPUs hand one cache line back and forth: how far apart the CPUs
// are, as a round trip (BM_CoreToCore, crumple_placement_probe). Cores sharing a last-level
// cache answer in some tens of nanoseconds; cores on separate ones (two chiplets, two sockets,
// or a VM's vCPUs placed so) take hundreds.
#pragma once

#include <vector>

namespace crumple::bench {

/// A round trip below this: the two CPUs share a last-level cache ("near"); above it they do not
/// ("far"). It lies in the gap between the two placements a VM's host gave its vCPUs
/// (docs/PERFORMANCE.md, "The Zen 5 VM's two vCPUs move between near and far placements").
inline constexpr double kNearRoundTripNs = 250.0;

/// Round trips BM_Pair samples before each pair: a fraction of a millisecond near, about a
/// millisecond far, against frames of tens of milliseconds.
inline constexpr long kPlacementSampleTrips = 2000;

/// The round trip in ns between the first two allowed CPUs, measured with `trips` round trips;
/// negative when there are fewer than two CPUs or they cannot be pinned.
double first_two_cpus_round_trip_ns(long trips);

/// The CPUs this process may run on, in order (sched_getaffinity).
std::vector<int> allowed_cpus();

/// Seconds that `trips` round trips take between a thread pinned to CPU a (the caller, timed)
/// and one pinned to CPU b; negative when either could not be pinned (unpinned, the two could
/// share a CPU and the time would be the scheduler's). The caller's affinity is restored.
double round_trip_seconds(int a, int b, long trips);

}  // namespace crumple::bench
