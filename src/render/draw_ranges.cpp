#include "draw_ranges.hpp"

#include <algorithm>

namespace limn {

void patch_draw_ranges(std::span<const uint32_t> face, std::span<const uint8_t> seen, size_t gap,
                       size_t chunk, std::vector<DrawRange>& out) {
  out.clear();
  size_t begin = 0, end = 0;  // the run of patches to draw, not yet cut into draws
  auto flush = [&] {
    // Steps of at most end - first: first + chunk would wrap for chunk = SIZE_MAX.
    for (size_t first = begin; first < end;) {
      const size_t n = std::min(chunk, end - first);
      out.push_back({first, n});
      first += n;
    }
  };
  for (size_t p = 0; p < face.size(); ++p) {
    if (!seen[face[p]]) continue;
    if (end == 0 || p > end + gap) flush(), begin = p;
    end = p + 1;
  }
  flush();
}

}  // namespace limn
