// Lazy refinement: a leaf is split only where the region needs more resolution and only into the
// cells its box shares with the surface (exact box-triangle tests on triangles the Embree BVH
// returns for the box), so memory follows the painted detail and nothing else.
#include "refine.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include <limits>
#include <mutex>
#include <stdexcept>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/cpu.hpp"
#include "surface_impl.hpp"

namespace limn::detail {

using namespace paint_detail;

Refiner::Refiner(OctreeTexture& t, const PaintSurface& s) : ed_(t), s_(s) {
  // Boxes grow by 2^-22 of the cube: a triangle lying on a cell face belongs to both cells, so a
  // point on the surface always lands in a cell that holds it.
  slack_ = t.size() * float(1.0 / double(1u << 22));
  for (int l = 0; l <= octree::kMaxDepth; ++l)
    scale_[size_t(l)] = double(t.size()) / double(1u << l);
  for (int k = 0; k < 3; ++k) origin_[k] = double(t.origin()[k]);
}

bool Refiner::meets(const CellBox& b) const {
  if (region_.everything) return true;
  const float d[3] = {std::max(std::fabs(region_.c.x - b.c.x) - b.h, 0.0f),
                      std::max(std::fabs(region_.c.y - b.c.y) - b.h, 0.0f),
                      std::max(std::fabs(region_.c.z - b.c.z) - b.h, 0.0f)};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= region_.r * region_.r;
}

bool Refiner::within(const CellBox& b) const {
  if (region_.everything) return true;
  const float d[3] = {std::fabs(region_.c.x - b.c.x) + b.h, std::fabs(region_.c.y - b.c.y) + b.h,
                      std::fabs(region_.c.z - b.c.z) + b.h};
  // The margin (2^-8 of r^2) is far above the few units of rounding in either test, whose terms
  // are all on the scale of r, so meets() is true for every cell inside b.
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= region_.r * region_.r * (1.0f - 1.0f / 256);
}

void Refiner::filter(std::span<const uint32_t> in, const CellBox& b,
                     std::vector<uint32_t>& out) const {
  out.clear();
  for (uint32_t t : in) {
    const V3 p0 = v3(s_.corner(t, 0)), p1 = v3(s_.corner(t, 1)), p2 = v3(s_.corner(t, 2));
    if (tri_meets_box(b.c, b.h, p0, p1, p2, slack_)) out.push_back(t);
  }
}

namespace {

// Refiner::split's loop: a triangle is tested only when its bounding box reaches several
// children, against all of them at once.
__attribute__((always_inline)) inline void split_loop(const PaintSurface& s,
                                                      std::span<const uint32_t> in, V3 c,
                                                      const float* kx, const float* ky,
                                                      const float* kz, float kh, float slack,
                                                      uint32_t want, Refiner::Split& out) {
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
                     Refiner::Split& out) {
  split_loop(s, in, c, kx, ky, kz, kh, slack, want, out);
}

void split_loop_generic(const PaintSurface& s, std::span<const uint32_t> in, V3 c, const float* kx,
                        const float* ky, const float* kz, float kh, float slack, uint32_t want,
                        Refiner::Split& out) {
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
        if (mask >> Refiner::leaf_index(m, a) & 1) r[size_t(a)][size_t(mask)] |= uint64_t(1) << m;
  return r;
}();

// Refiner::leaf_masks's loop. off[a][i]: the offset from the brick's centre of the centres of
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

void Refiner::leaf_masks(std::span<const uint32_t> in, const CellBox& bb, const BrickLeaves& l,
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

uint64_t Refiner::meeting_leaves(const CellBox& bb, const BrickLeaves& l) const {
  if (region_.everything) return ~uint64_t(0);
  CellBox k1[8];
  children(bb, k1);
  const uint32_t want1 = meeting(k1);
  // meets()'s terms per axis and leaf index.
  const float rc[3] = {region_.c.x, region_.c.y, region_.c.z};
  float dd[3][4];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 4; ++k) {
      const float d = std::max(std::fabs(rc[a] - l.c[a][k]) - l.h, 0.0f);
      dd[a][k] = d * d;
    }
  const float r2 = region_.r * region_.r;
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

uint32_t Refiner::meeting(const CellBox kids[8]) const {
  if (region_.everything) return 0xffu;
  uint32_t m = 0;
  for (int c = 0; c < 8; ++c) m |= uint32_t(meets(kids[c])) << c;
  return m;
}

void Refiner::split(std::span<const uint32_t> in, const CellBox& b, Split& out,
                    uint32_t want) const {
  CellBox kids[8];
  children(b, kids);
  split(in, b, kids, out, want);
}

void Refiner::split(std::span<const uint32_t> in, const CellBox& b, const CellBox kids[8],
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

bool Refiner::whole_list_in_one(const ListBox& box, const CellBox& nb, uint32_t want,
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

bool Refiner::all_inside(const ListBox& box, const CellBox& b) const {
  // tri_inside_box(b) for every triangle of the list: its test bounds each corner's offset
  // from the centre, and the rounded offsets of the corners lie between those of the bounds.
  float m;
  if (!inside_margin(b.h, slack_, m)) return false;
  const float c[3] = {b.c.x, b.c.y, b.c.z};
  for (int a = 0; a < 3; ++a)
    if (!(std::fabs(box.lo[a] - c[a]) <= m && std::fabs(box.hi[a] - c[a]) <= m)) return false;
  return true;
}

void Refiner::split_maybe_parallel(const Ctx& w, std::span<const uint32_t> in, const CellBox& b,
                                   const CellBox kids[8], Split& out, uint32_t want) const {
  if (!w.log || in.size() < 2 * kChunk) {
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

void Refiner::full_tris(const CellBox& b, std::span<const uint32_t> region_tris,
                        std::vector<uint32_t>& out) const {
  if (region_.everything) {
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

LeafCell Refiner::leaf_of(uint32_t first, uint32_t back, const LeafCell* parent) const {
  LeafCell cell;
  cell.tag = uint8_t(s_.tag(first));
  cell.s[0] = inherit(s_, parent, ed_.background(), first);
  if (back != ~0u) cell.dbl = true, cell.s[1] = inherit(s_, parent, ed_.background(), back);
  return cell;
}

LeafCell Refiner::make_leaf(std::span<const uint32_t> tris, const LeafCell* parent) const {
  const int tag = s_.tag(tris[0]);
  for (uint32_t t : tris)
    if (s_.side(tag, t) == 1) return leaf_of(tris[0], t, parent);
  return leaf_of(tris[0], ~0u, parent);
}

bool Refiner::leaf_from_candidates(std::span<const uint32_t> candidates, const CellBox& cb,
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

std::span<const uint32_t> Refiner::block(const Ctx& w, uint32_t ptr, uint32_t& at) const {
  if (w.log && ptr >= temp0_) {
    // Stored earlier by this task or one it waits for or has joined: ordered before this read.
    const Where& at_log = where_[ptr - temp0_];
    if (!at_log.log) throw std::logic_error("octree refiner: a temporary address not logged");
    const Log::Op& op = at_log.log->ops[at_log.op];
    at = 0;
    return std::span<const uint32_t>(at_log.log->words).subspan(op.off, op.n);
  }
  at = ptr;
  return ed_.pool();
}

Rgba8 Refiner::child_avg(const Ctx& w, const GeneralNode& n, int c) const {
  uint32_t at = 0;
  if (n.kind[c] == CellKind::general)
    return block(w, n.ptr[c], at)[at + 2 * uint32_t(popc(octree::generals(n.info[c]))) +
                                  uint32_t(popc(octree::bricks(n.info[c])))];
  if (n.kind[c] == CellKind::brick) {
    const uint32_t word = n.ptr[c];
    return block(w, word & ~octree::kBrickDoubleFlag,
                 at)[at + 2 + ((word & octree::kBrickDoubleFlag) ? 2 : 0)];
  }
  return 0;
}

Rgba8 Refiner::general_avg(const Ctx& w, const GeneralNode& n) const {
  ColorMean m;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::leaf) add_leaf(m, n.leaf[c]);
    if (n.kind[c] == CellKind::general || n.kind[c] == CellKind::brick) m.add(child_avg(w, n, c));
  }
  return m.mean();
}

Rgba8 Refiner::brick_avg(const Brick& b) {
  return brick_average(b);
}

uint32_t Refiner::put_block(Ctx& w, uint32_t old_ptr, uint32_t old_n, bool brick, int generals,
                            int bricks) {
  if (!w.log) return ed_.replace_block(old_ptr, old_n, w.words, brick);
  Log& log = *w.log;
  Log::Op op;
  op.kind = Log::kStore, op.brick = brick;
  op.generals = uint8_t(generals), op.bricks = uint8_t(bricks);
  op.ptr = old_ptr, op.old_n = old_n;
  op.off = uint32_t(log.words.size()), op.n = uint32_t(w.words.size());
  log.words.insert(log.words.end(), w.words.begin(), w.words.end());
  // The slot's index is the address: each slot written once, whole, by the thread whose log
  // took it.
  if (log.next == log.end) {
    const auto first = where_.grow_by(kTempChunk);
    log.next = uint32_t(first - where_.begin()), log.end = log.next + kTempChunk;
  }
  const uint32_t slot = log.next++;
  where_[slot] = {&log, uint32_t(log.ops.size())};
  op.temp = temp0_ + slot;
  log.ops.push_back(op);
  return op.temp;
}

void Refiner::release(Ctx& w, uint32_t ptr, uint32_t n, bool brick) {
  if (!w.log) return ed_.release(ptr, n, brick);
  Log::Op op{};
  op.kind = Log::kRelease, op.brick = brick, op.ptr = ptr, op.old_n = n;
  w.log->ops.push_back(op);
}

void Refiner::replay(Log& log) {
  for (const Log::Op& op : log.ops) {
    if (op.kind == Log::kChild) {
      replay(*log.children[op.off]);
      continue;
    }
    if (op.kind == Log::kRelease) {
      ed_.release(resolve(op.ptr), op.old_n, op.brick);
      continue;
    }
    const std::span<uint32_t> words = std::span<uint32_t>(log.words).subspan(op.off, op.n);
    for (uint32_t k = 0; k < op.generals; ++k) words[2 * k] = resolve(words[2 * k]);
    for (uint32_t k = 0; k < op.bricks; ++k)
      words[2 * op.generals + k] = resolve_brick(words[2 * op.generals + k]);
    real_[op.temp - temp0_] = ed_.replace_block(resolve(op.ptr), op.old_n, words, op.brick);
  }
}

void Refiner::store_general(Ctx& w, const GeneralNode& n, uint32_t old_ptr, uint32_t old_info,
                            uint32_t& ptr, uint32_t& info) {
  info = encode_general(n, w.words);
  const uint32_t old_n = old_ptr ? general_block_words(old_info) : 0;
  ptr =
      put_block(w, old_ptr, old_n, false, popc(octree::generals(info)), popc(octree::bricks(info)));
}

uint32_t Refiner::store_brick(Ctx& w, const Brick& b, uint32_t old_word, const Brick* old) {
  const uint32_t flag = encode_brick(b, w.words);
  const uint32_t old_ptr = old_word & ~octree::kBrickDoubleFlag;
  const uint32_t old_n = old ? brick_block_words(old->mask, old->dbl) : 0;
  return put_block(w, old_ptr, old_n, true, 0, 0) | flag;
}

GeneralNode Refiner::refine_leaf(Ctx& w, const CellBox& cb, const LeafCell& leaf,
                                 const std::vector<uint32_t>* full_list) {
  GeneralNode g;
  Split& parts = w.scratch[size_t(cb.level)].full_parts;
  CellBox kids[8];
  children(cb, kids);
  bool off_region[8] = {};
  LeafCell off_leaf[8];
  if (!full_list) {
    // Each child's list from the BVH (at once on the threads with a log): the lists splitting
    // the cell's own would give, without querying it first. A child off the region
    // (visit_general will not visit it) needs only its leaf, found from the query's candidates.
    auto query = [&](int c) {
      const float kc[3] = {kids[c].c.x, kids[c].c.y, kids[c].c.z};
      std::vector<uint32_t>& out = parts[size_t(c)];
      out.clear();
      if (meets(kids[c])) {
        s_.triangles_in_box(kc, kids[c].h, slack_, out);
        return;
      }
      s_.box_candidates(kc, kids[c].h, slack_, out);
      off_region[c] = leaf_from_candidates(out, kids[c], &leaf, off_leaf[c]);
      out.clear();
    };
    if (w.log)
      tbb::parallel_for(0, 8, query);
    else
      for (int c = 0; c < 8; ++c) query(c);
  } else {
    split_maybe_parallel(w, *full_list, cb, kids, parts);
  }
  for (int c = 0; c < 8; ++c) {
    const std::vector<uint32_t>& fc = parts[size_t(c)];
    if (fc.empty() && !off_region[c]) continue;
    g.kind[c] = CellKind::leaf;
    g.leaf[c] = off_region[c] ? off_leaf[c] : make_leaf(fc, &leaf);
    ++w.stats.leaves_created;
  }
  ++w.stats.generals_created;
  return g;
}

namespace {

// The elements of sorted `a` that sorted `b` holds, in order.
void intersect_sorted(std::span<const uint32_t> a, std::span<const uint32_t> b,
                      std::vector<uint32_t>& out) {
  out.clear();
  size_t j = 0;
  for (uint32_t v : a) {
    while (j < b.size() && b[j] < v) ++j;
    if (j == b.size()) break;
    if (b[j] == v) out.push_back(v);
  }
}

}  // namespace

void Refiner::leaf_lists(std::span<const uint32_t> in, std::span<const uint64_t> masks,
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

bool Refiner::build_brick(Ctx& w, const CellBox& cb, const LeafCell& leaf,
                          std::span<const uint32_t> full, std::span<const uint32_t> tris,
                          Brick& b) {
  b = Brick{};
  std::vector<uint64_t>& masks = w.masks;
  const BrickLeaves l = brick_leaves(cb);
  leaf_masks(full, cb, l, ~uint64_t(0), masks);
  // Each leaf's first triangle and first on side 1 of that one's tag: what make_leaf reads of
  // its list, found in one pass over the list.
  uint32_t first[64], back[64];
  uint64_t any = 0, open = 0;  // open: leaves with a first triangle and no back one yet
  for (size_t i = 0; i < full.size(); ++i) {
    const uint32_t t = full[i];
    const uint64_t fresh = masks[i] & ~any;
    for (uint64_t m = fresh; m; m &= m - 1) first[std::countr_zero(m)] = t;
    for (uint64_t m = masks[i] & open; m; m &= m - 1) {
      const int k = std::countr_zero(m);
      if (s_.side(s_.tag(first[k]), t) == 1) back[k] = t, open &= ~(uint64_t(1) << k);
    }
    any |= fresh, open |= fresh;
  }
  for (uint64_t left = any; left; left &= left - 1) {
    const int m = std::countr_zero(left);
    b.cell[m] = leaf_of(first[m], open >> m & 1 ? ~0u : back[m], &leaf);
    ++w.stats.leaves_created;
  }
  b.mask = any;
  ++w.stats.bricks_created;  // counted as before, even when no sub-cell meets the surface
  if (b.mask == 0) return false;
  if (w.painter) {
    // tris is a subset of full (both sorted): a leaf's region list is its full list less the
    // triangles outside tris.
    const uint64_t want = any & (within(cb) ? ~uint64_t(0) : meeting_leaves(cb, l));
    size_t j = 0;
    for (size_t i = 0; i < full.size(); ++i) {
      while (j < tris.size() && tris[j] < full[i]) ++j;
      masks[i] &= j < tris.size() && tris[j] == full[i] ? want : 0;
    }
    LeafLists& ll = w.lists;
    leaf_lists(full, masks, ll);
    for (uint64_t left = want; left; left &= left - 1) {
      const int m = std::countr_zero(left);
      if (ll.start[m] == ll.start[m + 1]) continue;
      w.painter->paint(leaf_box(l, m), b.cell[m], ll.list(m), LeafPainter::kNoMemo),
          ++w.stats.leaves_painted;
    }
  }
  return true;
}

GeneralNode Refiner::explode(Ctx& w, const Brick& b, const CellBox&) {
  GeneralNode g;
  for (int c1 = 0; c1 < 8; ++c1) {
    const uint32_t byte = uint32_t(b.mask >> (8 * c1)) & 255u;
    if (!byte) continue;
    GeneralNode child;
    for (int c2 = 0; c2 < 8; ++c2)
      if (byte >> c2 & 1) child.kind[c2] = CellKind::leaf, child.leaf[c2] = b.cell[8 * c1 + c2];
    child.avg = general_avg(w, child);
    store_general(w, child, 0, 0, g.ptr[c1], g.info[c1]);
    g.kind[c1] = CellKind::general;
  }
  g.avg = b.avg;
  ++w.stats.bricks_exploded;
  return g;
}

bool Refiner::try_compact(const Ctx& w, const GeneralNode& n, Brick& out) const {
  bool any = false;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::empty) continue;
    if (n.kind[c] != CellKind::general) return false;
    if (octree::leaves(n.info[c]) != octree::occupied(n.info[c])) return false;
    any = true;
  }
  if (!any) return false;
  out = Brick{};
  for (int c1 = 0; c1 < 8; ++c1) {
    if (n.kind[c1] != CellKind::general) continue;
    uint32_t at = 0;
    const std::span<const uint32_t> words = block(w, n.ptr[c1], at);
    const GeneralNode child = decode_general(words, at, n.info[c1]);
    for (int c2 = 0; c2 < 8; ++c2)
      if (child.kind[c2] == CellKind::leaf) {
        out.mask |= uint64_t(1) << (8 * c1 + c2);
        out.cell[8 * c1 + c2] = child.leaf[c2];
      }
  }
  out.avg = brick_avg(out);
  return true;
}

namespace {

// Whether two bricks hold the same cells (what encode_brick stores, less the average).
bool same_cells(const Brick& a, const Brick& b) {
  if (a.mask != b.mask || a.dbl != b.dbl) return false;
  for (uint64_t m = a.mask; m; m &= m - 1) {
    const LeafCell &x = a.cell[std::countr_zero(m)], &y = b.cell[std::countr_zero(m)];
    if (x.tag != y.tag || x.dbl != y.dbl || x.s[0] != y.s[0] || x.s[1] != y.s[1]) return false;
  }
  return true;
}

}  // namespace

void Refiner::visit_brick(Ctx& w, Brick& b, const CellBox& bb, std::span<const uint32_t> tris) {
  // Only leaves meeting the region are visited: only they are tested. Most bricks of a dab lie
  // inside its ball: then all their cells meet it.
  const BrickLeaves l = brick_leaves(bb);
  const uint64_t want = within(bb) ? ~uint64_t(0) : meeting_leaves(bb, l);
  KeptBrick* kept = nullptr;
  uint32_t memo0 = LeafPainter::kNoMemo;  // memo of leaf m: memo0 + m
  auto visit_leaf = [&](int m, std::span<const uint32_t> t2) {
    if (!(b.mask >> m & 1)) {
      // A surface cell the brick lacks: the texture was made for another mesh.
      b.mask |= uint64_t(1) << m;
      b.cell[m] = make_leaf(t2, nullptr);
      ++w.stats.leaves_created;
    }
    const uint32_t memo = memo0 == LeafPainter::kNoMemo ? memo0 : memo0 + uint32_t(m);
    if (w.painter) w.painter->paint(leaf_box(l, m), b.cell[m], t2, memo), ++w.stats.leaves_painted;
  };
  if (keep_) {
    const uint64_t key = morton3(bb.x, bb.y, bb.z) | uint64_t(bb.level) << 48;
    Kept& k = *w.kept;
    const auto [it, added] = k.index.try_emplace(key, uint32_t(k.bricks.size()));
    if (added) k.bricks.emplace_back();
    kept = &k.bricks[it->second];
    if (it->second < (1u << 25)) memo0 = 64 * it->second;
    if (!(want & ~kept->known)) {
      // Every leaf wanted has its list from an earlier run: the same visits, no tests.
      for (uint64_t left = want; left; left &= left - 1) {
        const int m = std::countr_zero(left);
        if (kept->len[m])
          visit_leaf(m,
                     std::span<const uint32_t>(w.kept->tris.data() + kept->off[m], kept->len[m]));
      }
      return;
    }
  }
  std::vector<uint64_t>& masks = w.masks;
  leaf_masks(tris, bb, l, want, masks);
  uint64_t any = 0;
  for (uint64_t m : masks) any |= m;
  if (kept) {
    for (uint64_t left = want & ~any; left; left &= left - 1) kept->len[std::countr_zero(left)] = 0;
    kept->known |= want;
  }
  LeafLists& ll = w.lists;
  leaf_lists(tris, masks, ll);
  for (uint64_t left = any; left; left &= left - 1) {
    const int m = std::countr_zero(left);
    const std::span<const uint32_t> list = ll.list(m);
    if (kept) {
      std::vector<uint32_t>& kt = w.kept->tris;
      kept->off[m] = uint32_t(kt.size()), kept->len[m] = uint32_t(list.size());
      kt.insert(kt.end(), list.begin(), list.end());
    }
    visit_leaf(m, list);
  }
}

void Refiner::visit_general(Ctx& w, GeneralNode& n, const CellBox& nb,
                            std::span<const uint32_t> tris,
                            const std::vector<uint32_t>* parent_full, const ListBox* box) {
  CellBox kids[8];
  children(nb, kids);
  const uint32_t want = meeting(kids);
  Scratch& sc = w.scratch[size_t(nb.level)];
  Split &parts = sc.parts, &full_parts = sc.full_parts;
  // Just refined: full_parts holds parent_full split by child, and tris (a subset of
  // parent_full, both sorted) splits into the same lists less the triangles it lacks.
  const bool full_split = parent_full != nullptr;
  const bool same = full_split && tris.size() == parent_full->size();
  // Near the root a dab's list often lies in one child whole: it goes there untested, with its
  // bounds (the lists split() would make).
  int only = -1;
  const bool whole = !full_split && box && whole_list_in_one(*box, nb, want, only);
  if (whole) {
    for (int c = 0; c < 8; ++c) parts[size_t(c)].clear();
    if (only >= 0) parts[size_t(only)].assign(tris.begin(), tris.end());
  } else if (!full_split) {
    split_maybe_parallel(w, tris, nb, kids, parts, want);
  } else if (!same) {
    for (int c = 0; c < 8; ++c) intersect_sorted(full_parts[size_t(c)], tris, parts[size_t(c)]);
  }
  const Split& tparts = same ? full_parts : parts;
  uint32_t todo = 0;
  for (int c = 0; c < 8; ++c)
    if (!tparts[size_t(c)].empty() && (want >> c & 1)) todo |= 1u << c;
  if (tasks_ && nb.level <= depth_ - kTaskDepth - 1) {
    visit_parts(w, n, kids, todo, tparts, full_split ? &full_parts : nullptr,
                nb.level == depth_ - kTaskDepth - 1, whole ? box : nullptr);
  } else {
    for (int c = 0; c < 8; ++c)
      if (todo >> c & 1)
        visit_child(w, n, c, kids[c], tparts[size_t(c)],
                    full_split ? &full_parts[size_t(c)] : nullptr, whole ? box : nullptr);
  }
  finish_bricks(w);
  if (w.painter) w.painter->flush();
  n.avg = general_avg(w, n);
}

void Refiner::finish_bricks(Ctx& w) {
  if (!w.pending) return;
  if (w.painter) w.painter->flush();
  for (int i = 0; i < w.pending; ++i) {
    PendingBrick& p = w.bricks[size_t(i)];
    GeneralNode& n = *p.n;
    if (p.fresh) {
      p.b.avg = brick_avg(p.b);
      n.kind[p.c] = CellKind::brick;
      n.ptr[p.c] = store_brick(w, p.b, 0, nullptr);
    } else if (!same_cells(p.before, p.b)) {
      // A brick the visit left as it was (its texels already as strong from an earlier dab of
      // the stroke, or out of the brush's reach) is not averaged, encoded and written again:
      // the same words would come out.
      p.b.avg = brick_avg(p.b);
      n.ptr[p.c] = store_brick(w, p.b, n.ptr[p.c], &p.before);
    }
  }
  w.pending = 0;
}

Refiner::Shard& Refiner::shard(uint64_t key) {
  std::lock_guard<std::mutex> lock(shard_mutex_);
  std::unique_ptr<Shard>& s = shards_[key];
  if (!s) s = std::make_unique<Shard>(), s->painter = painter_->shard(key);
  return *s;
}

namespace {

void add(RefineStats& to, const RefineStats& a) {
  to.leaves_created += a.leaves_created, to.bricks_created += a.bricks_created;
  to.generals_created += a.generals_created, to.bricks_exploded += a.bricks_exploded;
  to.bricks_compacted += a.bricks_compacted, to.leaves_painted += a.leaves_painted;
  to.tasks += a.tasks, to.tasks_threaded += a.tasks_threaded;
}

}  // namespace

// Never destroyed: a refiner that outlives main() (a painter in a static) still gives back.
SharedPool<Refiner::Ctx>& Refiner::ctx_pool() {
  static SharedPool<Ctx>& pool = *new SharedPool<Ctx>;
  return pool;
}

SharedPool<Refiner::Log>& Refiner::log_pool() {
  static SharedPool<Log>& pool = *new SharedPool<Log>;
  return pool;
}

Refiner::Ctx& Refiner::take_ctx() {
  return ctx_pool().take();
}
void Refiner::put_ctx(Ctx& w) {
  ctx_pool().put(w);
}
Refiner::Log& Refiner::take_log() {
  return log_pool().take();
}
void Refiner::put_log(Log& l) {
  log_pool().put(l);
}

void Refiner::visit_parts(Ctx& w, GeneralNode& n, const CellBox kids[8], uint32_t todo,
                          const Split& tparts, const Split* full_parts, bool task_cells,
                          const ListBox* box) {
  int cs[8], count = 0;
  Shard* sh[8] = {};
  for (int c = 0; c < 8; ++c) {
    if (!(todo >> c & 1)) continue;
    if (task_cells && painter_) {
      const CellBox& cb = kids[c];
      sh[count] = &shard(morton3(cb.x, cb.y, cb.z) | uint64_t(cb.level) << 48);
    }
    cs[count++] = c;
  }
  if (task_cells) w.stats.tasks += size_t(count);
  auto visit = [&](Ctx& x, int i) {
    const int c = cs[i];
    visit_child(x, n, c, kids[c], tparts[size_t(c)],
                full_parts ? &(*full_parts)[size_t(c)] : nullptr, box);
  };
  if (!w.log || count < 2) {
    // One thread: the same visits in order, each task cell through its shard.
    LeafPainter* const painter = w.painter;
    Kept* const kept = w.kept;
    for (int i = 0; i < count; ++i) {
      if (sh[i]) w.painter = sh[i]->painter, w.kept = &sh[i]->kept;
      visit(w, i);
      finish_bricks(w);  // through this child's painter
    }
    w.painter = painter, w.kept = kept;
    return;
  }
  if (task_cells) w.stats.tasks_threaded += size_t(count);
  // Each child with a context and log of its own (a thread waiting for its children may run
  // other tasks meanwhile, so contexts are not per thread); logs merged in child order, so
  // the writes come out in the order one thread makes them.
  Log* logs[8];
  {
    std::lock_guard<std::mutex> lock(logs_mutex_);
    for (int i = 0; i < count; ++i)
      logs[i] = &take_log(), logs[i]->clear(), taken_logs_.push_back(logs[i]);
  }
  tbb::parallel_for(
      tbb::blocked_range<int>(0, count, 1),
      [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i < r.end(); ++i) {
          Ctx& x = take_ctx();
          x.log = logs[i];
          x.painter = sh[i] ? sh[i]->painter : nullptr;
          x.kept = sh[i] ? &sh[i]->kept : &kept_;
          visit(x, i);
          finish_bricks(x);
          {
            std::lock_guard<std::mutex> lock(stats_mutex_);
            add(task_stats_, x.stats);
          }
          x.stats = {}, x.log = nullptr, x.painter = nullptr, x.kept = nullptr;
          put_ctx(x);
        }
      },
      tbb::simple_partitioner());
  // Each child's writes where one thread would make them: after what w wrote before the join.
  for (int i = 0; i < count; ++i) {
    Log::Op op{};
    op.kind = Log::kChild, op.off = uint32_t(w.log->children.size());
    w.log->children.push_back(logs[i]);
    w.log->ops.push_back(op);
  }
}

void Refiner::visit_child(Ctx& w, GeneralNode& n, int c, const CellBox& cb,
                          std::span<const uint32_t> tc, const std::vector<uint32_t>* full_c,
                          const ListBox* box_c) {
  const int level = cb.level;
  std::vector<uint32_t>& full = w.scratch[size_t(level - 1)].full;
  // The child's full list, from its parent's when known (no BVH query, and no triangles from
  // outside the parent's box to test).
  auto child_full = [&] {
    if (full_c) {
      full = *full_c;
    } else {
      full_tris(cb, tc, full);
    }
  };
  if (n.kind[c] == CellKind::empty) {
    child_full();
    if (full.empty()) return;
    n.kind[c] = CellKind::leaf;
    n.leaf[c] = make_leaf(full, nullptr);
    ++w.stats.leaves_created;
  }
  switch (n.kind[c]) {
    case CellKind::leaf: {
      if (level >= depth_) {
        if (w.painter)
          w.painter->paint(cb, n.leaf[c], tc, LeafPainter::kNoMemo), ++w.stats.leaves_painted;
        break;
      }
      // A leaf with no list at hand (made by an earlier run) that becomes a general node takes
      // its children's lists straight from the BVH, instead of its own list queried and then
      // split; its own list then stays empty, so visit_general sees it as not `same`. A start
      // cell's list is at hand in the surface's table.
      bool queried = !full_c && level < depth_ - 2 && !region_.everything;
      if (queried && level == octree::kStartDepth) {
        const std::span<const uint32_t> kept = start_list(cb.x, cb.y, cb.z);
        full.assign(kept.begin(), kept.end());
        queried = false;
      } else if (queried) {
        full.clear();
      } else {
        child_full();
      }
      // A cell the surface only grazes within the boxes' slack may have no sub-cell the surface
      // meets once rounded: it stays a leaf.
      if (level == depth_ - 2) {
        PendingBrick& p = w.bricks[w.pending];
        if (!build_brick(w, cb, n.leaf[c], full, tc, p.b)) break;
        p.n = &n, p.c = c, p.fresh = true;
        ++w.pending;
      } else {
        GeneralNode g = refine_leaf(w, cb, n.leaf[c], queried ? nullptr : &full);
        bool any = false;
        for (int k = 0; k < 8; ++k) any |= g.kind[k] != CellKind::empty;
        if (!any) break;
        visit_general(w, g, cb, tc, &full);
        n.kind[c] = CellKind::general;
        store_general(w, g, 0, 0, n.ptr[c], n.info[c]);
      }
      break;
    }
    case CellKind::general: {
      finish_bricks(w);  // their stores first, in child order
      // From the log when just stored by this task (an exploded brick's children).
      uint32_t at = 0;
      const std::span<const uint32_t> words = block(w, n.ptr[c], at);
      GeneralNode g = decode_general(words, at, n.info[c]);
      visit_general(w, g, cb, tc, nullptr, box_c);
      Brick b;
      if (try_compact(w, g, b)) {
        for (int k = 0; k < 8; ++k)
          if (g.kind[k] == CellKind::general)
            release(w, g.ptr[k], general_block_words(g.info[k]), false);
        release(w, n.ptr[c], general_block_words(n.info[c]), false);
        n.kind[c] = CellKind::brick;
        n.ptr[c] = store_brick(w, b, 0, nullptr);
        ++w.stats.bricks_compacted;
      } else {
        store_general(w, g, n.ptr[c], n.info[c], n.ptr[c], n.info[c]);
      }
      break;
    }
    case CellKind::brick: {
      uint32_t at = 0;
      const std::span<const uint32_t> words = block(w, n.ptr[c] & ~octree::kBrickDoubleFlag, at);
      Brick b = decode_brick(words, at | (n.ptr[c] & octree::kBrickDoubleFlag));
      if (level + 2 < depth_) {
        finish_bricks(w);  // their stores first, in child order
        const uint32_t old_ptr = n.ptr[c] & ~octree::kBrickDoubleFlag;
        GeneralNode g = explode(w, b, cb);
        release(w, old_ptr, brick_block_words(b.mask, b.dbl), true);
        visit_general(w, g, cb, tc);
        n.kind[c] = CellKind::general;
        store_general(w, g, 0, 0, n.ptr[c], n.info[c]);
      } else {
        PendingBrick& p = w.bricks[w.pending++];
        p.n = &n, p.c = c, p.fresh = false;
        p.b = b, p.before = b;
        visit_brick(w, p.b, cb, tc);
      }
      break;
    }
    case CellKind::empty:
      break;
  }
}

struct Refiner::StartLists {
  double origin[3], size;
  std::vector<uint32_t> start;  // per cell (x + n (y + n z)), its list's first index in tris
  std::vector<uint32_t> tris;
};

std::shared_ptr<const Refiner::StartLists> Refiner::start_lists() const {
  if (start_) return start_;
  const double size = double(ed_.texture().size());
  {
    std::lock_guard<std::mutex> lock(s_.impl().derived_mutex);
    auto kept = std::static_pointer_cast<const StartLists>(s_.impl().derived);
    if (kept && kept->size == size && kept->origin[0] == origin_[0] &&
        kept->origin[1] == origin_[1] && kept->origin[2] == origin_[2])
      return kept;
  }
  // Each triangle against the start cells its bounds reach (grown by the slack and by the
  // rounding of the boxes' float centres), with the test triangles_in_box makes on the boxes
  // box() gives: the same lists.
  const int level = octree::kStartDepth;
  const uint32_t n = 1u << level;
  const double s = cell_size(level);
  auto lists = std::make_shared<StartLists>();
  for (int a = 0; a < 3; ++a) lists->origin[a] = origin_[a];
  lists->size = size;
  double grow[3];
  for (int a = 0; a < 3; ++a)
    grow[a] = 2 * double(slack_) +
              8 * double(std::numeric_limits<float>::epsilon()) * (std::fabs(origin_[a]) + size);
  std::vector<CellBox> boxes(size_t(n) * n * n);
  for (uint32_t z = 0; z < n; ++z)
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) boxes[x + n * (y + n * z)] = box(level, x, y, z);
  // In chunks of triangles on TBB's threads, each chunk's (cell, triangle) pairs in index order.
  constexpr uint32_t kTris = 8192;
  const uint32_t count = uint32_t(s_.triangle_count());
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> parts((count + kTris - 1) / kTris);
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t part) {
    std::vector<std::pair<uint32_t, uint32_t>>& hits = parts[part];
    for (uint32_t t = uint32_t(part) * kTris; t < std::min(count, uint32_t(part + 1) * kTris);
         ++t) {
      if (s_.degenerate(t)) continue;
      uint32_t lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        double mn = INFINITY, mx = -INFINITY;
        for (int k = 0; k < 3; ++k)
          mn = std::min(mn, double(s_.corner(t, k)[a])),
          mx = std::max(mx, double(s_.corner(t, k)[a]));
        const double l = std::floor((mn - grow[a] - origin_[a]) / s),
                     h = std::floor((mx + grow[a] - origin_[a]) / s);
        lo[a] = uint32_t(std::clamp(l, 0.0, double(n - 1)));
        hi[a] = uint32_t(std::clamp(h, 0.0, double(n - 1)));
      }
      const V3 p0 = v3(s_.corner(t, 0)), p1 = v3(s_.corner(t, 1)), p2 = v3(s_.corner(t, 2));
      for (uint32_t z = lo[2]; z <= hi[2]; ++z)
        for (uint32_t y = lo[1]; y <= hi[1]; ++y)
          for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
            const uint32_t cell = x + n * (y + n * z);
            const CellBox& b = boxes[cell];
            if (tri_meets_box(b.c, b.h, p0, p1, p2, slack_)) hits.push_back({cell, t});
          }
    }
  });
  // Counted, then placed: each cell's triangles in index order.
  lists->start.assign(size_t(n) * n * n + 1, 0);
  for (const auto& hits : parts)
    for (const auto& h : hits) ++lists->start[h.first + 1];
  for (size_t i = 1; i < lists->start.size(); ++i) lists->start[i] += lists->start[i - 1];
  lists->tris.resize(lists->start.back());
  std::vector<uint32_t> pos(lists->start.begin(), lists->start.end() - 1);
  for (const auto& hits : parts)
    for (const auto& h : hits) lists->tris[pos[h.first]++] = h.second;
  {
    std::lock_guard<std::mutex> lock(s_.impl().derived_mutex);
    s_.impl().derived = lists;
  }
  return lists;
}

std::span<const uint32_t> Refiner::start_list(uint32_t x, uint32_t y, uint32_t z) const {
  if (!start_) throw std::logic_error("octree refiner: start lists not prepared");
  const StartLists* l = start_.get();
  const uint32_t n = 1u << octree::kStartDepth;
  const size_t i = x + n * (y + size_t(n) * z);
  return std::span<const uint32_t>(l->tris).subspan(l->start[i], l->start[i + 1] - l->start[i]);
}

void Refiner::give_back_logs() {
  for (Log* l : taken_logs_) l->clear(), put_log(*l);
  taken_logs_.clear();
  where_.clear();
}

void Refiner::run(const Region& region, std::span<const uint32_t> tris, int depth,
                  LeafPainter* painter) {
  give_back_logs();  // those of a run a throw cut short
  region_ = region, depth_ = depth, painter_ = painter;
  // Start cells may be refined below (see visit_child): their lists at hand before any thread
  // asks.
  if (!region.everything && depth - 2 > octree::kStartDepth) prepare_start_lists();
  {
    // The calling thread's context, from the shared pool too: a click's refiner is made and
    // dropped per dab, and a warm context saves its lists' allocations.
    struct Taken {
      Ctx& w;
      RefineStats& into;
      std::mutex& m;
      ~Taken() {
        {
          std::lock_guard<std::mutex> lock(m);
          add(into, w.stats);
        }
        w.stats = {}, w.log = nullptr, w.painter = nullptr, w.kept = nullptr;
        put_ctx(w);
      }
    } taken{take_ctx(), task_stats_, stats_mutex_};
    Ctx& main = taken.w;
    main.painter = painter, main.kept = &kept_;
    tasks_ = false;
    if (!painter) {
      tasks_ = depth - kTaskDepth - 1 >= 0;  // refining only: no shards to keep apart
    } else if (painter->sharded()) {
      tasks_ = depth - kTaskDepth - 1 >= 0;
      if (tasks_) {
        main.painter = nullptr;  // every cell painted lies under a task cell
      } else {
        // Too shallow for tasks: one shard for everything.
        Shard& s = shard(~uint64_t(0));
        main.painter = s.painter, main.kept = &s.kept;
      }
    }
    const uint32_t ptr = ed_.word(0), info = ed_.word(1);
    GeneralNode root =
        octree::occupied(info) ? decode_general(ed_.pool(), ptr, info) : GeneralNode{};
    const CellBox rb = box(0, 0, 0, 0);
    // The triangles meeting the root's box: all of them when their corners' bounds lie inside
    // it (the texture was made for this mesh), and those bounds let the visit skip splits.
    ListBox tbox = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (uint32_t t : tris)
      for (int v = 0; v < 3; ++v)
        for (int a = 0; a < 3; ++a) {
          const float x = s_.corner(t, v)[a];
          tbox.lo[a] = std::min(tbox.lo[a], x), tbox.hi[a] = std::max(tbox.hi[a], x);
        }
    const bool known = !tris.empty() && all_inside(tbox, rb);
    std::vector<uint32_t> filtered;
    if (!known) filter(tris, rb, filtered);
    const std::span<const uint32_t> t0 = known ? tris : std::span<const uint32_t>(filtered);
    // On several threads every write waits in a log, replayed once the visit is over (reads of
    // the pool meanwhile see it as it was); temporary addresses need room above the pool.
    temp0_ = uint32_t(ed_.pool().size());
    const bool threads =
        tasks_ && temp0_ < octree::kMaxPoolWords / 2 &&
        tbb::this_task_arena::max_concurrency() > 1 &&
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
    main.log = threads ? &main_log_ : nullptr;
    main_log_.clear();
    if (!t0.empty()) {
      visit_general(main, root, rb, t0, nullptr, known ? &tbox : nullptr);
      bool any = false;
      for (int c = 0; c < 8; ++c) any |= root.kind[c] != CellKind::empty;
      if (any) {
        uint32_t nptr = 0, ninfo = 0;
        store_general(main, root, ptr, info, nptr, ninfo);
        if (main.log) {
          real_.assign(where_.size(), 0);
          replay(*main.log);
          nptr = resolve(nptr);
        }
        ed_.set(0, nptr);
        ed_.set(1, ninfo);
      }
    }
    main.log = nullptr;
  }
  give_back_logs();
  stats = task_stats_;
}

}  // namespace limn::detail
