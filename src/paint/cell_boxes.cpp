// Box geometry of the octree's cells: see cell_boxes.hpp. The two list loops (split, leaf
// masks) are compiled twice, for AVX2 and for any x86-64 or other processor, and chosen at run
// time (core/cpu.hpp).
#include "cell_boxes.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include <tbb/parallel_for.h>

#include "core/cpu.hpp"

namespace limn::detail {

using namespace paint_detail;

CellBoxes::CellBoxes(const OctreeTexture& t, const PaintSurface& s)
    : s_(s), background_(t.background()), size_(t.size()) {
  // Boxes grow by 2^-22 of the cube: a triangle lying on a cell face belongs to both cells, so a
  // point on the surface always lands in a cell that holds it.
  slack_ = t.size() * float(1.0 / double(1u << 22));
  for (int l = 0; l <= octree::kMaxDepth; ++l)
    scale_[size_t(l)] = double(t.size()) / double(1u << l);
  for (int k = 0; k < 3; ++k) origin_[k] = double(t.origin()[k]);
}

bool CellBoxes::meets(const Region& rg, const CellBox& b) {
  if (rg.everything) return true;
  const float d[3] = {std::max(std::fabs(rg.c.x - b.c.x) - b.h, 0.0f),
                      std::max(std::fabs(rg.c.y - b.c.y) - b.h, 0.0f),
                      std::max(std::fabs(rg.c.z - b.c.z) - b.h, 0.0f)};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= rg.r * rg.r;
}

bool CellBoxes::within(const Region& rg, const CellBox& b) {
  if (rg.everything) return true;
  const float d[3] = {std::fabs(rg.c.x - b.c.x) + b.h, std::fabs(rg.c.y - b.c.y) + b.h,
                      std::fabs(rg.c.z - b.c.z) + b.h};
  // The margin (2^-8 of r^2) is far above the few units of rounding in either test, whose terms
  // are all on the scale of r, so meets() is true for every cell inside b.
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= rg.r * rg.r * (1.0f - 1.0f / 256);
}

void CellBoxes::filter(std::span<const uint32_t> in, const CellBox& b,
                       std::vector<uint32_t>& out) const {
  out.clear();
  for (uint32_t t : in) {
    const V3 p0 = v3(s_.corner(t, 0)), p1 = v3(s_.corner(t, 1)), p2 = v3(s_.corner(t, 2));
    if (tri_meets_box(b.c, b.h, p0, p1, p2, slack_)) out.push_back(t);
  }
}

namespace {

// CellBoxes::split's loop: a triangle is tested only when its bounding box reaches several
// children, against all of them at once.
__attribute__((always_inline)) inline void split_loop(const PaintSurface& s,
                                                      std::span<const uint32_t> in, V3 c,
                                                      const float* kx, const float* ky,
                                                      const float* kz, float kh, float slack,
                                                      uint32_t want, Split& out) {
  for (uint32_t t : in) {
    const V3 p0 = v3(s.corner(t, 0)), p1 = v3(s.corner(t, 1)), p2 = v3(s.corner(t, 2));
    const bool lo[3] = {std::min({p0.x, p1.x, p2.x}) <= c.x + slack,
                        std::min({p0.y, p1.y, p2.y}) <= c.y + slack,
                        std::min({p0.z, p1.z, p2.z}) <= c.z + slack};
    const bool hi[3] = {std::max({p0.x, p1.x, p2.x}) >= c.x - slack,
                        std::max({p0.y, p1.y, p2.y}) >= c.y - slack,
                        std::max({p0.z, p1.z, p2.z}) >= c.z - slack};
    // Children by axis side: bit k of a mask is child k.
    const uint32_t sx = (lo[0] ? 0x55u : 0u) | (hi[0] ? 0xaau : 0u),
                   sy = (lo[1] ? 0x33u : 0u) | (hi[1] ? 0xccu : 0u),
                   sz = (lo[2] ? 0x0fu : 0u) | (hi[2] ? 0xf0u : 0u);
    const uint32_t reach = sx & sy & sz;
    uint32_t hit = reach & want;
    if (!hit) continue;
    // A triangle whose bounds lie on one child's side of the three mid-planes (within the
    // slack) meets that child: it meets the node's grown box (split's precondition), and the
    // part of that box on the child's side lies in the child's grown box. Only triangles
    // reaching several children are tested (those of them wanted).
    if (reach & (reach - 1)) hit &= tri_box_overlap8(kx, ky, kz, kh, p0, p1, p2, slack);
    for (; hit; hit &= hit - 1) out[size_t(std::countr_zero(hit))].push_back(t);
  }
}

LIMN_TARGET("avx2")
void split_loop_avx2(const PaintSurface& s, std::span<const uint32_t> in, V3 c, const float* kx,
                     const float* ky, const float* kz, float kh, float slack, uint32_t want,
                     Split& out) {
  split_loop(s, in, c, kx, ky, kz, kh, slack, want, out);
}

void split_loop_generic(const PaintSurface& s, std::span<const uint32_t> in, V3 c, const float* kx,
                        const float* ky, const float* kz, float kh, float slack, uint32_t want,
                        Split& out) {
  split_loop(s, in, c, kx, ky, kz, kh, slack, want, out);
}

}  // namespace

namespace {

// Per axis, the leaves of a brick (bit 8 * c1 + c2: leaf c2 of child c1) whose index along the
// axis (0-3) is in a 4-bit mask: kReach[axis][mask].
constexpr std::array<std::array<uint64_t, 16>, 3> kReach = [] {
  std::array<std::array<uint64_t, 16>, 3> r{};
  for (int a = 0; a < 3; ++a)
    for (int mask = 0; mask < 16; ++mask)
      for (int m = 0; m < 64; ++m)
        if (mask >> CellBoxes::leaf_index(m, a) & 1) r[size_t(a)][size_t(mask)] |= uint64_t(1) << m;
  return r;
}();

// CellBoxes::leaf_masks's loop. off[a][i]: the offset from the brick's centre of the centres of
// its leaves of index i along axis a; lanes[a][m]: the same per leaf, set for the leaves of want.
__attribute__((always_inline)) inline void leaf_masks_loop(
    const PaintSurface& s, std::span<const uint32_t> in, V3 o, const float (&off)[3][4],
    const float (&lanes)[3][64], float h, float slack, uint64_t want, uint64_t* masks) {
  using F4 = float __attribute__((vector_size(16)));
  using I4 = int32_t __attribute__((vector_size(16)));
  const float e = h + slack;
  F4 offv[3];
  for (int a = 0; a < 3; ++a) __builtin_memcpy(&offv[a], off[a], sizeof(F4));
  const I4 bit = {1, 2, 4, 8};
  for (size_t i = 0; i < in.size(); ++i) {
    const uint32_t t = in[i];
    TriAxes ta;
    V3 v[3];
    tri_axes_bounds(o, v3(s.corner(t, 0)), v3(s.corner(t, 1)), v3(s.corner(t, 2)), v, ta);
    // The box axes, per axis: tri_axes_meet's expressions on the 4 leaf indices at once.
    uint64_t reach = want;
    for (int a = 0; a < 3; ++a) {
      const I4 hit = ~(ta.mn[a] - offv[a] > e) & ~(ta.mx[a] - offv[a] < -e) & bit;
      reach &= kReach[size_t(a)][uint32_t(hit[0] | hit[1] | hit[2] | hit[3])];
    }
    uint64_t m = 0;
    if (reach) {
      tri_axes_rest(h, slack, v, ta);
      for (uint64_t left = reach; left;) {
        const int g = std::countr_zero(left) >> 3;
        const uint64_t byte = reach >> (8 * g) & 255u;
        m |= uint64_t(tri_boxes_meet8(ta, lanes[0] + 8 * g, lanes[1] + 8 * g, lanes[2] + 8 * g) &
                      byte)
             << (8 * g);
        left &= ~(uint64_t(255) << (8 * g));
      }
    }
    masks[i] = m;
  }
}

LIMN_TARGET("avx2")
void leaf_masks_avx2(const PaintSurface& s, std::span<const uint32_t> in, V3 o,
                     const float (&off)[3][4], const float (&lanes)[3][64], float h, float slack,
                     uint64_t want, uint64_t* masks) {
  leaf_masks_loop(s, in, o, off, lanes, h, slack, want, masks);
}

void leaf_masks_generic(const PaintSurface& s, std::span<const uint32_t> in, V3 o,
                        const float (&off)[3][4], const float (&lanes)[3][64], float h, float slack,
                        uint64_t want, uint64_t* masks) {
  leaf_masks_loop(s, in, o, off, lanes, h, slack, want, masks);
}

}  // namespace

void CellBoxes::leaf_masks(std::span<const uint32_t> in, const CellBox& bb, const BrickLeaves& l,
                           uint64_t want, std::vector<uint64_t>& masks) const {
  masks.resize(in.size());
  // The leaves' centres as offsets from the brick's centre.
  const float c[3] = {bb.c.x, bb.c.y, bb.c.z};
  float off[3][4], lanes[3][64];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 4; ++k) off[a][k] = l.c[a][k] - c[a];
  for (uint32_t g = 0; g < 8; ++g) {
    if (!(want >> (8 * g) & 255u)) continue;
    for (int a = 0; a < 3; ++a) {
      const float lo = off[a][(g >> a & 1) * 2], hi = off[a][(g >> a & 1) * 2 + 1];
      for (int c2 = 0; c2 < 8; ++c2) lanes[a][8 * g + uint32_t(c2)] = (c2 >> a & 1) ? hi : lo;
    }
  }
  if (cpu::features().avx2)
    leaf_masks_avx2(s_, in, bb.c, off, lanes, l.h, slack_, want, masks.data());
  else
    leaf_masks_generic(s_, in, bb.c, off, lanes, l.h, slack_, want, masks.data());
}

