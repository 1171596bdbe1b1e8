// limn paint: an adaptive octree texture (colour on any surface, no UVs), after Li, Dang, Cheng and
// Jin's "indirection pool" of 2x2x2 grids (seed 002) and Lefebvre, Hornus and Neyret's octree
// textures (GPU Gems 2, ch. 37), with 32-bit links, compact children and per-leaf sides.
//
// Texture space is the mesh's rest-pose bounding cube (`origin`, `size`): a point p falls in the
// level-16 cell floor((p - origin) * (65536 / size)) (in double; `to_unit` gives the same scaled
// to [0,1)^3), so the cell at level l is that >> (16 - l). Level l splits the cube into 2^l cells
// per axis; the root
// node covers level 0 and its cells are at level 1. A texture painted at depth D has leaves at
// level D (2^D effective resolution), D <= kMaxDepth.
//
// ## The pool (one flat uint32 array, read as is by the CPU and by a shader)
//
// Every node is a 2x2x2 grid of cells, cell c = x | y << 1 | z << 2 (x, y, z the octant bits).
// Only occupied cells are stored, packed in cell order, so a node costs what it holds. General
// blocks start at even words and have even sizes, so their descriptors can be fetched as one
// uvec2 texel from an RG32UI view of the same buffer; bricks may start anywhere (no pad word:
// 0.13 byte per leaf) and their mask is read as two uint texels; colours and tags are uint texels
// of an R32UI view.
//
// * A *general* node is named by a descriptor (ptr, info), two words. The root's descriptor is
//   words 0-1. `info`: bits 0-7 occupied cells, 8-15 leaf cells, 16-23 brick cells, 24-31 leaf
//   cells holding two samples (front and back). The other occupied cells are general children.
//   Its block at `ptr`:
//     [2G words]  descriptors (ptr, info) of the G general children, in cell order
//     [B words]   brick words of the B brick children: bit 31 = the brick has a double mask,
//                 bits 0-30 = the brick's block
//     [1 word]    the node's average colour (mip level of this cell)
//     [ceil(L/8)] leaf tags, a nibble per leaf cell (cell k in bits 4(k%8)..4(k%8)+3 of word k/8)
//     [S words]   leaf samples (RGBA8), 1 per leaf cell, 2 for a double cell (front, back)
// * A *brick* is a node whose cells are general nodes holding only leaves: two levels stored as
//   one 4x4x4 block with a 64-bit mask in Morton order (bit 8 c1 + c2: c1 the cell at the brick's
//   level + 1, c2 the cell inside it), so each byte of the mask is one 2x2x2 node's occupancy.
//   On a surface a brick holds ~15 leaves, so its 12 bytes of mask and link cost ~0.8 byte per
//   leaf where a 2x2x2 node with a descriptor would cost ~2. Its block:
//     [2 words]   occupancy mask M (low word holds bits 0-31)
//     [2 words]   double mask (only when the brick word's bit 31 is set)
//     [1 word]    the brick's average colour
//     [ceil(N/8)] tags, a nibble per occupied cell
//     [S words]   samples, 1 per occupied cell, 2 for a double cell
//   A shader reads the mask (two words for two levels), the tag, then the sample; tags come
//   before samples so the three mostly share a cache line.
//
// Sample index of cell c within its node = popcount(leafs below c) + popcount(doubles below c).
//
// ## Sides (no bleeding between close sheets)
//
// A leaf cell's tag is a direction code (1-6: +x, -x, +y, -y, +z, -z; 7-14: the 8 diagonals
// (+-1, +-1, +-1)/sqrt(3), x sign slowest; 0: no direction). Its first sample serves lookups whose
// normal n has dot(dir(tag), n) >= 0, the second (double cells only) those facing the other way.
// Two sheets a fraction of a leaf apart facing opposite ways therefore never share a sample: a
// single-sided cell looked up from its back side returns nothing. Tag 0 cells have one sample,
// seen from everywhere (files may hold them; limn itself always tags the cells it creates).
//
// ## Mip averages
//
// Each general node and brick keeps the average of its cells: the mean of its occupied cells'
// values premultiplied by alpha, rounded to RGBA8, where a leaf's value is its sample (the mean
// of both sides for a two-sided cell) and an inner cell's value is its own average (a brick's
// eight inner nodes are averaged on the fly by the same rule). A footprint wider than a leaf
// then reads one texel per level. Averages ignore sides: the no-bleed guarantee holds for
// nearest and leaf-level filtered lookups.
//
// Blocks are recycled through free lists, one per block size. Every word write can be journaled
// (undo/redo per stroke, see undo.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

