// Brushes: dabs and strokes over the visible, front-facing surface; fill; eyedropper; texture
// creation (the coarse start tree).
#include "limn/paint/brush.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/timer.hpp"
#include "limn/paint/lookup.hpp"
#include "refine.hpp"

namespace limn {

using namespace detail;
using namespace paint_detail;

namespace {

bool finite_in(float v, float lo, float hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

std::vector<uint32_t> all_triangles(const PaintSurface& s) {
  std::vector<uint32_t> v;
  v.reserve(s.triangle_count());
  for (uint32_t t = 0; t < s.triangle_count(); ++t)
    if (!s.degenerate(t)) v.push_back(t);
  return v;
}

// Straight-alpha blend of `src` into `dst` at strength w in [0,1].
Rgba8 blend(Rgba8 dst, const float src[4], BlendMode mode, float w) {
  float d[4], o[4] = {0, 0, 0, 0};  // every mode sets all four
  rgba8_to_float(dst, d);
  const float a = w * src[3];
  switch (mode) {
    case BlendMode::mix: {
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[k] = o[3] > 0 ? (src[k] * a + d[k] * d[3] * (1 - a)) / o[3] : 0;
      break;
    }
    case BlendMode::add:
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[k] = std::min(1.0f, d[k] + src[k] * a);
      break;
    case BlendMode::multiply:
      for (int k = 0; k < 3; ++k) o[k] = d[k] * (1 - a + a * src[k]);
      o[3] = d[3];
      break;
    case BlendMode::erase:
      for (int k = 0; k < 3; ++k) o[k] = d[k];
      o[3] = d[3] * (1 - w);
      break;
  }
  return rgba8_from_floats(o[0], o[1], o[2], o[3]);
}

// Blends the brush's material channels into an RMH texel at strength w: each channel on starts
// from the texel's value over its default (by the texel's coverage), the others keep that
// value; the texel comes out fully covered.
Rgba8 blend_rmh(Rgba8 dst, Rgba8 background, const ChannelPaint ch[kMaterialChannels], float w) {
  float d[4], def[4], o[3];
  rgba8_to_float(dst, d);
  rgba8_to_float(background, def);
  for (int k = 0; k < kMaterialChannels; ++k) {
    float v = d[k] * d[3] + def[k] * (1 - d[3]);
    if (ch[k].on) {
      const float a = w * ch[k].opacity, s = ch[k].value;
      switch (ch[k].blend) {
        case BlendMode::mix:
          v += (s - v) * a;
          break;
        case BlendMode::add:
          v = std::min(1.0f, v + s * a);
          break;
        case BlendMode::multiply:
          v *= 1 - a + a * s;
          break;
        case BlendMode::erase:
          v += (def[k] - v) * a;
          break;
      }
    }
    o[k] = v;
  }
  return rgba8_from_floats(o[0], o[1], o[2], 1.0f);
}

inline float smooth01(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x * x * (3 - 2 * x);
}

// The texels a stroke touched, by key (never ~0): open addressing, linear probing, grown at half
// full. Values stay where they are until the next insertion.
template <class V>
class FlatMap {
 public:
  const V* find(uint64_t key) const {
    if (slots_.empty()) return nullptr;
    for (size_t i = slot(key);; i = (i + 1) & (slots_.size() - 1)) {
      if (slots_[i].key == key) return &slots_[i].val;
      if (slots_[i].key == kEmpty) return nullptr;
    }
  }
  // Room for n keys without growing.
  void reserve(size_t n) {
    if (2 * n > slots_.size()) grow(std::bit_ceil(2 * n));
  }
  V& find_or_add(uint64_t key, const V& init) {
    if (2 * (count_ + 1) > slots_.size()) grow(std::max<size_t>(32, 2 * slots_.size()));
    size_t i = slot(key);
    for (;; i = (i + 1) & (slots_.size() - 1)) {
      if (slots_[i].key == key) return slots_[i].val;
      if (slots_[i].key == kEmpty) break;
    }
    slots_[i] = {key, init}, ++count_;
    return slots_[i].val;
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  // Key and value side by side: one cache line read per probe.
  struct Slot {
    uint64_t key;
    V val;
  };
  size_t slot(uint64_t key) const {
    return size_t((key * 0x9e3779b97f4a7c15ull) >> 32) & (slots_.size() - 1);
  }
  void grow(size_t size) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(size, Slot{kEmpty, V{}});
    for (const Slot& x : old) {
      if (x.key == kEmpty) continue;
      size_t i = slot(x.key);
      while (slots_[i].key != kEmpty) i = (i + 1) & (slots_.size() - 1);
      slots_[i] = x;
    }
  }
  std::vector<Slot> slots_;
  size_t count_ = 0;
};

// The same interface for the texels of a stroke, in blocks of the 64 keys that differ only in
// their low 6 bits (the Morton code's last two levels: a brick's leaves, one side): one hash
// lookup per block, none while the lookups stay in the last block, and a brick's texels side by
// side in memory.
template <class V>
class BlockMap {
 public:
  const V* find(uint64_t key) const {
    const uint32_t b = block(key >> 6);
    if (b == kNone || !(at(b).present >> (key & 63) & 1)) return nullptr;
    return &at(b).v[key & 63];
  }
  // Room for about n keys.
  void reserve(size_t n) { index_.reserve(n / 16 + 16); }
  V& find_or_add(uint64_t key, const V& init) {
    uint32_t b = block(key >> 6);
    if (b == kNone) {
      b = count_++;
      if (b % kChunk == 0) chunks_.emplace_back(new Block[kChunk]);
      at(b).present = 0;
      index_.find_or_add(key >> 6, b);
      last_group_ = key >> 6, last_ = b;
    }
    Block& bl = at(b);
    const uint64_t bit = uint64_t(1) << (key & 63);
    if (!(bl.present & bit)) bl.present |= bit, bl.v[key & 63] = init;
    return bl.v[key & 63];
  }

 private:
  static constexpr uint32_t kNone = ~0u;
  struct Block {
    uint64_t present;
    V v[64];
  };
  // Blocks in chunks that never move: a growing stroke copies none (a task cell's texels, a
  // few dozen blocks of 0.5 KiB, were copied five times over as a vector grew).
  static constexpr uint32_t kChunk = 16;
  Block& at(uint32_t b) { return chunks_[b / kChunk][b % kChunk]; }
  const Block& at(uint32_t b) const { return chunks_[b / kChunk][b % kChunk]; }
  uint32_t block(uint64_t group) const {
    if (group == last_group_) return last_;
    const uint32_t* b = index_.find(group);
    if (!b) return kNone;
    last_group_ = group, last_ = *b;
    return *b;
  }
  FlatMap<uint32_t> index_;
  std::vector<std::unique_ptr<Block[]>> chunks_;
  uint32_t count_ = 0;
  mutable uint64_t last_group_ = ~uint64_t(0);
  mutable uint32_t last_ = kNone;
};

}  // namespace

void check_brush(const Brush& b, const char* what) {
  auto bad = [&](const char* field, const std::string& why) {
    throw InputError(std::string(what) + ": " + field + " " + why);
  };
  if (!(std::isfinite(b.radius) && b.radius > 0 && b.radius <= 1e30f))
    bad("radius", "must be a positive number");
  for (int k = 0; k < 4; ++k)
    if (!finite_in(b.color[k], 0, 1)) bad("color", "components must be numbers in [0, 1]");
  if (!finite_in(b.opacity, 0, 1)) bad("opacity", "must be a number in [0, 1]");
  if (!finite_in(b.hardness, 0, 1)) bad("hardness", "must be a number in [0, 1]");
  if (!(std::isfinite(b.spacing) && b.spacing > 0 && b.spacing <= 10))
    bad("spacing", "must be a number in (0, 10]");
  if (b.depth < 1 || b.depth > octree::kMaxDepth)
    bad("depth", "must be 1-" + std::to_string(octree::kMaxDepth));
  if (!finite_in(b.falloff_angle_deg, 0, 90)) bad("falloff angle", "must be 0-90 degrees");
  if (int(b.blend) > int(BlendMode::erase)) bad("blend", "is not a blend mode");
  for (int k = 0; k < kMaterialChannels; ++k) {
    const ChannelPaint& c = b.material[k];
    const std::string name = channel_name(MaterialChannel(k));
    if (!finite_in(c.value, 0, 1)) bad(name.c_str(), "must be a number in [0, 1]");
    if (!finite_in(c.opacity, 0, 1)) bad((name + " opacity").c_str(), "must be a number in [0, 1]");
    if (int(c.blend) > int(BlendMode::erase)) bad((name + " blend").c_str(), "is not a blend mode");
  }
}

namespace {

// A polyline walked point by point, calling f(point) every `step` of arc length from its first
// point (which gets the first call). Dab k sits at arc length k * step, computed from k (not
// accumulated), so no rounding drift drops or adds the last dab, and feeding the points one at a
// time gives the same dabs as feeding them all at once.
struct PolylineWalk {
  double step = 1;
  bool started = false;
  double last[3] = {0, 0, 0};
  double start = 0;  // arc length at the current segment's start
  uint64_t next = 1;

