// Wall-clock timing of a job's phases, for the reports of the CLI and the Python module.
#pragma once

#include <chrono>

namespace limn::jobs {

/// Milliseconds since construction.
class Stopwatch {
 public:
  double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_)
        .count();
  }
  /// Milliseconds since the last lap (or construction), and restarts the lap.
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double d = std::chrono::duration<double, std::milli>(now - lap_).count();
    lap_ = now;
    return d;
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now(), lap_ = t0_;
};

}  // namespace limn::jobs
