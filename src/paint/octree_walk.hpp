// The walks of a CPU lookup over the pool (nearest, trilinear taps, filtered), each compiled twice:
// for processors with AVX2's integer set and for any other; and the sampler's cache they share.
// Internal header of the paint layer: OctreeSampler (lookup.cpp) calls them.
#pragma once

#include <cstdint>

#include "core/cpu.hpp"
#include "limn/paint/lookup.hpp"
#include "octree_blocks.hpp"

namespace limn {

/// A node a walk reached: a general node or a brick, its level and its cell there.
struct OctreeSampler::CacheSlot {
  int level = -1;
  bool brick = false;
  uint32_t ptr = 0, info = 0, x = 0, y = 0, z = 0;
};
struct OctreeSampler::Cache {
  /// The last four nodes reached, most recent first: the 8 taps of a filtered lookup
  /// straddle up to a few bricks, and one slot would thrash between them.
  CacheSlot slot[4];
  /// The brick table: bricks a filtered lookup read its taps from, in 64 slots by the low two
  /// bits of their cell's coordinates (slot x | y << 2 | z << 4): the up to 8 bricks one
  /// lookup's taps straddle, and their neighbours along a coherent path, without evicting
  /// each other (four slots keep one brick in two a lookup needs in Morton order). Bricks
  /// used again are kept unpacked, a byte and two samples per cell (37 KB in all), so a tap
  /// costs two reads instead of mask ranks, a tag nibble and a sample offset, and a coherent
  /// path unpacks a brick once for the ~10 lookups it makes there. Entry e of a cell = slot *
  /// 64 + the cell's Morton index in the brick (as in its mask).
  static constexpr int kSlotBits = 2;  ///< bits of each coordinate naming a slot
  static constexpr int kSlots = 1 << (3 * kSlotBits);
  /// The brick cell's level and coordinates (0: none), bit 62 set once the brick is unpacked:
  /// on its second use, or its first along a coherent path (see `table_hits`), so random
  /// lookups, which use a brick once, do not pay for it.
  uint64_t brick_key[kSlots] = {};
  uint64_t brick_mask[kSlots] = {};  ///< the brick's occupancy mask
  uint32_t brick_word[kSlots] = {};  ///< its brick word (block address and double flag)
  /// Per entry: the cell's tag in bits 0-3, bit 4 when it has a front sample, bit 5 a back
  /// one (0 for an empty cell); 3 bytes more, so every entry can be read as 4 bytes.
  uint8_t brick_cell[kSlots * 64 + 3] = {};
  /// Per entry e: at 2e the front sample, at 2e + 1 the back one (or the front again).
  Rgba8 brick_color[kSlots * 64 * 2] = {};
  int brick_level = -1;  ///< the level of the last brick put in the table
  /// How often recent lookups found all their taps' bricks in the table (a moving average,
  /// 0-256): above half, a brick is unpacked on its first use, since the lookups that follow
  /// will read it again.
  uint32_t table_hits = 0;
  /// The general node the last walk into a brick came through: its other bricks are one
  /// step away when a coherent path leaves the cached ones.
  CacheSlot parent;
};

namespace detail {

inline constexpr int kD = octree::kMaxDepth;
inline constexpr uint32_t kFlag = octree::kBrickDoubleFlag;

/// The child (0-7) of the cell holding kMaxDepth coordinates (x, y, z) at the level whose cells
/// are 2^(shift + 1) units wide.
inline uint32_t octant(uint32_t x, uint32_t y, uint32_t z, int shift) {
  return (x >> shift & 1u) | (y >> shift & 1u) << 1 | (z >> shift & 1u) << 2;
}

/// A nearest lookup of the kMaxDepth cell (x, y, z): `out` the sample facing n of the leaf holding
/// it, `level` (may be null) the level the walk ended at; false when no leaf holds it (out kept).
bool walk_nearest_generic(const uint32_t* pool, const OctreeIndex* index,
                          OctreeSampler::Cache& cache, uint32_t x, uint32_t y, uint32_t z,
                          const float* n, Rgba8& out, int* level);
bool walk_nearest_fast(const uint32_t* pool, const OctreeIndex* index, OctreeSampler::Cache& cache,
                       uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out, int* level);
/// The 8 leaf taps around u (cube units, [0, 1)) at `level`, accumulated premultiplied into acc
/// (rgb, alpha, weight); `deepest`: the level of the finest leaf a tap read, `reach`: the deepest
/// level a tap's walk ended at. False when no tap has a sample.
bool walk_trilinear_generic(const uint32_t* pool, const OctreeIndex* index,
                            OctreeSampler::Cache& cache, const double u[3], int level,
                            const float* n, float acc[5], int& deepest, int& reach);
bool walk_trilinear_fast(const uint32_t* pool, const OctreeIndex* index,
                         OctreeSampler::Cache& cache, const double u[3], int level, const float* n,
                         float acc[5], int& deepest, int& reach);
/// A filtered lookup at the leaf level of kMaxDepth cell c (u: the same point in cube units):
/// acc as walk_trilinear's, leaf_level the level filtered at; -1 when the footprint (model
/// units, the cube `size` wide) asks for mip levels instead, else whether a tap had a sample.
int walk_filtered_generic(const uint32_t* pool, const OctreeIndex* index,
                          OctreeSampler::Cache& cache, const uint32_t c[3], const double u[3],
                          const float* n, float footprint, double size, int& leaf_level,
                          float acc[5]);
int walk_filtered_fast(const uint32_t* pool, const OctreeIndex* index, OctreeSampler::Cache& cache,
                       const uint32_t c[3], const double u[3], const float* n, float footprint,
                       double size, int& leaf_level, float acc[5]);
/// Whether lookups take the fast walks (LIMN_NO_SIMD=1 in the environment: the plain ones).
inline bool fast_walk() {
  return cpu::features().avx2_bits;
}

/// Which side of a leaf with `tag` faces n (0: front; n null or tag 0: front).
int leaf_side(uint32_t tag, const float* n);
/// The sample facing n of the leaf of the brick `word` (a brick at `level`) holding (x, y, z);
/// false when the brick has no leaf there or none facing n.
bool brick_leaf_sample(const uint32_t* pool, uint32_t word, int level, uint32_t x, uint32_t y,
                       uint32_t z, const float* n, Rgba8& out);

}  // namespace detail
}  // namespace limn