  template <class F>
  void to(const double* b, int dim, F&& f) {
    if (!started) {
      started = true;
      std::copy(b, b + dim, last);
      f(last);
      return;
    }
    double l2 = 0;
    for (int k = 0; k < dim; ++k) l2 += (b[k] - last[k]) * (b[k] - last[k]);
    const double len = std::sqrt(l2);
    if ((start + len) / step - double(next) > 1e7)
      throw InputError("stroke: more than 10 million dabs (spacing too small for its length)");
    double p[3];
    while (double(next) * step <= start + len + 1e-9 * step) {
      const double u = len > 0 ? std::clamp((double(next) * step - start) / len, 0.0, 1.0) : 1.0;
      for (int k = 0; k < dim; ++k) p[k] = last[k] + (b[k] - last[k]) * u;
      f(p);
      ++next;
    }
    start += len;
    std::copy(b, b + dim, last);
  }
};

}  // namespace

// The per-stroke state: the brush, the eye, and per texel the colour before the stroke and the
// strongest weight any dab of the stroke gave it.
struct StrokePainter::State : LeafPainter {
  State(OctreeTexture& t, const PaintSurface& s, PaintTarget to)
      : tex(t), surf(s), refiner(t, s), target(to) {}

  OctreeTexture& tex;
  const PaintSurface& surf;
  Refiner refiner;
  PaintTarget target;
  Brush brush;
  // The stroke's ceiling in weight(): the colour's opacity, or 1 for an RMH texture, whose
  // channels each apply their own in blend_rmh.
  float opacity = 1;
  bool has_camera = false;
  PaintCamera camera;
  StrokeStats stats;
  std::chrono::steady_clock::time_point t0;
  float cos_falloff = 0;  // cos(brush.falloff_angle_deg)
  // The current dab.
  V3 c, n0;
  bool screen = false;
  double cx = 0, cy = 0;
  float r_world = 0;
  std::vector<uint32_t> tris;
  PolylineWalk walk;  // extend_screen's polyline so far

