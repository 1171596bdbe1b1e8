// PatchDrawer's draw calls (which patches, in which calls) against a brute-force count: every
// patch of a face in view drawn exactly once, whatever the chunk size, including the whole-run
// draws real GPUs get (chunk = SIZE_MAX).
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "render/draw_ranges.hpp"

namespace limn {
namespace {

TEST(RenderDrawRanges, EverySeenPatchOnceAndGapsBounded) {
  std::mt19937 rng(5);
  std::vector<DrawRange> ranges;
  for (int trial = 0; trial < 200; ++trial) {
    const size_t faces = 1 + rng() % 40, patches = rng() % 300, gap = rng() % 10;
    std::vector<uint32_t> face(patches);
    // Runs of patches per face, as a patch table orders them.
    for (size_t p = 0; p < patches; ++p)
      face[p] = p && rng() % 4 ? face[p - 1] : uint32_t(rng() % faces);
    std::vector<uint8_t> seen(faces);
    const size_t share = rng() % 5;  // 0: nothing seen, 4: most faces seen
    for (uint8_t& s : seen) s = rng() % 4 < share;
    for (const size_t chunk : {size_t(1), size_t(3), size_t(32), SIZE_MAX}) {
      patch_draw_ranges(face, seen, gap, chunk, ranges);
      std::vector<int> drawn(patches, 0);
      size_t previous_end = 0;
      for (const DrawRange& r : ranges) {
        ASSERT_GE(r.count, 1u);
        ASSERT_LE(r.count, chunk);
        ASSERT_GE(r.first, previous_end) << "ranges in order and disjoint";
        ASSERT_LE(r.first + r.count, patches);
        previous_end = r.first + r.count;
        for (size_t p = r.first; p < r.first + r.count; ++p) ++drawn[p];
      }
      size_t unseen_run = 0;
      for (size_t p = 0; p < patches; ++p) {
        ASSERT_LE(drawn[p], 1) << "patch " << p << " drawn twice, chunk " << chunk;
        if (seen[face[p]]) {
          ASSERT_EQ(drawn[p], 1) << "patch " << p << " in view not drawn";
        }
        unseen_run = drawn[p] && !seen[face[p]] ? unseen_run + 1 : 0;
        ASSERT_LE(unseen_run, gap) << "more patches out of view drawn through than the gap";
      }
    }
  }
}

}  // namespace
}  // namespace limn
