#pragma once
/// @file StepClock.h (private)
/// The clock that times a step's phases (StepCounters' seconds).

#include <chrono>

namespace tetrapage {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace tetrapage