  // The brush's weight at surface point q (normal nq) were nothing in the way, and the
  // occlusion segment toward the eye that decides whether it is (origin o, direction dir,
  // length len). 0: nothing to paint, no ray.
  float weight(V3 q, V3 nq, float half, V3& o, V3& dir, float& len) const {
    float t;
    if (screen) {
      double px, py;
      const float qq[3] = {q.x, q.y, q.z};
      if (!camera.project(qq, px, py)) return 0;
      t = float(std::hypot(px - cx, py - cy) / double(brush.radius));
    } else {
      t = length(q - c) / r_world;
    }
    if (!(t <= 1)) return 0;
    const float h = brush.hardness;
    const float f = t <= h ? 1.0f : 1.0f - smooth01((t - h) / (1 - h));
    float tfar;
    if (has_camera) {
      dir = v3(camera.eye) - q;
      tfar = length(dir);
      if (!(tfar > 0)) return 0;
      dir = (1 / tfar) * dir;
    } else {
      dir = n0;
      tfar = 2 * r_world;
    }
    const float facing = dot(nq, dir);
    if (!(facing > 0)) return 0;
    const float cs = cos_falloff;
    const float fa = facing >= cs ? 1.0f : smooth01(facing / cs);
    const float w = opacity * f * fa;
    if (!(w > 0)) return 0;
    // Off the surface by a thousandth of the cell: far less than any sheet the tags separate.
    const float eps = std::max(half * 2e-3f, tex.size() * 1e-6f);
    o = q + eps * nq;
    len = tfar - eps;
    return w;
  }