uint64_t CellBoxes::meeting_leaves(const Region& rg, const CellBox& bb,
                                   const BrickLeaves& l) const {
  if (rg.everything) return ~uint64_t(0);
  CellBox k1[8];
  children(bb, k1);
  const uint32_t want1 = meeting(rg, k1);
  // meets()'s terms per axis and leaf index.
  const float rc[3] = {rg.c.x, rg.c.y, rg.c.z};
  float dd[3][4];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 4; ++k) {
      const float d = std::max(std::fabs(rc[a] - l.c[a][k]) - l.h, 0.0f);
      dd[a][k] = d * d;
    }
  const float r2 = rg.r * rg.r;
  uint64_t want = 0;
  for (uint32_t g = 0; g < 8; ++g) {
    if (!(want1 >> g & 1)) continue;
    // Leaf c2 of child g: index (g >> a & 1) * 2 + (c2 >> a & 1) along axis a.
    const float* x = dd[0] + (g & 1) * 2;
    const float* y = dd[1] + (g >> 1 & 1) * 2;
    const float* z = dd[2] + (g >> 2 & 1) * 2;
    uint32_t byte = 0;
    for (uint32_t c2 = 0; c2 < 8; ++c2)
      byte |= uint32_t(x[c2 & 1] + y[c2 >> 1 & 1] + z[c2 >> 2 & 1] <= r2) << c2;
    want |= uint64_t(byte) << (8 * g);
  }
  return want;
}

