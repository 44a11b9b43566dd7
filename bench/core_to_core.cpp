#include "core_to_core.h"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace crumple::bench {

std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  return cpus;
}

namespace {

bool pin_to(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

/// The counter the two threads hand back and forth, alone on its line.
struct alignas(64) Line {
  std::atomic<long> turn{0};
};

/// `trips` round trips, timed on this thread: it writes odd values, and the partner thread
/// answers each with the next even one.
double bounce(Line& line, long trips) {
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < trips; ++i) {
    const long ask = 2 * i + 1;
    line.turn.store(ask, std::memory_order_release);
    while (line.turn.load(std::memory_order_acquire) != ask + 1) {
    }
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

double round_trip_seconds(int a, int b, long trips) {
  const pthread_t self = pthread_self();
  cpu_set_t before;
  CPU_ZERO(&before);
  pthread_getaffinity_np(self, sizeof before, &before);
  Line line;
  std::atomic<bool> stop{false};
  std::atomic<int> partner_pinned{-1};  // -1 until the partner has tried, then 0 or 1
  std::thread partner([&] {
    partner_pinned = pin_to(b) ? 1 : 0;
    long seen = 0;
    while (!stop.load(std::memory_order_relaxed)) {
      const long v = line.turn.load(std::memory_order_acquire);
      if (v != seen && (v & 1)) line.turn.store(v + 1, std::memory_order_release), seen = v + 1;
    }
  });
  const bool pinned = pin_to(a);
  while (partner_pinned.load() < 0) std::this_thread::yield();
  const double seconds = pinned && partner_pinned.load() == 1 ? bounce(line, trips) : -1.0;
  stop = true;
  partner.join();
  pthread_setaffinity_np(self, sizeof before, &before);
  return seconds;
}

double first_two_cpus_round_trip_ns(long trips) {
  const std::vector<int> cpus = allowed_cpus();
  if (cpus.size() < 2) return -1.0;
  const double seconds = round_trip_seconds(cpus[0], cpus[1], trips);
  return seconds < 0 ? -1.0 : 1e9 * seconds / double(trips);
}

}  // namespace crumple::bench