  bool reuse = false;
  struct Shard;
  // Per task cell of the refiner (see LeafPainter::shard): what painting its cells writes.
  std::unordered_map<uint64_t, std::unique_ptr<Shard>> shards;
  bool sharded() const override { return true; }
  LeafPainter* shard(uint64_t key) override;
  void paint(const CellBox& box, LeafCell& cell, std::span<const uint32_t> cell_tris,
             uint32_t memo) override {
    shard(~uint64_t(0))->paint(box, cell, cell_tris, memo);
  }

  Rgba8 blend_texel(Rgba8 orig, float w) const {
    return target == PaintTarget::color ? blend(orig, brush.color, brush.blend, w)
                                        : blend_rmh(orig, tex.background(), brush.material, w);
  }

  void dab(V3 centre, float region_r) {
    c = centre;
    const int depth = brush.depth;
    const float leaf_diag = tex.size() / float(1u << depth) * 1.7320508f;
    const float list_r = region_r + leaf_diag * 1.001f + tex.size() * 1e-5f;
    tris.clear();
    const float cc[3] = {c.x, c.y, c.z};
    surf.triangles_near(cc, list_r, tris);
    Region reg;
    reg.everything = false, reg.c = c, reg.r = region_r;
    // From the stroke's second dab on (a single dab, a click, would only pay for the keeping).
    refiner.keep_brick_lists(reuse && stats.dabs > 0);
    refiner.run(reg, tris, depth, this);
    ++stats.dabs;
  }
};

// What painting the cells of one task cell writes: their rays in flight, per texel the colour
// before the stroke and the strongest weight any dab gave it, the reuse memos; the brush, the
// eye and the dab are the stroke's (read only while the refiner runs).
struct StrokePainter::State::Shard : LeafPainter {
  explicit Shard(const State& s) : st(s) {}
  const State& st;
  size_t samples_changed = 0, rays = 0;
  struct Texel {
    Rgba8 orig;
    float w;
  };
  BlockMap<Texel> texels;

  // A texel whose ray is in flight: the cell stays where it is until the refiner's next flush.
  struct Pending {
    uint64_t key;
    LeafCell* cell;
    int side;
    float w;
  };
  static constexpr size_t kBatch = 64;
  Pending pending[kBatch];
  float ray_org[3 * kBatch], ray_dir[3 * kBatch], ray_near[kBatch], ray_far[kBatch];
  uint8_t ray_hit[kBatch];
  size_t npending = 0;

  // What an unoccluded texel gets: within a stroke it keeps the strongest weight any dab gave
  // it, blended over its colour before the stroke.
  void apply(uint64_t key, LeafCell& cell, int side, float w) {
    Texel& tx = texels.find_or_add(key, Texel{cell.s[side], 0.0f});
    if (w <= tx.w) return;
    tx.w = w;
    const Rgba8 nc = st.blend_texel(tx.orig, w);
    if (nc != cell.s[side]) ++samples_changed, cell.s[side] = nc;
  }

  void flush() override {
    if (!npending) return;
    st.surf.occluded_many(npending, ray_org, ray_dir, ray_near, ray_far, ray_hit);
    rays += npending;
    for (size_t i = 0; i < npending; ++i)
      if (!ray_hit[i]) apply(pending[i].key, *pending[i].cell, pending[i].side, pending[i].w);
    npending = 0;
  }

  // With reuse on, per memo (a brick's leaf, see LeafPainter::paint): the cell's tag and per
  // side the nearest surface point to the cell's centre and its normal, which depend on nothing
  // else once the refiner gives the cell a memo.
  // Trivial, so memo slots are made without being zero-filled: a stroke's memos number its
  // bricks' leaves (tens of thousands), and filling them was 3% of a dab. q and nq of a side
  // are written, and read, only where `has` has the side's bit.
  struct Near {
    uint8_t tag, has;  // has: bit side, a triangle on that side
    float q[2][3], nq[2][3];
  };
  static constexpr size_t kNearChunk = 4096;
  std::vector<uint8_t> near_known;                  // per memo: its slot holds the cell's tag's
  std::vector<std::unique_ptr<Near[]>> near_slots;  // chunks of kNearChunk, never moved