uint32_t CellBoxes::meeting(const Region& rg, const CellBox kids[8]) {
  if (rg.everything) return 0xffu;
  uint32_t m = 0;
  for (int c = 0; c < 8; ++c) m |= uint32_t(meets(rg, kids[c])) << c;
  return m;
}

void CellBoxes::split(std::span<const uint32_t> in, const CellBox& b, Split& out,
                      uint32_t want) const {
  CellBox kids[8];
  children(b, kids);
  split(in, b, kids, out, want);
}

void CellBoxes::split(std::span<const uint32_t> in, const CellBox& b, const CellBox kids[8],
                      Split& out, uint32_t want) const {
  float kx[8], ky[8], kz[8];
  float kh = 0;
  for (int c = 0; c < 8; ++c) {
    const CellBox& k = kids[c];
    kx[c] = k.c.x, ky[c] = k.c.y, kz[c] = k.c.z, kh = k.h;
    out[size_t(c)].clear();
  }
  if (cpu::features().avx2)
    split_loop_avx2(s_, in, b.c, kx, ky, kz, kh, slack_, want, out);
  else
    split_loop_generic(s_, in, b.c, kx, ky, kz, kh, slack_, want, out);
}

namespace {

// Lists this long are split in chunks on TBB's threads (a coarse cell's full list, a dab's list
// above its task cells: thousands of triangles, on the path every dab waits for).
constexpr size_t kChunk = 512;

}  // namespace

bool CellBoxes::whole_list_in_one(const ListBox& box, const CellBox& nb, uint32_t want,
                                  int& only) const {
  // split_loop's sides: a triangle whose lowest corner lies above c + slack reaches only the
  // upper child along that axis, one whose highest lies below c - slack only the lower.
  const float c[3] = {nb.c.x, nb.c.y, nb.c.z};
  int k = 0;
  for (int a = 0; a < 3; ++a) {
    if (box.lo[a] > c[a] + slack_)
      k |= 1 << a;
    else if (!(box.hi[a] < c[a] - slack_))
      return false;
  }
  only = want >> k & 1 ? k : -1;
  return true;
}

