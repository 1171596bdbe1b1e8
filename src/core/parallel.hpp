// Loops over [0, n) on TBB's threads in chunks, serially when too short to pay. Internal header.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace limn {

/// Calls body(begin, end) over chunks of [0, n) of about `grain` items on TBB's threads, or once
/// over the whole range when n < 2 * grain (threading would cost more than it saves).
template <class F>
void parallel_range(size_t n, size_t grain, F&& body) {
  if (n < 2 * grain) {
    body(size_t(0), n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

}  // namespace limn
