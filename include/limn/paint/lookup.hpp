// limn paint: reading an octree texture on the CPU, with the walk a shader does over the same
// pool (one fetch per level: a general node's descriptor, or a brick's mask, then the sample).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "limn/paint/texture.hpp"

namespace limn {

/// A dense table over the cells of one level naming the deepest node (general node or brick)
/// holding each, where a walk resumes: random lookups skip the top levels (the design note's
/// "dense top-level index"). CPU only, not part of the texture or its file; rebuild it after the
/// texture changes. 12 bytes per cell: level 5 = 384 KiB, level 6 = 3 MiB.
class OctreeIndex {
 public:
  /// Builds the table at `level` (1-7). O(8^level + nodes above it).
  explicit OctreeIndex(const OctreeTexture& t, int level = 6);
  int level() const { return level_; }
  size_t bytes() const { return entries_.size() * sizeof(Entry); }

  struct Entry {
    uint32_t ptr = 0, info = 0;  ///< a general node (ptr, info), or a brick word in ptr
    int8_t level = 0;            ///< the node's level
    uint8_t brick = 0;           ///< 1: ptr is a brick word
  };
  const Entry& at(uint32_t x, uint32_t y, uint32_t z) const {
    return entries_[(size_t(z) << (2 * level_)) | (size_t(y) << level_) | x];
  }

 private:
  std::vector<Entry> entries_;
  int level_;
};

/// Lookups with a cache of the last node reached, so coherent points (neighbours, a Morton
/// order, the 8 taps of a filtered lookup) resume there instead of walking from the root. One
/// sampler per thread (it holds ~40 KB, zeroed when made: keep it for many lookups); the
/// texture must not change while a sampler reads it (call `reset` after a change).
class OctreeSampler {
 public:
  /// `index` (may be null): an OctreeIndex of the same texture, for random access.
  explicit OctreeSampler(const OctreeTexture& t, const OctreeIndex* index = nullptr);
  ~OctreeSampler();
  OctreeSampler(OctreeSampler&&) noexcept;
  OctreeSampler& operator=(OctreeSampler&&) noexcept;

  /// Nearest: the colour of the leaf holding p, the sample facing n (n null: the front sample;
  /// n need not be unit). False, with `out` = background, when p is outside the cube, no leaf
  /// holds it or the leaf has no sample facing n. `level` (may be null) receives the level of
  /// the leaf or of the empty cell the walk ended in (the coarsest one holding no leaf).
  /// O(depth), O(1) when cached.
  bool nearest(const float p[3], const float* n, Rgba8& out, int* level = nullptr);

  /// Filtered: trilinear over the 8 cells around p at the level of p's leaf, each tap a nearest
  /// lookup (so coarser leaves count once per tap), premultiplied by alpha, at a finer level
  /// wherever a tap reads the sample of a finer leaf (p in a coarse leaf beside finer ones: the
  /// level rises to that leaf's until no tap finds a finer one, so the filter never reaches a
  /// coarse cell away into painted detail), with the weights renormalised over taps that have a
  /// sample facing n:
  /// samples of a sheet facing the other way never leak in. p where no leaf is (a drawn surface
  /// a little off the painted one) starts at the coarsest cell holding p that holds no leaf and
  /// goes one level finer while a tap's cell holds finer leaves, so it reads the paint within
  /// about a leaf of p rather than coarse cell centres that miss it. `footprint` (world units, 0:
  /// none): when wider than the leaf, the mip levels the footprint spans (node averages) are
  /// blended trilinearly instead; averages ignore sides. Out: straight RGBA in [0,1]. False (rgba =
  /// 0) when no tap has a sample. O(8 depth), ~O(8) cached.
  bool filtered(const float p[3], const float* n, float footprint, float rgba[4]);

  /// Forgets the cache.
  void reset();

  /// Many lookups at once, with the results of `nearest` / `filtered` for each point (p and n:
  /// 3 floats per point; n may be null). Points go in groups of 16 whose walks first descend in
  /// lockstep issuing prefetches for each level's nodes, so the memory latency of 16 random
  /// walks overlaps instead of adding up; then each point is looked up as usual, from cache.
  /// After a group that follows a path (most points in the cell of the one before), the next
  /// skips the prefetching: the cache holds its nodes, and walks would only cost time.
  /// `found` (may be null) receives 1/0 per point. Same results as one call per point.
  void nearest_batch(const float* p, const float* n, size_t count, Rgba8* out,
                     uint8_t* found = nullptr);
  void filtered_batch(const float* p, const float* n, size_t count, float footprint, float* rgba,
                      uint8_t* found = nullptr);

  /// Integer-coordinate form of `nearest`: (x, y, z) at level kMaxDepth.
  bool nearest_at(uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out, int* level);
  /// The value of the cell at `level` holding (x, y, z) (kMaxDepth coordinates): a leaf at or
  /// above that level (its sample facing n), or the average of the node at that level.
  bool cell_value(uint32_t x, uint32_t y, uint32_t z, int level, const float* n, Rgba8& out);

  /// The nodes and bricks recent walks reached (src/paint/octree_walk.hpp).
  struct CacheSlot;
  struct Cache;

 private:
  /// Prefetches the walks of up to 16 points (when `prefetch`); returns whether they follow a
  /// path (most of them beside the point before).
  bool prefetch_group(const float* p, size_t count, bool prefetch);
  void prefetch_coords(const uint32_t* xyz, size_t count);
  bool trilinear(const double u[3], int level, const float* n, bool averages, float acc[5]);

  const OctreeTexture* t_;
  const OctreeIndex* index_;
  double origin_[3], scale_;  ///< scale_: the cube's size
  std::unique_ptr<Cache> cache_;
};

/// One nearest lookup without a cache (see OctreeSampler::nearest).
bool lookup_nearest(const OctreeTexture& t, const float p[3], const float* n, Rgba8& out);
/// One filtered lookup without a cache (see OctreeSampler::filtered).
bool lookup_filtered(const OctreeTexture& t, const float p[3], const float* n, float footprint,
                     float rgba[4]);

}  // namespace limn
