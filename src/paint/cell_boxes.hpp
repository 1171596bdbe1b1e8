// The octree's cells as boxes in model space and the surface's triangles meeting them: a cell's
// box, its children's, a list of triangles filtered or split by child (the AVX2 loops the
// refiner spends most of its time in), a brick's 64 leaves' lists at once, a region's cells and
// the leaf a cell gets from its list. Internal header of the paint layer.
#pragma once

#include <array>
#include <cstdint>
#include <span>
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

/// The bounds of a list's triangles' corners.
struct ListBox {
  float lo[3], hi[3];
};

/// Where to refine and paint: everywhere, or cells meeting a ball.
struct Region {
  bool everything = true;
  paint_detail::V3 c;
  float r = 0;
};

/// A list of triangles split by child of a cell: out[c], child c's.
using Split = std::array<std::vector<uint32_t>, 8>;

/// A brick's leaves' lists, one after another: leaf m's in tris[start[m], start[m + 1]).
struct LeafLists {
  uint32_t start[65];
  std::vector<uint32_t> tris;
  std::span<const uint32_t> list(int m) const {
    return std::span<const uint32_t>(tris).subspan(start[m], start[m + 1] - start[m]);
  }
};

/// A texture cube's cells against a surface. Every test grows a cell's box by slack(), so a
/// triangle lying on a cell face belongs to both cells. Cheap to make (per refiner); reads the
/// texture's cube and background and the surface, which must outlive it.
class CellBoxes {
 public:
  CellBoxes(const OctreeTexture& t, const PaintSurface& s);

  const PaintSurface& surface() const { return s_; }
  /// How far every box test grows a cell's box (model units): 2^-22 of the cube.
  float slack() const { return slack_; }
  /// The texture cube's corner (model units, double as every box is computed from it).
  const double* origin() const { return origin_; }
  /// A cell's size at a level: the quotient divided out once per level.
  double cell_size(int level) const {
    return level >= 0 && level <= octree::kMaxDepth ? scale_[size_t(level)]
                                                    : double(size_) / double(1u << level);
  }
  /// The box of a cell.
  CellBox box(int level, uint32_t x, uint32_t y, uint32_t z) const {
    CellBox b;
    b.level = level, b.x = x, b.y = y, b.z = z;
    const double s = cell_size(level);
    b.c = {centre(0, x, s), centre(1, y, s), centre(2, z, s)};
    b.h = float(0.5 * s);
    return b;
  }
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

  /// A brick's leaves (cells two levels below a cell): per axis the centres of the 4 leaves
  /// along it, as box() computes them; leaf m (8 * c1 + c2) has index (c1 >> a & 1) * 2 +
  /// (c2 >> a & 1) along axis a.
  struct BrickLeaves {
    float c[3][4];
    float h;
    int level;
    uint32_t base[3];
  };
  BrickLeaves brick_leaves(const CellBox& bb) const {
    BrickLeaves l;
    l.level = bb.level + 2;
    const double s = cell_size(l.level);
    l.base[0] = 4 * bb.x, l.base[1] = 4 * bb.y, l.base[2] = 4 * bb.z;
    for (int a = 0; a < 3; ++a)
      for (uint32_t k = 0; k < 4; ++k) l.c[a][k] = centre(a, l.base[a] + k, s);
    l.h = float(0.5 * s);
    return l;
  }
  static constexpr int leaf_index(int m, int a) { return (m >> (3 + a) & 1) * 2 + (m >> a & 1); }
  /// The box of leaf m: what child(child(bb, m >> 3), m & 7) gives.
  static CellBox leaf_box(const BrickLeaves& l, int m) {
    CellBox b;
    const int i = leaf_index(m, 0), j = leaf_index(m, 1), k = leaf_index(m, 2);
    b.level = l.level, b.x = l.base[0] + uint32_t(i), b.y = l.base[1] + uint32_t(j),
    b.z = l.base[2] + uint32_t(k);
    b.c = {l.c[0][i], l.c[1][j], l.c[2][k]};
    b.h = l.h;
    return b;
  }

