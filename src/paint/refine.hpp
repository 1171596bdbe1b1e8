// Lazy refinement of the octree over a region of the surface, calling a painter on the leaves it
// reaches. Internal header of the paint layer.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "geometry.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "octree_blocks.hpp"

namespace limn::detail {

/// A cell of the octree: its level, integer coordinates at that level, centre and half size.
struct CellBox {
  int level = 0;
  uint32_t x = 0, y = 0, z = 0;
  paint_detail::V3 c;
  float h = 0;
};

/// What happens to a leaf cell at or below the target depth inside the region.
class LeafPainter {
 public:
  virtual ~LeafPainter() = default;
  static constexpr uint32_t kNoMemo = ~0u;
  /// `tris`: every triangle (sorted) meeting the cell; may change `cell` (samples, or add the
  /// back sample). `memo`: with Refiner::keep_brick_lists, a number the refiner gives a brick's
  /// leaf it visits (not one it builds), the same for that cell, with the same `tris`, in every
  /// run of that refiner and no other cell's; kNoMemo for other cells.
  virtual void paint(const CellBox& box, LeafCell& cell, std::span<const uint32_t> tris,
                     uint32_t memo) = 0;
  /// Finishes what `paint` left pending (cells painted since the last flush stay where they are
  /// until then). Called before a node's cells are stored or averaged.
  virtual void flush() {}
};

/// Where to refine and paint: everywhere, or cells meeting a ball.
struct Region {
  bool everything = true;
  paint_detail::V3 c;
  float r = 0;
};

struct RefineStats {
  size_t leaves_created = 0, bricks_created = 0, generals_created = 0, bricks_exploded = 0,
         bricks_compacted = 0, leaves_painted = 0;
};

class Refiner {
 public:
  Refiner(OctreeTexture& t, const PaintSurface& s);

  /// Refines every cell meeting `region` and touched by the surface down to level `depth`, then
  /// calls `painter` (may be null) on every leaf at level >= depth there. `tris`: a sorted list
  /// holding at least every triangle meeting a cell of the region at level >= depth - 2.
  /// Precondition: 1 <= depth <= kMaxDepth.
  void run(const Region& region, std::span<const uint32_t> tris, int depth, LeafPainter* painter);

  /// The box of a cell.
  CellBox box(int level, uint32_t x, uint32_t y, uint32_t z) const {
    CellBox b;
    b.level = level, b.x = x, b.y = y, b.z = z;
    const double s = cell_size(level);
    b.c = {centre(0, x, s), centre(1, y, s), centre(2, z, s)};
    b.h = float(0.5 * s);
    return b;
  }
  /// The triangles of `in` meeting the box (order kept).
  void filter(std::span<const uint32_t> in, const CellBox& b, std::vector<uint32_t>& out) const;
  /// The same for each of b's 8 children at once: a triangle is tested only against the
  /// children its bounding box reaches (1-2 of 8 deep in the tree). out[c] as filter() gives.
  using Split = std::array<std::vector<uint32_t>, 8>;
  /// Only the children in `want` (bit c: child c) are tested; the others' lists come out empty.
  void split(std::span<const uint32_t> in, const CellBox& b, Split& out,
             uint32_t want = 0xffu) const;
  /// The same with b's children already at hand (`kids`, as children() gives them).
  void split(std::span<const uint32_t> in, const CellBox& b, const CellBox kids[8], Split& out,
             uint32_t want = 0xffu) const;
  /// The 8 children of a box: child(b, c) for each c, with each of the 6 distinct coordinates
  /// computed once (box()'s formula) instead of 24 times.
  void children(const CellBox& b, CellBox kids[8]) const {
    const int level = b.level + 1;
    const double s = cell_size(level);
    const uint32_t x = 2 * b.x, y = 2 * b.y, z = 2 * b.z;
    float cx[2], cy[2], cz[2];
    for (uint32_t i = 0; i < 2; ++i)
      cx[i] = centre(0, x + i, s), cy[i] = centre(1, y + i, s), cz[i] = centre(2, z + i, s);
    const float h = float(0.5 * s);
    for (int c = 0; c < 8; ++c) {
      const uint32_t i = uint32_t(c & 1), j = uint32_t(c >> 1 & 1), k = uint32_t(c >> 2 & 1);
      CellBox& o = kids[c];
      o.level = level, o.x = x + i, o.y = y + j, o.z = z + k;
      o.c = {cx[i], cy[j], cz[k]};
      o.h = h;
    }
  }
  /// Child c of a box.
  CellBox child(const CellBox& b, int c) const {
    return box(b.level + 1, 2 * b.x + uint32_t(c & 1), 2 * b.y + uint32_t(c >> 1 & 1),
               2 * b.z + uint32_t(c >> 2 & 1));
  }
  /// A new leaf for a cell whose triangles are `tris` (non-empty), with colours inherited from
  /// `parent` (null: background).
  LeafCell make_leaf(std::span<const uint32_t> tris, const LeafCell* parent) const;

