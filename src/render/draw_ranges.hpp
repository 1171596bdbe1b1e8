// Which patches a frame draws, in which draw calls: the part of PatchDrawer::draw that needs no
// GL, so that tests can hold it to a brute-force count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace limn {

struct DrawRange {
  size_t first = 0, count = 0;  ///< patches [first, first + count)
};

/// The draw calls for patches whose cage face is `face[p]`: the patches of faces marked in
/// `seen` (indexed by face), runs of them joined across gaps of at most `gap` patches out of
/// view (drawing a few such patches costs less than another call), each run cut into draws of
/// at most `chunk` patches (chunk >= 1; SIZE_MAX: whole runs). In order, disjoint; every seen
/// patch in exactly one range. Replaces `out`. O(patches).
void patch_draw_ranges(std::span<const uint32_t> face, std::span<const uint8_t> seen, size_t gap,
                       size_t chunk, std::vector<DrawRange>& out);

}  // namespace limn
