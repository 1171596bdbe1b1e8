// The benchmarks' clock and medians.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace limn::bench {

/// Milliseconds on the steady clock (differences are durations).
inline double now_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// The median (upper median for an even count); 0 for none.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace limn::bench