bool CellBoxes::all_inside(const ListBox& box, const CellBox& b) const {
  // tri_inside_box(b) for every triangle of the list: its test bounds each corner's offset
  // from the centre, and the rounded offsets of the corners lie between those of the bounds.
  float m;
  if (!inside_margin(b.h, slack_, m)) return false;
  const float c[3] = {b.c.x, b.c.y, b.c.z};
  for (int a = 0; a < 3; ++a)
    if (!(std::fabs(box.lo[a] - c[a]) <= m && std::fabs(box.hi[a] - c[a]) <= m)) return false;
  return true;
}

void CellBoxes::split_maybe_parallel(bool parallel, std::span<const uint32_t> in, const CellBox& b,
                                     const CellBox kids[8], Split& out, uint32_t want) const {
  if (!parallel || in.size() < 2 * kChunk) {
    split(in, b, kids, out, want);
    return;
  }
  const size_t chunks = (in.size() + kChunk - 1) / kChunk;
  std::vector<Split> part(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t i) {
    const size_t lo = i * kChunk, hi = std::min(in.size(), lo + kChunk);
    split(in.subspan(lo, hi - lo), b, kids, part[i], want);
  });
  for (int c = 0; c < 8; ++c) {
    out[size_t(c)].clear();
    for (const Split& p : part)
      out[size_t(c)].insert(out[size_t(c)].end(), p[size_t(c)].begin(), p[size_t(c)].end());
  }
}

void CellBoxes::full_tris(const Region& rg, const CellBox& b, std::span<const uint32_t> region_tris,
                          std::vector<uint32_t>& out) const {
  if (rg.everything) {
    out.assign(region_tris.begin(), region_tris.end());
    return;
  }
  out.clear();
  const float c[3] = {b.c.x, b.c.y, b.c.z};
  s_.triangles_in_box(c, b.h, slack_, out);
}

namespace {

// A new leaf's colour on a side from its parent's: the parent's sample of the side its tag gives
// triangle t, or the background.
Rgba8 inherit(const PaintSurface& s, const LeafCell* parent, Rgba8 background, uint32_t t) {
  if (!parent) return background;
  if (s.side(parent->tag, t) == 0) return parent->s[0];
  return parent->dbl ? parent->s[1] : background;
}

}  // namespace

LeafCell CellBoxes::leaf_of(uint32_t first, uint32_t back, const LeafCell* parent) const {
  LeafCell cell;
  cell.tag = uint8_t(s_.tag(first));
  cell.s[0] = inherit(s_, parent, background_, first);
  if (back != ~0u) cell.dbl = true, cell.s[1] = inherit(s_, parent, background_, back);
  return cell;
}

LeafCell CellBoxes::make_leaf(std::span<const uint32_t> tris, const LeafCell* parent) const {
  const int tag = s_.tag(tris[0]);
  for (uint32_t t : tris)
    if (s_.side(tag, t) == 1) return leaf_of(tris[0], t, parent);
  return leaf_of(tris[0], ~0u, parent);
}

bool CellBoxes::leaf_from_candidates(std::span<const uint32_t> candidates, const CellBox& cb,
                                     const LeafCell* parent, LeafCell& out) const {
  auto meets_cell = [&](uint32_t t) {
    return tri_meets_box(cb.c, cb.h, v3(s_.corner(t, 0)), v3(s_.corner(t, 1)), v3(s_.corner(t, 2)),
                         slack_);
  };
  // make_leaf reads the list's first triangle and its first on side 1 of that one's tag: the
  // lowest indices meeting the cell.
  uint32_t first = ~0u;
  for (uint32_t t : candidates)
    if (t < first && meets_cell(t)) first = t;
  if (first == ~0u) return false;
  const int tag = s_.tag(first);
  uint32_t back = ~0u;
  for (uint32_t t : candidates)
    if (t < back && s_.side(tag, t) == 1 && meets_cell(t)) back = t;
  out = leaf_of(first, back, parent);
  return true;
}

void CellBoxes::leaf_lists(std::span<const uint32_t> in, std::span<const uint64_t> masks,
                           LeafLists& out) {
  // Counted, then placed: each leaf's triangles in list order, one pass over the bits each.
  uint32_t n[64] = {};
  for (uint64_t m : masks)
    for (; m; m &= m - 1) ++n[std::countr_zero(m)];
  uint32_t at = 0;
  for (int k = 0; k < 64; ++k) out.start[k] = at, at += n[k];
  out.start[64] = at;
  out.tris.resize(at);
  uint32_t pos[64];
  std::copy_n(out.start, 64, pos);
  for (size_t i = 0; i < in.size(); ++i)
    for (uint64_t m = masks[i]; m; m &= m - 1) out.tris[pos[std::countr_zero(m)]++] = in[i];
}

}  // namespace limn::detail
