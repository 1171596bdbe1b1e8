// limn subdiv: corner twins from a level's edge -> corner lists (internal header).
#pragma once

#include <cstdint>
#include <span>

#include "limn/mesh/topology.hpp"

namespace limn::detail {

// twin[c] (sized to the level's corners) := the other corner on c's edge: kNone on a boundary,
// kNonManifold on an edge of more than two faces; corners on no listed edge stay kNone.
// O(corners + edges).
inline void corner_twins(std::span<const uint32_t> edge_corner_offsets,
                         std::span<const uint32_t> edge_corners, std::span<uint32_t> twin) {
  for (uint32_t& t : twin) t = kNone;
  const size_t ne = edge_corner_offsets.empty() ? 0 : edge_corner_offsets.size() - 1;
  for (size_t e = 0; e < ne; ++e) {
    const uint32_t lo = edge_corner_offsets[e], hi = edge_corner_offsets[e + 1];
    if (hi - lo == 2) {
      twin[edge_corners[lo]] = edge_corners[lo + 1], twin[edge_corners[lo + 1]] = edge_corners[lo];
    } else if (hi - lo > 2) {
      for (uint32_t i = lo; i < hi; ++i) twin[edge_corners[i]] = kNonManifold;
    }
  }
}

}  // namespace limn::detail
