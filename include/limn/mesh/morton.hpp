// Morton (Z-order) codes: coordinates' bits interleaved, so that points near each other in space
// mostly get codes near each other; sorting work by code keeps what it touches close in memory.
#pragma once

#include <cstdint>

namespace limn {

/// The low 16 bits of x spread to every third bit (bit i to bit 3i). O(1).
constexpr uint64_t spread_bits3(uint32_t x) {
  uint64_t v = x & 0xffffu;
  v = (v | v << 16) & 0x0000ff0000ffull;
  v = (v | v << 8) & 0x00f00f00f00full;
  v = (v | v << 4) & 0x0c30c30c30c3ull;
  v = (v | v << 2) & 0x249249249249ull;
  return v;
}

/// The 48-bit Morton code of cell (x, y, z), 16 bits each (higher bits ignored): bit i of x goes
/// to bit 3i, of y to 3i + 1, of z to 3i + 2. O(1).
constexpr uint64_t morton3(uint32_t x, uint32_t y, uint32_t z) {
  return spread_bits3(x) | spread_bits3(y) << 1 | spread_bits3(z) << 2;
}

static_assert(morton3(1, 0, 0) == 1 && morton3(0, 1, 0) == 2 && morton3(0, 0, 1) == 4 &&
              morton3(3, 0, 0) == 9 && morton3(0xffff, 0xffff, 0xffff) == (uint64_t(1) << 48) - 1);

}  // namespace limn