/// RGBA8 packed with R in the low byte (the byte order of an RGBA8 texel on a little-endian
/// machine).
using Rgba8 = uint32_t;

/// Packs 8-bit channels. O(1).
inline constexpr Rgba8 pack_rgba8(uint32_t r, uint32_t g, uint32_t b, uint32_t a) {
  return (r & 255u) | (g & 255u) << 8 | (b & 255u) << 16 | (a & 255u) << 24;
}
/// Channel k (0 = R ... 3 = A) of a packed colour. O(1).
inline constexpr uint32_t channel(Rgba8 c, int k) {
  return (c >> (8 * k)) & 255u;
}
/// Rounds floats in [0,1] (clamped) to RGBA8. O(1).
Rgba8 rgba8_from_float(const float rgba[4]);
/// RGBA8 to floats in [0,1]. O(1).
void rgba8_to_float(Rgba8 c, float rgba[4]);

namespace octree {

/// Deepest level a texture may hold (65536^3 effective).
inline constexpr int kMaxDepth = 16;
/// Depth of the coarse tree a new texture starts with (the paper's 4^3 / 8^3 start).
inline constexpr int kStartDepth = 3;

/// Number of direction codes (tags 1..kTagCount are directions, 0 is none).
inline constexpr int kTagCount = 14;
/// Unit direction of tag t (t in 1..kTagCount); (0,0,0) for tag 0. O(1).
std::array<float, 3> tag_direction(int tag);
/// The tag whose direction is closest to n (any length > 0); 0 for a zero or non-finite n. O(1).
int tag_for_normal(const float n[3]);
/// Which sample of a cell with tag `tag` serves a lookup with normal n: 0 (front) or 1 (back).
/// Tag 0 or a null/zero n: 0. O(1).
int side_for_normal(int tag, const float* n);

}  // namespace octree

/// Counts and sizes of a texture (see `OctreeTexture::stats`).
struct OctreeTextureStats {
  size_t general_nodes = 0;  ///< 2x2x2 nodes stored as general nodes (the root included).
  size_t bricks = 0;         ///< two-level 4x4x4 blocks.
  size_t nodes = 0;       ///< 2x2x2 grids in all, as the paper counts them: general nodes, plus per
                          ///< brick its own grid and each occupied grid below it.
  size_t leaf_cells = 0;  ///< leaf cells.
  size_t double_cells = 0;     ///< leaf cells holding two samples.
  size_t samples = 0;          ///< leaf samples (texels).
  size_t painted_samples = 0;  ///< samples whose colour differs from the background.
  size_t leaves_at_depth = 0;  ///< leaf cells at the deepest level present.
  int max_depth = 0;           ///< deepest leaf level.
  size_t pool_words = 0;       ///< words in the pool, free blocks included.
  size_t free_words = 0;       ///< words in free blocks.
  size_t bytes = 0;            ///< pool bytes (4 per word, free blocks included).
  /// bytes / painted_samples (0 when nothing is painted).
  double bytes_per_painted_texel = 0;
};

/// One leaf sample, as `for_each_sample` reports it.
struct OctreeSample {
  int level = 0;                 ///< the leaf cell's level.
  uint32_t x = 0, y = 0, z = 0;  ///< the cell's integer coordinates at that level.
  int tag = 0;                   ///< the cell's direction code.
  int side = 0;                  ///< 0 front, 1 back.
  Rgba8 color = 0;
  size_t word = 0;  ///< index of the sample in the pool.
};

class PaintSurface;
namespace detail {
class OctreeEditor;
}  // namespace detail

/// The texture: the pool, the cube it covers, and the free lists. Copyable (a snapshot).
class OctreeTexture {
 public:
  OctreeTexture() = default;

  /// A texture over the bounding cube of `mesh` (centred on its box, side = the longest extent
  /// times 1 + 2 * `margin`), starting as background leaves at level kStartDepth over every cell
  /// the surface touches (fewer when the mesh is tiny). Throws InputError for a mesh without
  /// faces or with a zero-size box. O(triangles * kStartDepth).
  static OctreeTexture create(const Mesh& mesh, Rgba8 background = 0, float margin = 0.01f);
  /// The same over a surface already built (saves building its BVH twice).
  static OctreeTexture create(const PaintSurface& surface, Rgba8 background = 0,
                              float margin = 0.01f);

