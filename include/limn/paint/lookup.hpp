// limn paint: reading an octree texture on the CPU, with the walk a shader does over the same
// pool (one fetch per level: a general node's descriptor, or a brick's mask, then the sample).
#pragma once

#include <cstdint>

#include "limn/paint/texture.hpp"

namespace limn {

/// Lookups with a cache of the last node reached, so coherent points (neighbours, a Morton
/// order, the 8 taps of a filtered lookup) resume there instead of walking from the root. One
/// sampler per thread; the texture must not change while a sampler reads it (call `reset` after
/// a change).
class OctreeSampler {
 public:
  explicit OctreeSampler(const OctreeTexture& t) : t_(&t) {}

  /// Nearest: the colour of the leaf holding p, the sample facing n (n null: the front sample;
  /// n need not be unit). False, with `out` = background, when p is outside the cube, no leaf
  /// holds it or the leaf has no sample facing n. `level` (may be null) receives the level of
  /// the leaf or of the empty cell the walk ended in. O(depth), O(1) when cached.
  bool nearest(const float p[3], const float* n, Rgba8& out, int* level = nullptr);

  /// Filtered: trilinear over the 8 cells around p at the level of p's leaf, each tap a nearest
  /// lookup (so coarser leaves count once per tap and finer ones by the sample at the tap),
  /// premultiplied by alpha, with the weights renormalised over taps that have a sample facing n:
  /// samples of a sheet facing the other way never leak in. `footprint` (world units, 0: none):
  /// when wider than the leaf, the mip levels the footprint spans (node averages) are blended
  /// trilinearly instead; averages ignore sides. Out: straight RGBA in [0,1]. False (rgba = 0)
  /// when no tap has a sample. O(8 depth), ~O(8) cached.
  bool filtered(const float p[3], const float* n, float footprint, float rgba[4]);

  /// Forgets the cache.
  void reset() { cache_level_ = -1; }

  /// Integer-coordinate form of `nearest`: (x, y, z) at level kMaxDepth.
  bool nearest_at(uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out, int* level);
  /// The value of the cell at `level` holding (x, y, z) (kMaxDepth coordinates): a leaf at or
  /// above that level (its sample facing n), or the average of the node at that level.
  bool cell_value(uint32_t x, uint32_t y, uint32_t z, int level, const float* n, Rgba8& out);

 private:
  bool brick_leaf(uint32_t word, int level, uint32_t x, uint32_t y, uint32_t z, const float* n,
                  Rgba8& out, int* leaf_level) const;
  bool trilinear(const double u[3], int level, const float* n, bool averages, float acc[5]);

  const OctreeTexture* t_;
  // The last node reached: a general node (info != 0 or kind) or a brick, its level and the
  // coordinates of its cell at that level.
  int cache_level_ = -1;
  bool cache_brick_ = false;
  uint32_t cache_ptr_ = 0, cache_info_ = 0, cache_x_ = 0, cache_y_ = 0, cache_z_ = 0;
};

/// One nearest lookup without a cache (see OctreeSampler::nearest).
bool lookup_nearest(const OctreeTexture& t, const float p[3], const float* n, Rgba8& out);
/// One filtered lookup without a cache (see OctreeSampler::filtered).
bool lookup_filtered(const OctreeTexture& t, const float p[3], const float* n, float footprint,
                     float rgba[4]);

}  // namespace limn