  // The nearest point to the cell's centre on the cell's triangles of each side.
  void nearest(const CellBox& box, const LeafCell& cell, std::span<const uint32_t> cell_tris,
               Near& e) const {
    // Both sides in one pass, each keeping the first nearest in list order.
    float best[2] = {INFINITY, INFINITY};
    uint32_t arg[2] = {0, 0};
    for (uint32_t t : cell_tris) {
      const int side = st.surf.side(cell.tag, t);
      const V3 p = closest_on_triangle(box.c, v3(st.surf.corner(t, 0)), v3(st.surf.corner(t, 1)),
                                       v3(st.surf.corner(t, 2)));
      const V3 d = p - box.c;
      const float d2 = dot(d, d);
      if (d2 < best[side])
        best[side] = d2, e.q[side][0] = p.x, e.q[side][1] = p.y, e.q[side][2] = p.z, arg[side] = t;
    }
    e.has = 0;
    for (int side = 0; side < 2; ++side)
      if (best[side] != INFINITY) {
        e.has = uint8_t(e.has | 1 << side);
        const float* n = st.surf.normal(arg[side]);
        e.nq[side][0] = n[0], e.nq[side][1] = n[1], e.nq[side][2] = n[2];
      }
  }

  // The last 4x4x4 block paint() keyed (any cell of it, its level) and its key bits.
  uint32_t key_x = ~0u, key_y = ~0u, key_z = ~0u;
  int key_level = -1;
  uint64_t key_block = 0;