  /// Keeps, across runs (the dabs of a stroke), the triangle lists of the leaves of each brick
  /// run() visits (not those it builds), and uses them instead of splitting the brick's lists
  /// again when a later run wants no leaf of it the earlier ones did not. A leaf a run paints
  /// meets the region, so every triangle meeting it is in the run's list (see run()): its list,
  /// the triangles passing the same box tests from the root down, is the same in every run, so
  /// the results are the same bit for bit. Only for runs with the same depth over an unchanged
  /// mesh; off by default.
  void keep_brick_lists(bool on) { keep_ = on; }

  RefineStats stats;

 private:
  /// A cell's size at a level: the quotient divided out once per level.
  double cell_size(int level) const {
    return level >= 0 && level <= octree::kMaxDepth
               ? scale_[size_t(level)]
               : double(ed_.texture().size()) / double(1u << level);
  }
  /// The centre coordinate along `axis` of cell i of size s.
  float centre(int axis, uint32_t i, double s) const {
    return float(origin_[axis] + (double(i) + 0.5) * s);
  }
  bool meets(const CellBox& b) const;
  /// b lies inside the region (with a margin): meets() holds for every cell inside b.
  bool within(const CellBox& b) const;
  /// Which of b's children (`kids`) meet the region (bit c: child c).
  uint32_t meeting(const CellBox kids[8]) const;
  void full_tris(const CellBox& b, std::span<const uint32_t> region_tris,
                 std::vector<uint32_t>& out) const;
  /// `full` (may be null): every triangle meeting the node's box, when known (a node just made
  /// by refining): its children's lists are filtered from it instead of queried; then the
  /// node's scratch already holds full split by child (`full_parts`), as refine_leaf left it.
  void visit_general(GeneralNode& n, const CellBox& nb, std::span<const uint32_t> tris,
                     const std::vector<uint32_t>* full = nullptr);
  /// Paints b's leaves in the region; b.avg is left for the caller (stale if a cell changed).
  void visit_brick(Brick& b, const CellBox& bb, std::span<const uint32_t> tris);
  /// A new general node for the leaf cell `cb` (refined one level); leaves full split by child
  /// in cb's scratch (`full_parts`).
  GeneralNode refine_leaf(const CellBox& cb, const LeafCell& leaf, std::span<const uint32_t> full);
  /// A new brick for the leaf cell `cb` (two levels), visited at once: what make-then-visit
  /// did, with the region's lists taken from the full ones (`tris`, the region's list for cb,
  /// is a subset of `full`) instead of split again. False (b.mask 0) when no sub-cell meets
  /// the surface.
  bool build_brick(const CellBox& cb, const LeafCell& leaf, std::span<const uint32_t> full,
                   std::span<const uint32_t> tris, Brick& b);
  GeneralNode explode(const Brick& b, const CellBox& bb);
  /// Encodes and stores a node; returns (ptr, info). `old_ptr` 0: new.
  void store_general(const GeneralNode& n, uint32_t old_ptr, uint32_t old_info, uint32_t& ptr,
                     uint32_t& info);
  uint32_t store_brick(const Brick& b, uint32_t old_word);
  Rgba8 child_avg(const GeneralNode& n, int c) const;
  Rgba8 general_avg(const GeneralNode& n) const;
  static Rgba8 brick_avg(const Brick& b);
  /// A general node whose cells are all leaf-only general nodes becomes a brick.
  bool try_compact(const GeneralNode& n, Brick& out) const;

  OctreeEditor ed_;
  const PaintSurface& s_;
  std::array<double, octree::kMaxDepth + 1> scale_;  // cell size by level
  double origin_[3];
  Region region_;
  int depth_ = 0;
  LeafPainter* painter_ = nullptr;
  float slack_ = 0;
  std::vector<uint32_t> words_;
  /// Per node level: lists a visit keeps while it recurses below.
  struct Scratch {
    std::vector<uint32_t> full;
    Split parts, full_parts;
  };
  std::array<Scratch, octree::kMaxDepth + 1> scratch_;
  Split brick1_, brick2_;      // a brick's two levels
  std::vector<uint32_t> sub_;  // one sub-cell's region list
  /// keep_brick_lists: per brick (by level and Morton code), which leaves' lists are known and
  /// where they are in kept_tris_.
  struct KeptBrick {
    uint64_t known = 0;
    uint32_t off[64], len[64];
  };
  bool keep_ = false;
  std::unordered_map<uint64_t, uint32_t> kept_index_;
  std::vector<KeptBrick> kept_;
  std::vector<uint32_t> kept_tris_;
};

}  // namespace limn::detail
