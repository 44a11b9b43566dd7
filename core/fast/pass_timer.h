// Accumulates the wall time of a scope into one pass's slot (per-pass profile of a step).
#pragma once

#include <array>
#include <chrono>

namespace crumple::fast {

template <std::size_t N>
class PassTimer {
 public:
  PassTimer(std::array<double, N>& acc, int slot) : acc_(acc), slot_(slot) {}
  ~PassTimer() { acc_[slot_] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }

 private:
  std::array<double, N>& acc_;  ///< seconds per pass
  int slot_;                    ///< which pass
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

}  // namespace crumple::fast