  void paint(const CellBox& box, LeafCell& cell, std::span<const uint32_t> cell_tris,
             uint32_t memo) override {
    Near local;
    const Near* e = &local;
    if (st.reuse && memo != kNoMemo) {
      if (memo >= near_known.size())
        near_known.resize(std::max<size_t>(size_t(memo) + 1, 2 * near_known.size()), 0);
      const size_t chunk = memo / kNearChunk;
      if (chunk >= near_slots.size()) near_slots.resize(chunk + 1);
      if (!near_slots[chunk]) near_slots[chunk].reset(new Near[kNearChunk]);
      Near& kept = near_slots[chunk][memo % kNearChunk];
      if (!near_known[memo] || kept.tag != cell.tag) {
        nearest(box, cell, cell_tris, kept);
        near_known[memo] = 1, kept.tag = cell.tag;
      }
      e = &kept;
    } else {
      nearest(box, cell, cell_tris, local);
    }
    // morton3 splits into the code of the 4x4x4 block (a brick's leaves) shifted by 6 and the
    // code of the cell inside it: the block's, computed once for its up to 64 leaves.
    if ((box.x ^ key_x) >> 2 || (box.y ^ key_y) >> 2 || (box.z ^ key_z) >> 2 ||
        box.level != key_level) {
      key_x = box.x, key_y = box.y, key_z = box.z, key_level = box.level;
      key_block = morton3(box.x >> 2, box.y >> 2, box.z >> 2) << 6 | uint64_t(box.level) << 48;
    }
    auto low2 = [](uint32_t v) { return uint64_t((v & 1u) | (v & 2u) << 2); };
    const uint64_t cell_key = key_block | low2(box.x) | low2(box.y) << 1 | low2(box.z) << 2;
    for (int side = 0; side < 2; ++side) {
      if (!(e->has >> side & 1)) continue;
      if (side == 1 && !cell.dbl) cell.dbl = true, cell.s[1] = st.tex.background();
      V3 o, dir;
      float len;
      const float w = st.weight(v3(e->q[side]), v3(e->nq[side]), box.h, o, dir, len);
      if (!(w > 0)) continue;
      const uint64_t key = cell_key | uint64_t(side) << 53;
      // A texel this stroke already gave as much changes whatever the ray finds: no ray.
      if (const Texel* tx = texels.find(key); tx && w <= tx->w) continue;
      if (npending == kBatch) flush();
      pending[npending] = {key, &cell, side, w};
      ray_org[3 * npending] = o.x, ray_org[3 * npending + 1] = o.y, ray_org[3 * npending + 2] = o.z;
      ray_dir[3 * npending] = dir.x, ray_dir[3 * npending + 1] = dir.y,
                  ray_dir[3 * npending + 2] = dir.z;
      ray_near[npending] = 0.0f, ray_far[npending] = len;
      ++npending;
    }
  }
};

LeafPainter* StrokePainter::State::shard(uint64_t key) {
  std::unique_ptr<Shard>& s = shards[key];
  if (!s) s = std::make_unique<Shard>(*this);
  return s.get();
}

StrokePainter::StrokePainter(OctreeTexture& texture, const PaintSurface& surface,
                             PaintHistory* history, PaintTarget target)
    : t_(texture), s_(surface), history_(history), target_(target) {}

StrokePainter::~StrokePainter() {
  if (st_) {
    if (history_) history_->end(t_);
    delete st_;
  }
}

void StrokePainter::begin(const Brush& brush, const PaintCamera* camera) {
  check_brush(brush, "brush");
  if (camera && !camera->valid())
    throw InputError("camera: degenerate (eye at the target, up along the view, or bad fovy/size)");
  if (st_) end();
  st_ = new State(t_, s_, target_);
  st_->brush = brush;
  st_->opacity = target_ == PaintTarget::color ? brush.opacity : 1.0f;
  st_->cos_falloff = std::cos(brush.falloff_angle_deg * 3.14159265f / 180.0f);
  st_->has_camera = camera != nullptr;
  st_->reuse = reuse_;
  if (camera) st_->camera = *camera;
  st_->t0 = std::chrono::steady_clock::now();
  if (history_) history_->begin(t_);
}

bool StrokePainter::dab_world(const float p[3]) {
  if (!st_) throw std::logic_error("StrokePainter::dab_world outside a stroke");
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
    throw InputError("stroke: a point is not finite");
  SurfaceHit hit;
  if (!s_.closest_point(p, st_->brush.radius, hit)) {
    ++st_->stats.dabs_missed;
    return false;
  }
  st_->screen = false;
  st_->n0 = v3(hit.n);
  st_->r_world = st_->brush.radius;
  st_->dab(v3(hit.p), st_->brush.radius);
  return true;
}

bool StrokePainter::dab_screen(double px, double py) {
  if (!st_) throw std::logic_error("StrokePainter::dab_screen outside a stroke");
  if (!st_->has_camera) throw InputError("stroke: screen points need a camera");
  if (!(std::isfinite(px) && std::isfinite(py))) throw InputError("stroke: a point is not finite");
  float dir[3];
  SurfaceHit hit;
  if (!st_->camera.ray(px, py, dir) || !s_.intersect(st_->camera.eye, dir, 0.0f, INFINITY, hit) ||
      dot(v3(hit.n), v3(dir)) >= 0) {
    ++st_->stats.dabs_missed;
    return false;
  }
  st_->screen = true;
  st_->cx = px, st_->cy = py;
  st_->n0 = v3(hit.n);
  st_->r_world = float(st_->brush.radius * st_->camera.world_per_pixel(hit.p));
  // A disc on screen is a cone in space: take the surface within twice its radius at the hit.
  st_->dab(v3(hit.p), 2 * st_->r_world);
  return true;
}

namespace {

// Calls f(point) every `step` of arc length along a polyline of `dim`-vectors.
template <class T, class F>
void along(std::span<const T> pts, int dim, double step, F&& f) {
  const size_t n = pts.size() / size_t(dim);
  for (T v : pts)
    if (!std::isfinite(double(v))) throw InputError("stroke: a point is not finite");
  double total = 0;
  for (size_t i = 1; i < n; ++i) {
    double l2 = 0;
    for (int k = 0; k < dim; ++k) {
      const double d =
          double(pts[i * size_t(dim) + size_t(k)]) - double(pts[(i - 1) * size_t(dim) + size_t(k)]);
      l2 += d * d;
    }
    total += std::sqrt(l2);
  }
  if (total / step + double(n) > 1e7)
    throw InputError("stroke: more than 10 million dabs (spacing too small for its length)");
  PolylineWalk walk;
  walk.step = step;
  double p[3];
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < dim; ++k) p[k] = double(pts[i * size_t(dim) + size_t(k)]);
    walk.to(p, dim, f);
  }
}

}  // namespace

void StrokePainter::stroke_world(std::span<const float> xyz) {
  if (!st_) throw std::logic_error("StrokePainter::stroke_world outside a stroke");
  along(xyz, 3, double(st_->brush.spacing) * st_->brush.radius, [&](const double* p) {
    const float q[3] = {float(p[0]), float(p[1]), float(p[2])};
    dab_world(q);
  });
}

