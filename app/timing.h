// timing.h: wall-clock seconds for the commands' reports (stage times, frame rates).
#pragma once

#include <chrono>

namespace glaze {

using Clock = std::chrono::steady_clock;

// Seconds elapsed since `start`.
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace glaze