  /// The triangles of `in` meeting the box (order kept). O(|in|).
  void filter(std::span<const uint32_t> in, const CellBox& b, std::vector<uint32_t>& out) const;
  /// The same for each of b's 8 children at once, for a list of triangles meeting b (as
  /// filter() decides; every list the refiner splits is one): a triangle whose bounding box
  /// lies on one child's side of b's three mid-planes (within the slack) goes to that child
  /// untested, as it meets the part of b's grown box on that side; one reaching several is
  /// tested against those (separating axes, 8 at once). out[c] is filter()'s list for child c
  /// but for triangles within rounding of its grown faces, kept. Only the children in `want`
  /// (bit c: child c) are tested; the others' lists come out empty.
  void split(std::span<const uint32_t> in, const CellBox& b, Split& out,
             uint32_t want = 0xffu) const;
  /// The same with b's children already at hand (`kids`, as children() gives them).
  void split(std::span<const uint32_t> in, const CellBox& b, const CellBox kids[8], Split& out,
             uint32_t want = 0xffu) const;
  /// split(), on TBB's threads in chunks when `parallel` and the list is long, each chunk's
  /// parts appended in chunk order: the same lists.
  void split_maybe_parallel(bool parallel, std::span<const uint32_t> in, const CellBox& b,
                            const CellBox kids[8], Split& out, uint32_t want = 0xffu) const;
  /// A brick's two levels at once: masks[i], the leaves (bit 8 * c1 + c2: leaf c2 of child c1,
  /// Brick's numbering) among `want` that in[i] meets, for the brick cell `bb` (level depth - 2).
  /// Each leaf is tested once, from the triangle's axes taken from the brick's centre
  /// (TriAxes): the lists of a brick's leaves are the same whichever list of the brick's
  /// triangles they come from.
  void leaf_masks(std::span<const uint32_t> in, const CellBox& bb, uint64_t want,
                  std::vector<uint64_t>& masks) const {
    leaf_masks(in, bb, brick_leaves(bb), want, masks);
  }
  /// leaf_masks with the brick's leaves at hand.
  void leaf_masks(std::span<const uint32_t> in, const CellBox& bb, const BrickLeaves& l,
                  uint64_t want, std::vector<uint64_t>& masks) const;
  /// The lists of the leaves of a brick from leaf_masks' masks of `in`: leaf m's, the in[i]
  /// with bit m of masks[i], in order.
  static void leaf_lists(std::span<const uint32_t> in, std::span<const uint64_t> masks,
                         LeafLists& out);
  /// Whether split(tris, nb, kids, out, want) would give every triangle of a list whose
  /// corners' bounds are `box` to one child, keeping all of them: then `only` is that child
  /// (-1: one not in want, every list empty). Decided from the bounds alone (the split's
  /// bounding-box sides, which only grow with them): exact.
  bool whole_list_in_one(const ListBox& box, const CellBox& nb, uint32_t want, int& only) const;
  /// Whether every triangle of a list whose corners' bounds are `box` passes tri_inside_box(b).
  bool all_inside(const ListBox& box, const CellBox& b) const;

  /// Whether the cell meets the region.
  static bool meets(const Region& r, const CellBox& b);
  /// b lies inside the region (with a margin): meets() holds for every cell inside b.
  static bool within(const Region& r, const CellBox& b);
  /// Which of b's children (`kids`) meet the region (bit c: child c).
  static uint32_t meeting(const Region& r, const CellBox kids[8]);
  /// Which leaves of the brick `bb` (bit m, leaf_box(l, m)) meet the region and lie in a
  /// child of bb that does: meets() on each, from per-axis terms (the same float operations).
  uint64_t meeting_leaves(const Region& r, const CellBox& bb, const BrickLeaves& l) const;
  /// Every triangle meeting b: `region_tris` (the region's list for b) when the region is
  /// everything, else from the surface's BVH.
  void full_tris(const Region& r, const CellBox& b, std::span<const uint32_t> region_tris,
                 std::vector<uint32_t>& out) const;

  /// A new leaf for a cell whose triangles are `tris` (non-empty), with colours inherited from
  /// `parent` (null: background).
  LeafCell make_leaf(std::span<const uint32_t> tris, const LeafCell* parent) const;
  /// The leaf of a list whose first triangle is `first` and whose first on side 1 of that one's
  /// tag is `back` (~0: none): what make_leaf makes of it.
  LeafCell leaf_of(uint32_t first, uint32_t back, const LeafCell* parent) const;
  /// The leaf make_leaf gives the cell `cb` (its list: the triangles of `candidates` meeting it,
  /// sorted), found from candidates in any order, repeats allowed, with box tests only on
  /// those that could change it (a lower index than the one kept): false when none meets the
  /// cell. For a cell only its leaf is wanted of (no list to split further).
  bool leaf_from_candidates(std::span<const uint32_t> candidates, const CellBox& cb,
                            const LeafCell* parent, LeafCell& out) const;

 private:
  /// The centre coordinate along `axis` of cell i of size s.
  float centre(int axis, uint32_t i, double s) const {
    return float(origin_[axis] + (double(i) + 0.5) * s);
  }

  const PaintSurface& s_;
  Rgba8 background_;
  float size_;
  float slack_;
  double origin_[3];
  std::array<double, octree::kMaxDepth + 1> scale_;  // cell size by level
};

}  // namespace limn::detail