void StrokePainter::stroke_screen(std::span<const double> xy) {
  if (!st_) throw std::logic_error("StrokePainter::stroke_screen outside a stroke");
  along(xy, 2, double(st_->brush.spacing) * st_->brush.radius,
        [&](const double* p) { dab_screen(p[0], p[1]); });
}

void StrokePainter::extend_screen(double px, double py) {
  if (!st_) throw std::logic_error("StrokePainter::extend_screen outside a stroke");
  if (!std::isfinite(px) || !std::isfinite(py)) throw InputError("stroke: a point is not finite");
  PolylineWalk& w = st_->walk;
  w.step = double(st_->brush.spacing) * st_->brush.radius;
  const double p[2] = {px, py};
  w.to(p, 2, [&](const double* q) { dab_screen(q[0], q[1]); });
}

StrokeStats StrokePainter::end() {
  if (!st_) return {};
  StrokeStats s = st_->stats;
  for (const auto& [key, sh] : st_->shards)
    s.samples_changed += sh->samples_changed, s.rays += sh->rays;
  s.leaves_created = st_->refiner.stats.leaves_created;
  s.bricks_created = st_->refiner.stats.bricks_created;
  s.nodes_created = st_->refiner.stats.generals_created + st_->refiner.stats.bricks_created;
  s.tasks = st_->refiner.stats.tasks, s.tasks_threaded = st_->refiner.stats.tasks_threaded;
  s.ms = ms_since(st_->t0);
  delete st_;
  st_ = nullptr;
  if (history_) history_->end(t_);
  return s;
}

OctreeTexture OctreeTexture::create(const PaintSurface& s, Rgba8 background, float margin) {
  const Box& b = s.bounds();
  float ext = 0;
  for (int k = 0; k < 3; ++k) ext = std::max(ext, b.max[k] - b.min[k]);
  if (!(ext > 0) || !std::isfinite(ext))
    throw InputError("mesh: its bounding box has no extent; nothing to paint on");
  if (!(margin >= 0 && margin < 10)) throw InputError("texture: margin must be in [0, 10)");
  const float size = ext * (1 + 2 * margin);
  float origin[3];
  for (int k = 0; k < 3; ++k) origin[k] = 0.5f * (b.min[k] + b.max[k]) - 0.5f * size;
  OctreeTexture t = empty(origin, size, background);
  refine_surface(t, s, octree::kStartDepth);
  // The start cells' lists a first dab on any of them splits (kept with the surface).
  Refiner(t, s).prepare_start_lists();
  return t;
}

OctreeTexture OctreeTexture::create(const Mesh& mesh, Rgba8 background, float margin) {
  const PaintSurface s(mesh);
  return create(s, background, margin);
}

void refine_surface(OctreeTexture& t, const PaintSurface& s, int depth) {
  if (depth < 1 || depth > octree::kMaxDepth)
    throw InputError("depth " + std::to_string(depth) + ": must be 1-" +
                     std::to_string(octree::kMaxDepth));
  Refiner r(t, s);
  const std::vector<uint32_t> all = all_triangles(s);
  r.run(Region{}, all, depth, nullptr);
}

namespace {

// What a fill writes into a texel: the brush's colour, or its material channels (target rmh).
struct FillBlend {
  const Brush* brush;
  PaintTarget target;
  Rgba8 background;
  Rgba8 operator()(Rgba8 c) const {
    return target == PaintTarget::color ? blend(c, brush->color, brush->blend, brush->opacity)
                                        : blend_rmh(c, background, brush->material, 1.0f);
  }
};

struct FillPainter : LeafPainter {
  explicit FillPainter(const FillBlend& b) : blend_texel(b) {}
  FillBlend blend_texel;
  size_t changed = 0;
  // Per task cell a painter of its own (its count), so a fill runs on TBB's threads.
  std::unordered_map<uint64_t, std::unique_ptr<FillPainter>> shards;
  void paint(const CellBox&, LeafCell& cell, std::span<const uint32_t>, uint32_t) override {
    for (int side = 0; side < (cell.dbl ? 2 : 1); ++side) {
      const Rgba8 nc = blend_texel(cell.s[side]);
      if (nc != cell.s[side]) cell.s[side] = nc, ++changed;
    }
  }
  bool sharded() const override { return true; }
  LeafPainter* shard(uint64_t key) override {
    std::unique_ptr<FillPainter>& p = shards[key];
    if (!p) p = std::make_unique<FillPainter>(blend_texel);
    return p.get();
  }
  size_t total() const {
    size_t n = changed;
    for (const auto& [key, p] : shards) n += p->total();
    return n;
  }
};

size_t fill_texture(OctreeTexture& t, const PaintSurface& s, const Brush& b, PaintTarget target,
                    int depth) {
  const FillBlend fb{&b, target, t.background()};
  if (depth > 0) {
    FillPainter p(fb);
    Refiner r(t, s);
    const std::vector<uint32_t> all = all_triangles(s);
    r.run(Region{}, all, depth, &p);
    return p.total();
  }
  std::vector<std::pair<size_t, Rgba8>> writes;
  t.for_each_sample([&](const OctreeSample& x) {
    const Rgba8 nc = fb(x.color);
    if (nc != x.color) writes.push_back({x.word, nc});
  });
  OctreeEditor ed(t);
  for (auto [w, c] : writes) ed.set(uint32_t(w), c);
  recompute_averages(t);
  return writes.size();
}

}  // namespace