  /// A texture over an explicit cube with only an empty root (no start tree): nothing exists
  /// until painted. Precondition: size > 0, all finite. O(1).
  static OctreeTexture empty(const float origin[3], float size, Rgba8 background = 0);

  const float* origin() const { return origin_; }
  float size() const { return size_; }
  Rgba8 background() const { return background_; }
  /// The pool (layout in this header's comment): upload as is.
  std::span<const uint32_t> words() const { return pool_; }
  /// Free blocks as (class, block) pairs, sorted; class = 2 * words, + 1 for a brick's block.
  std::vector<std::pair<uint32_t, uint32_t>> free_blocks() const;

  /// Texture-space coordinates of a world point: (p - origin) * (65536 / size) / 65536, in
  /// [0,1)^3 inside the cube (the mapping every lookup uses). O(1).
  void to_unit(const float p[3], double u[3]) const;

  /// Counts, bytes and depth. O(pool).
  OctreeTextureStats stats() const;

  /// Calls f(const OctreeSample&) for every leaf sample, cells in depth-first Morton order.
  /// O(pool).
  template <class F>
  void for_each_sample(F&& f) const {
    visit_samples(&f, [](void* ctx, const OctreeSample& s) { (*static_cast<F*>(ctx))(s); });
  }

  /// Checks the structure: every block inside the pool (general blocks at even words), no two
  /// blocks sharing a word (so no cycles), masks consistent, tags valid, free blocks disjoint
  /// from live ones and every word accounted for. Returns an empty string when valid, else the
  /// first problem. O(pool).
  std::string check() const;

  /// Rewrites the pool in depth-first order (each node's block just before its children's,
  /// bricks after their general siblings), dropping every free block: the smallest pool, and a
  /// walk that stays within a few pages near the leaves. Lookups are unchanged; undo records of
  /// this texture no longer apply (clear its PaintHistory). Throws std::logic_error while a
  /// stroke is being recorded. O(pool).
  void compact();

  /// True when the two textures hold the same pool, free lists, cube and background.
  bool operator==(const OctreeTexture& o) const;

  /// One entry of a stroke's journal (see undo.hpp): a word write (index, old, new), the pool's
  /// growth (old size, new size), a free-list push or pop (size class, block).
  struct JournalOp {
    uint32_t kind, a, b, c;
  };

 private:
  friend class detail::OctreeEditor;
  void visit_samples(void* ctx, void (*f)(void*, const OctreeSample&)) const;

  float origin_[3] = {0, 0, 0};
  float size_ = 0;
  Rgba8 background_ = 0;
  /// The pool's storage: one flat array of words that lookups read at random and painting
  /// grows; past 2 MiB, 2 MiB-aligned and advised as huge pages (src/paint/texture.cpp), so one
  /// TLB entry and one page fault cover 2 MiB instead of 4 KiB. Made as the empty root's two
  /// words (ptr 0 = no block, info 0 = empty).
  class Words {
   public:
    Words();
    Words(const Words& o);
    Words(Words&& o) noexcept;
    Words& operator=(const Words& o);
    Words& operator=(Words&& o) noexcept;
    ~Words();
    /// Grows (new words = v) or shrinks to n words. Amortised O(1) per word.
    void resize(size_t n, uint32_t v = 0);
    size_t size() const { return size_; }
    uint32_t* data() { return data_; }
    const uint32_t* data() const { return data_; }
    uint32_t& operator[](size_t i) { return data_[i]; }
    uint32_t operator[](size_t i) const { return data_[i]; }
    operator std::span<const uint32_t>() const { return {data_, size_}; }

   private:
    uint32_t* data_ = nullptr;
    size_t size_ = 0, capacity_ = 0;
  };
  Words pool_;
  /// free_[2n + b]: free blocks of n words, of bricks (b = 1) or general nodes (b = 0).
  std::vector<std::vector<uint32_t>> free_;
  /// The journal of the stroke being recorded, in order.
  bool recording_ = false;
  std::vector<JournalOp> journal_;
};

}  // namespace limn
