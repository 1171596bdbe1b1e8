// Wall-clock milliseconds for the timings the library reports in its stats. Internal header.
#pragma once

#include <chrono>

namespace limn {

/// Milliseconds on the steady clock since t0.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace limn