size_t fill(OctreeTexture& t, const PaintSurface& s, const float color[4], BlendMode mode,
            float opacity, int depth) {
  Brush b;
  std::copy_n(color, 4, b.color);
  b.opacity = opacity, b.blend = mode;
  if (depth > 0) b.depth = depth;
  check_brush(b, "fill");
  return fill_texture(t, s, b, PaintTarget::color, depth);
}

size_t fill(MaterialTexture& m, const PaintSurface& s, const Brush& brush, int depth,
            MaterialDefaults defaults) {
  Brush b = brush;
  if (depth > 0) b.depth = depth;
  check_brush(b, "fill");
  size_t n = 0;
  if (b.paint_color) n += fill_texture(m.color, s, b, PaintTarget::color, depth);
  if (b.paints_material())
    n += fill_texture(m.ensure_rmh(s, defaults), s, b, PaintTarget::rmh, depth);
  return n;
}

bool pick_world(const OctreeTexture& t, const PaintSurface& s, const float p[3], float max_dist,
                float rgba[4]) {
  rgba8_to_float(t.background(), rgba);
  SurfaceHit hit;
  if (!s.closest_point(p, max_dist, hit)) return false;
  Rgba8 c;
  const bool ok = lookup_nearest(t, hit.p, hit.n, c);
  rgba8_to_float(c, rgba);
  return ok;
}

bool pick_screen(const OctreeTexture& t, const PaintSurface& s, const PaintCamera& camera,
                 double px, double py, float rgba[4]) {
  rgba8_to_float(t.background(), rgba);
  float dir[3];
  SurfaceHit hit;
  if (!camera.ray(px, py, dir) || !s.intersect(camera.eye, dir, 0.0f, INFINITY, hit)) return false;
  Rgba8 c;
  const bool ok = lookup_nearest(t, hit.p, hit.n, c);
  rgba8_to_float(c, rgba);
  return ok;
}

namespace {

Rgba8 average_brick(OctreeEditor& ed, uint32_t word) {
  const Rgba8 avg = brick_average(decode_brick(ed.pool(), word));
  ed.set((word & ~octree::kBrickDoubleFlag) + ((word & octree::kBrickDoubleFlag) ? 4 : 2), avg);
  return avg;
}

Rgba8 average_general(OctreeEditor& ed, uint32_t ptr, uint32_t info) {
  const GeneralNode n = decode_general(ed.pool(), ptr, info);
  ColorMean m;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::leaf) add_leaf(m, n.leaf[c]);
    if (n.kind[c] == CellKind::general) m.add(average_general(ed, n.ptr[c], n.info[c]));
    if (n.kind[c] == CellKind::brick) m.add(average_brick(ed, n.ptr[c]));
  }
  const Rgba8 avg = m.mean();
  ed.set(ptr + 2 * uint32_t(popc(octree::generals(info))) + uint32_t(popc(octree::bricks(info))),
         avg);
  return avg;
}

}  // namespace

void recompute_averages(OctreeTexture& t) {
  OctreeEditor ed(t);
  const uint32_t info = ed.word(1);
  if (octree::occupied(info)) average_general(ed, ed.word(0), info);
}

}  // namespace limn
