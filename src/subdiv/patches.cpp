// Feature-adaptive patch tables: isolation by sparse refinement, classification per face, patch
// points, and Gregory end caps.
//
// The end-cap points follow OpenSubdiv 3.5's Far GREGORY_BASIS end caps (its GregoryConverter:
// limit position P, edge points Ep/Em from the limit tangent masks with its eigenvalue scaling,
// face points Fp/Fm from Loop et al. 2009's formula with its cosine terms), so that the test
// suite can hold limn to OpenSubdiv's adaptive surface at the same isolation level.
#include "limn/subdiv/patches.hpp"

#include <fmt/format.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "core/timer.hpp"
#include "corner_twins.hpp"
#include "limn/mesh/topology.hpp"
#include "shared_weights.hpp"

namespace limn {

namespace {

constexpr int kMaxDepth = 16;
constexpr float kInf = kInfiniteSharpness;

// First ptex face of each cage face (one per quad, one per corner of any other face), and the
// total at the end.
std::vector<uint32_t> ptex_offsets(const Mesh& cage) {
  std::vector<uint32_t> first(1, 0);
  first.reserve(cage.face_count() + 1);
  for (size_t f = 0; f < cage.face_count(); ++f) {
    const uint32_t n = cage.face_size(f);
    first.push_back(first.back() + (n == 4 ? 1 : n));
  }
  return first;
}

// A linear combination of an end cap's points: dense over the cap's support (the ids of its four
// corners and their rings), so adding a term is two lookups (the point's slot in the support,
// from a map by point id), combining rows is a dense axpy, and emitting walks the support. A row
// touches a few of the support's slots (7 of ~35 on average): up to 64 slots, a mask of the
// touched ones lets combining and emitting visit only those, in the same (support) order.
struct Terms {
  const std::vector<uint32_t>* ids = nullptr;
  const uint32_t* slot = nullptr;  // slot[p - base]: p's place in ids (valid for ids only)
  uint32_t base = 0, span = 0;
  std::vector<double> w;
  uint64_t touched = 0;  // bit s: slot s may be non-zero (all slots when the support is wide)
  bool wide = false;     // more than 64 slots: no mask
  void reset(const std::vector<uint32_t>& support, const uint32_t* slots, uint32_t first,
             uint32_t count) {
    ids = &support, slot = slots, base = first, span = count;
    w.assign(support.size(), 0.0);
    touched = 0, wide = support.size() > 64;
  }
  void add(uint32_t p, double x) {
    const uint32_t s = p - base < span ? slot[p - base] : kNone;
    if (s >= ids->size() || (*ids)[s] != p)
      throw std::logic_error("patches: end-cap point off support");
    w[s] += x;
    if (!wide) touched |= uint64_t(1) << s;
  }
  void add(const Terms& o, double s) {
    if (wide) {
      for (size_t i = 0; i < w.size(); ++i) w[i] += o.w[i] * s;
      return;
    }
    for (uint64_t m = o.touched; m; m &= m - 1) {
      const int i = std::countr_zero(m);
      w[size_t(i)] += o.w[size_t(i)] * s;
    }
    touched |= o.touched;
  }
  // Writes the row's non-zero terms to idx/weight (room for the whole support); returns how
  // many.
  size_t emit(uint32_t* idx, float* weight) const {
    size_t n = 0;
    if (wide) {
      for (size_t i = 0; i < w.size(); ++i) {
        idx[n] = (*ids)[i], weight[n] = float(w[i]);
        n += w[i] != 0.0;
      }
      return n;
    }
    for (uint64_t m = touched; m; m &= m - 1) {
      const size_t i = size_t(std::countr_zero(m));
      idx[n] = (*ids)[i], weight[n] = float(w[i]);
      n += w[i] != 0.0;
    }
    return n;
  }
};

// One vertex's neighbourhood in rotational order: face i lies between edge i (towards the next
// vertex of face i) and edge i + 1; boundary vertices start at their leading boundary edge.
struct Ring {
  std::vector<uint32_t> edge_end;  // other end of each edge (nfaces, or nfaces + 1 on a boundary)
  std::vector<uint32_t> diagonal;  // vertex opposite the centre in each (quad) face
  std::vector<uint32_t> face;      // face ids
  bool boundary = false, manifold = true, all_quads = true;
};

// The corner table the builder walks, made from refine_sparse's own adjacency (no second
// adjacency build): next/prev in the face, the opposite corner (kNone on a boundary,
// kNonManifold on an edge of more than two faces), and each vertex's corners.
// Every level after the cage (and many cages) is all quads: corner c is then corner c % 4 of face
// c / 4, and the per-corner face/next/prev arrays (a third of the walking data on the last,
// largest level) are not stored.
template <int kOp>  // 0: face, 1: next corner in the face, 2: previous
struct CornerRel {
  std::vector<uint32_t> table;  // empty when all faces are quads
  uint32_t operator[](uint32_t c) const {
    if (!table.empty()) return table[c];
    if constexpr (kOp == 0) return c >> 2;
    if constexpr (kOp == 1) return (c & ~3u) | ((c + 1) & 3u);
    return (c & ~3u) | ((c + 3) & 3u);
  }
};

// The sharpness of each corner's edge, read through the level's adjacency.
struct CornerSharpness {
  std::span<const uint32_t> corner_edge;
  const float* edge_sharpness = nullptr;
  float operator[](uint32_t c) const { return edge_sharpness[corner_edge[c]]; }
};

// Corner twins: refine_sparse's for a last level (it drops its edge lists first), else made here.
struct CornerTwins {
  std::vector<uint32_t> own;
  std::span<const uint32_t> given;
  uint32_t operator[](uint32_t c) const { return given.empty() ? own[c] : given[c]; }
};

struct Topo {
  bool quads = true;  // every face is a quad (a corner count of 4 per face is not enough)
  CornerRel<0> corner_face;
  CornerRel<1> corner_next;
  CornerRel<2> corner_prev;
  CornerTwins corner_twin;
  std::span<const uint32_t> vertex_offsets, vertex_corners;  // refine_sparse's, during a request
};

Topo make_topo(const RefinedLevel& R, const LevelAdjacency& a) {
  Topo t;
  const size_t nc = R.face_vertices.size();
  for (size_t f = 0; f < R.face_count() && t.quads; ++f)
    t.quads = R.face_offsets[f + 1] - R.face_offsets[f] == 4;
  if (!t.quads) {
    t.corner_face.table.resize(nc), t.corner_next.table.resize(nc), t.corner_prev.table.resize(nc);
    for (uint32_t f = 0; f < R.face_count(); ++f) {
      const uint32_t b = R.face_offsets[f], e = R.face_offsets[f + 1];
      for (uint32_t c = b; c < e; ++c) {
        t.corner_face.table[c] = f;
        t.corner_next.table[c] = c + 1 == e ? b : c + 1;
        t.corner_prev.table[c] = c == b ? e - 1 : c - 1;
      }
    }
  }
  if (!a.corner_twin.empty()) {
    if (a.corner_twin.size() != nc) throw std::logic_error("patches: corner twins off the level");
    t.corner_twin.given = a.corner_twin;
  } else {
    t.corner_twin.own.resize(nc);
    detail::corner_twins(a.edge_corner_offsets, a.edge_corners, t.corner_twin.own);
  }
  t.vertex_offsets = a.vertex_corner_offsets;
  t.vertex_corners = a.vertex_corners;
  return t;
}

// Gives a vector's memory back (`v = {}` would pick the initializer-list assignment, which
// empties it and keeps its capacity).
template <class V>
void release(V& v) {
  V().swap(v);
}

// An append-only array in blocks of 2^kShift elements: growing never copies what it holds (a
// vector's doubling holds both copies at once, and the pending end caps are held through the
// build's peak, the last level's emission).
template <class T, int kShift>
class BlockArray {
 public:
  size_t size() const { return size_; }
  const T& operator[](size_t i) const { return blocks_[i >> kShift][i & kMask]; }
  void push_back(const T& x) {
    if (size_ >> kShift == blocks_.size())
      blocks_.push_back(std::make_unique_for_overwrite<T[]>(kMask + 1));
    blocks_[size_ >> kShift][size_ & kMask] = x;
    ++size_;
  }
  // Elements [at, at + n) into out.
  void copy(size_t at, size_t n, T* out) const {
    while (n) {
      const size_t k = std::min(n, kMask + 1 - (at & kMask));
      out = std::copy_n(&blocks_[at >> kShift][at & kMask], k, out);
      at += k, n -= k;
    }
  }
  void release() { *this = BlockArray(); }

 private:
  static constexpr size_t kMask = (size_t(1) << kShift) - 1;
  std::vector<std::unique_ptr<T[]>> blocks_;
  size_t size_ = 0;
};

// Per-level state of the isolation.
struct Level {
  Topo topo;
  CornerSharpness corner_sharpness;        // sharpness of each corner's edge (by corner)
  std::vector<uint8_t> rem;                // per vertex: levels still wanted around it
  std::vector<uint8_t> irregular;          // per vertex (complete ones only)
  std::vector<uint8_t> owned;              // per face: this level covers it (or a deeper one)
  std::vector<uint8_t> requested;          // per face: refined for its own sake
  std::vector<uint8_t> force;              // per face: refined whatever the depths (non-quads)
  std::vector<uint8_t> role;               // region builds, per face: 2 emits patches, 1 may be
                                           // refined, 0 context only (empty: all 2)
  std::vector<uint32_t> src_offsets, src;  // hierarchy: the cage vertices each vertex's depth
                                           // comes from (CSR, sorted)
  std::vector<int8_t> crease_edge;         // per face: local edge of a single crease, or -1
  std::vector<float> crease_sharpness;     // per face: its sharpness
  struct Face {  // 12 bytes (two levels of them live at once): the cage face from ptex_first_
    uint32_t ptex = kNone;
    uint16_t u = 0, v = 0;
    uint8_t depth = 0, rot = 0, corner = 0;
  };
  static_assert(sizeof(Face) == 12);
  std::vector<Face> param;
  // This level's faces and edges, which the next level's provenance refers to (refine_sparse
  // keeps its levels in place: they are reserved up front).
  const RefinedLevel* level = nullptr;
  // Rings of the vertices asked for so far, flat: vertex v's faces are ring_face[ring_slot[v].at ..
  // + ring_slot[v].faces), its edge ends ring_edge[ring_slot[v].at + i] (one more on a boundary).
  struct RingSlot {
    uint32_t at = kNone;  // first entry in the ring arrays; kNone: not made yet
    uint16_t faces = 0;
    uint8_t flags = 0;  // 1 boundary, 2 manifold, 4 all quads
  };
  std::vector<RingSlot> ring_slot;  // one per vertex, so a lookup is one cache line
  std::vector<uint32_t> ring_edge, ring_diag, ring_face;
  // Per vertex, what is known of it, asked once per level and again by every patch at it:
  // kCutsKnown | kCuts (cuts_at_inf_sharp), kPlainKnown | kPlain (plain_interior).
  mutable std::vector<uint8_t> vinfo;
  static constexpr uint8_t kCutsKnown = 1, kCuts = 2, kPlainKnown = 4, kPlain = 8;
  bool deferred = false;  // classified in level_done (a level that refines nothing)
};

// Appends to a CSR of vertex sets (values, offsets) the sorted union of `from`'s sets of the
// given vertices: the cage vertices a new point's, or a face's, depth comes from.
template <class Vertices>
void append_union(std::vector<uint32_t>& values, std::vector<uint32_t>& offsets, const Level& from,
                  const Vertices& vertices) {
  const auto start = long(values.size());
  for (const uint32_t x : vertices)
    values.insert(values.end(), from.src.begin() + from.src_offsets[x],
                  from.src.begin() + from.src_offsets[x + 1]);
  std::sort(values.begin() + start, values.end());
  values.erase(std::unique(values.begin() + start, values.end()), values.end());
  offsets.push_back(uint32_t(values.size()));
}

// A cached ring.
struct RingView {
  const uint32_t *edge_end = nullptr, *diagonal = nullptr, *face = nullptr;
  uint32_t faces = 0;
  bool boundary = false, manifold = false, all_quads = false;
  uint32_t edges() const { return faces + (boundary ? 1 : 0); }
  int index_of(uint32_t f) const {
    for (uint32_t i = 0; i < faces; ++i)
      if (face[i] == f) return int(i);
    return -1;
  }
};

// Marks, while a table is built, an end-cap point that is not a plain id: in gregory_points a
// face point (a row of gregory_face_stencils), in gregory_face_stencils' indices a corner point
// (a row of gregory_stencils). Builder::build and RegionBuilder::finish give them global ids.
constexpr uint32_t kCapRef = 1u << 31;

// Gregory end-cap points of one quad (OpenSubdiv's GregoryConverter; see the file comment).
// The corner points (P, Ep, Em) are functions of a corner's fan alone, so end caps that share a
// corner share them (Builder::emit_cap keeps one row each); the face points are short rows over
// those and four ring points, not the corner points' expansions (pole360's 360 end caps around
// one vertex repeated its 721-point ring in each of their 20 rows).
class GregoryCap {
 public:
  struct Corner {
    uint32_t v = 0;              // global point id
    uint32_t fan = 0;            // the smallest face of its span: which of v's fans
    int fan_at = 0;              // its place in the span (where an interior fan's ring starts)
    std::vector<uint32_t> ring;  // global ids: edge end 2m, face diagonal 2m + 1
    int faces = 0, face_in_ring = 0, valence = 0;
    bool boundary = false, sharp = false, regular = false;
    bool ep_on_boundary = false, em_on_boundary = false;
    bool fp_regular = false, fm_regular = false, fp_copied = false, fm_copied = false;
    double cos_angle = 0;
  };

  Corner c[4];
  Terms p[4], ep[4], em[4];
  std::vector<uint32_t> support;  // ids of the corners and their rings, each once, as met
  std::vector<uint32_t> slots;    // by point id - first: place in support (its entries only)
  std::vector<uint32_t> row_idx;  // emit_row's scratch: a row's terms before they are copied
  std::vector<float> row_w;

  // Appends the row `t` to `table` (its weights shared through `shared`); returns its index.
  uint32_t emit_row(const Terms& t, StencilTable& table, detail::SharedWeights& shared) {
    if (row_idx.size() < support.size())
      row_idx.resize(support.size()), row_w.resize(support.size());
    const size_t n = t.emit(row_idx.data(), row_w.data());
    table.indices.insert(table.indices.end(), row_idx.begin(), row_idx.begin() + long(n));
    table.weight_offsets.push_back(shared.add(table.weights, row_w.data(), uint32_t(n)));
    table.offsets.push_back(uint32_t(table.indices.size()));
    return uint32_t(table.size() - 1);
  }

  // Ready for another patch, keeping the buffers.
  void reset() {
    for (int i = 0; i < 4; ++i) {
      std::vector<uint32_t> ring = std::move(c[i].ring);
      ring.clear();
      c[i] = Corner{};
      c[i].ring = std::move(ring);
    }
  }
  // `first`, `count`: the range of point ids the corners and rings lie in (one level's).
  void finish_topology(uint32_t first, uint32_t count);
  // Corner i's P, Ep and Em as terms over the support.
  void edge_points(int i);
  // Appends corner i's face point Fp (plus) or Fm to `table`: over the four corners where both
  // corners of its edge are regular, else over the corner points (rows p, e_near, e_far of
  // gregory_stencils) and four ring points. Returns its row.
  uint32_t emit_face_point(int i, bool plus, uint32_t p, uint32_t e_near, uint32_t e_far,
                           StencilTable& table, detail::SharedWeights& shared) const;
};

class Builder {
 public:
  Builder(const Mesh& cage, const PatchOptions& o, std::span<const uint8_t> depth,
          PatchHierarchy* h = nullptr)
      : cage_(cage), o_(o), depth_(depth), h_(h) {}

  /// Decides which of level k's faces to refine (refine_sparse's request).
  void request(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
               std::vector<uint8_t>& requested);
  /// Emits level k's patches, once refine_sparse has built the level's stencils and dropped
  /// level k - 1 (its level_done): only one level's topology is held while the table grows.
  void level_done(size_t k, const SparseLevel& S, const LevelAdjacency& adj);
  void build(PatchTable& out, SparseRefinement& r, PatchStats* stats);
  void set_stats(PatchStats* stats) { stats_ = stats; }
  /// Region builds: the role of each cage face (see Level::role).
  void set_roles(std::span<const uint8_t> roles) { roles_ = roles; }

 private:
  RingView ring(Level& L, const RefinedLevel& R, uint32_t v) const;
  // Writes into `g` (its buffers reused from call to call).
  void span(const Level& L, const RefinedLevel& R, uint32_t corner, bool& sharp, Ring& g) const;
  struct SharpEdges {
    int inf = 0, semi = 0;  // infinitely sharp (boundary ones included) and semi-sharp edges
    bool boundary = false;
    uint32_t faces = 0;
  };
  SharpEdges sharp_edges(const Level& L, uint32_t v) const;
  bool cuts_at_inf_sharp(const Level& L, const RefinedLevel& R, uint32_t v) const;
  // Level k's corner table, tags, single creases and (requested non-null) requests.
  void classify(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
                std::vector<uint8_t>* requested);
  bool regular_vertex(Level& L, const RefinedLevel& R, uint32_t v) const;
  bool regular_vertex_inf(Level& L, const RefinedLevel& R, uint32_t v) const;
  int single_crease(Level& L, const RefinedLevel& R, uint32_t f, float& sharpness) const;
  void aligned_corners(const Level& L, const RefinedLevel& R, uint32_t f, uint32_t c[4]) const;

  const Mesh& cage_;
  PatchOptions o_;
  std::span<const uint8_t> depth_;
  std::span<const uint8_t> roles_;
  std::vector<Level> levels_;
  std::vector<uint32_t> ptex_first_;  // ptex_offsets(cage_): becomes the table's ptex_of_face
  // The cage face whose ptex faces hold `ptex`. O(log faces).
  uint32_t base_face(uint32_t ptex) const {
    return uint32_t(std::upper_bound(ptex_first_.begin(), ptex_first_.end(), ptex) -
                    ptex_first_.begin() - 1);
  }
  PatchHierarchy* h_;
  // Filled level by level as the refinement runs (each level's patches are emitted as soon as
  // its requests are known, then its walking data is dropped).
  void emit(size_t k, const SparseLevel& S);
  void reserve_output(const Level& L, const RefinedLevel& R);
  PatchTable out_;
  // Each level's regular patches (points, params), joined into out_ by build().
  std::vector<std::vector<uint32_t>> level_points_;
  std::vector<std::vector<PatchParam>> level_params_;
  PatchStats* stats_ = nullptr;
  double emit_ms_ = 0;
  std::vector<uint32_t> level_offsets_{0};  // first global point id of each level, as refined
  std::vector<std::vector<uint32_t>> node_of_level_;  // hierarchy: node of each level's faces
  GregoryCap cap_;                                    // reused: its buffers stay allocated
  // The end-cap tables' weights, one sharer per kind of row (P, Ep, Em; Fp, Fm) over each
  // table's pool: a row most often equals the last row of its kind.
  detail::SharedWeights corner_weights_[3], face_weights_[2];
  // cap_'s rows into out_: its corner points shared with the level's earlier end caps at the
  // same corner fans (`count`: the level's points); ids gets the 20 points (face points marked
  // kCapRef).
  void emit_cap(size_t k, uint32_t count, const uint32_t a[4], uint32_t ids[20]);
  // End caps wait for their level to be gone (the next level's level_done, or build() for the
  // last): a cap's rows read only its corners' fans, which emit() keeps (a few ids a corner), so
  // the end-cap tables (a third of a small cage's table) and their sharing state never grow
  // beside their level's topology and walking state (the last level's is the build's peak).
  struct PendingCorner {
    uint32_t a = 0;  // level point
    uint32_t fan = 0, fan_at = 0, face_in_ring = 0;
    // Its ring: pending_rings_ from ring_at, turned by ring_rot faces (a fan of many faces keeps
    // one ring for all the end caps around it, which would otherwise hold its valence squared).
    uint32_t ring_at = 0, ring_rot = 0;
    uint32_t faces : 30 = 0, boundary : 1 = 0, sharp : 1 = 0;
  };
  struct PendingLevel {
    uint32_t level = 0, first_point = 0, points = 0;  // its global offset and point count
    size_t caps_end = 0;                              // pending_corners_ / 4 after its caps
  };
  BlockArray<PendingCorner, 10> pending_corners_;  // 4 per end cap, in emission order
  BlockArray<uint32_t, 12> pending_rings_;         // the corners' rings (GregoryCap::Corner::ring)
  std::vector<PendingLevel> pending_levels_;
  static constexpr uint32_t kLongFan = 16;  // faces from which a fan's ring is kept once
  // Long fans' kept rings by (global point, fan): where the ring is and its fan_at.
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> long_fans_;
  // Emits the pending end caps' rows and points in the order they were met, and drops their fans.
  void emit_pending_caps();
  // Room in the end-cap arrays for `caps` more end caps.
  void reserve_caps(size_t caps);
  // The corner points made so far at this level: per vertex a list of (fan, ring edge or kNone
  // for P, row of gregory_stencils).
  struct SharedRow {
    uint32_t fan, to, row, next;
  };
  std::vector<uint32_t> shared_head_;  // per vertex of level shared_level_; kNone: none yet
  std::vector<SharedRow> shared_;
  size_t shared_level_ = ~size_t(0);
  Ring spans_[4];  // a patch's corner spans (end caps; regular patches cut by sharp edges)
  mutable Ring span_scratch_;  // regular_vertex_inf's
};

// Whether an edge at v is non-manifold or joins two faces that disagree on its direction.
bool torn(const Topo& t, const uint32_t* fv, uint32_t v) {
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]}) {
      const uint32_t tw = t.corner_twin[h];
      if (tw == kNonManifold || (tw != kNone && fv[tw] == fv[h])) return true;
    }
  }
  return false;
}

RingView Builder::ring(Level& L, const RefinedLevel& R, uint32_t v) const {
  if (L.ring_slot.empty()) L.ring_slot.assign(R.vertex_count(), Level::RingSlot{});
  if (L.ring_slot[v].at == kNone) {
    const Topo& t = L.topo;
    const uint32_t* fv = R.face_vertices.data();
    const uint32_t s0 = t.vertex_offsets[v], n = t.vertex_offsets[v + 1] - s0;
    bool boundary = false, manifold = n > 0 && !torn(t, fv, v), quads = true;
    uint32_t start = n ? t.vertex_corners[s0] : kNone;
    for (uint32_t i = 0; i < n && !boundary; ++i) {
      const uint32_t c = t.vertex_corners[s0 + i];
      if (t.corner_twin[c] == kNone) start = c, boundary = true;
    }
    const uint32_t at = uint32_t(L.ring_face.size());
    uint32_t faces = 0;
    if (manifold) {
      uint32_t c = start;
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t f = t.corner_face[c];
        quads = quads && R.face_offsets[f + 1] - R.face_offsets[f] == 4;
        L.ring_edge.push_back(fv[t.corner_next[c]]);
        L.ring_diag.push_back(fv[t.corner_next[t.corner_next[c]]]);
        L.ring_face.push_back(f);
        ++faces;
        const uint32_t in = t.corner_prev[c];
        const uint32_t tw = t.corner_twin[in];
        if (tw == kNone) {
          L.ring_edge.push_back(fv[in]);
          break;
        }
        if (tw == start || tw >= kNonManifold) break;
        c = tw;
      }
      if (faces != n) manifold = false;  // faces in more than one fan
    }
    // Keep the three arrays in step (a boundary ring has one edge more than faces).
    while (L.ring_diag.size() < L.ring_edge.size()) L.ring_diag.push_back(kNone);
    while (L.ring_face.size() < L.ring_edge.size()) L.ring_face.push_back(kNone);
    Level::RingSlot& slot = L.ring_slot[v];
    slot.at = at;
    slot.faces = uint16_t(std::min<uint32_t>(faces, 0xFFFF));
    slot.flags =
        uint8_t((boundary ? 1 : 0) | (manifold && faces <= 0xFFFF ? 2 : 0) | (quads ? 4 : 0));
  }
  RingView g;
  const Level::RingSlot slot = L.ring_slot[v];
  g.edge_end = L.ring_edge.data() + slot.at;
  g.diagonal = L.ring_diag.data() + slot.at;
  g.face = L.ring_face.data() + slot.at;
  g.faces = slot.faces;
  g.boundary = slot.flags & 1;
  g.manifold = slot.flags & 2;
  g.all_quads = slot.flags & 4;
  return g;
}

Builder::SharpEdges Builder::sharp_edges(const Level& L, uint32_t v) const {
  const Topo& t = L.topo;
  SharpEdges e;
  e.faces = t.vertex_offsets[v + 1] - t.vertex_offsets[v];
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]}) {
      // Each interior edge is seen from both of its faces; count it once.
      const uint32_t tw = t.corner_twin[h];
      if (tw == kNone) e.boundary = true;
      if (!(tw >= kNonManifold || h == c)) continue;
      const float x = L.corner_sharpness[h];
      if (x >= kInf)
        ++e.inf;
      else if (x > 0.0f)
        ++e.semi;
    }
  }
  return e;
}

// With infinitely sharp patches, whether the vertex's spans are cut at its infinitely sharp
// edges (OpenSubdiv: the vertex has such edges and is not a dart).
bool Builder::cuts_at_inf_sharp(const Level& L, const RefinedLevel& R, uint32_t v) const {
  if (!o_.inf_sharp_patches) return false;
  uint8_t& x = L.vinfo[v];
  if (!(x & Level::kCutsKnown)) {
    const SharpEdges e = sharp_edges(L, v);
    const bool dart = !e.boundary && e.inf + e.semi == 1 && R.vertex_sharpness[v] == 0.0f;
    x |= Level::kCutsKnown | (e.inf > 0 && !dart ? Level::kCuts : 0);
  }
  return x & Level::kCuts;
}

// The fan of faces around a patch corner that a patch sees (OpenSubdiv's corner spans): the
// whole ring, or, when non-manifold edges (or, with infinitely sharp patches, infinitely sharp
// edges) cut it, the faces between the cuts that hold the patch face, as a boundary. `corner` is
// the patch face's corner at the vertex. `sharp`: an end cap interpolates the vertex (with
// infinitely sharp features approximated as smooth: a one-face boundary vertex, OpenSubdiv's
// sharp and legacy corners; with infinitely sharp patches also corners of sharp edges and
// infinitely sharp vertices).
void Builder::span(const Level& L, const RefinedLevel& R, uint32_t corner, bool& sharp,
                   Ring& g) const {
  const Topo& t = L.topo;
  const uint32_t* fv = R.face_vertices.data();
  const uint32_t v = fv[corner];
  const uint32_t n = t.vertex_offsets[v + 1] - t.vertex_offsets[v];
  const bool cut_sharp = cuts_at_inf_sharp(L, R, v);
  auto cut = [&](uint32_t h) {
    const uint32_t tw = t.corner_twin[h];
    return tw >= kNonManifold || fv[tw] == fv[h] || (cut_sharp && L.corner_sharpness[h] >= kInf);
  };
  // Back up to the leading cut (or all the way round).
  uint32_t start = corner;
  for (uint32_t guard = 0; guard <= n; ++guard) {
    if (cut(start)) break;
    const uint32_t prev = t.corner_next[t.corner_twin[start]];
    if (prev == corner) break;
    start = prev;
  }
  g.edge_end.clear(), g.diagonal.clear(), g.face.clear();
  g.all_quads = true;
  g.boundary = cut(start);
  uint32_t c = start;
  for (uint32_t guard = 0; guard <= n; ++guard) {
    const uint32_t f = t.corner_face[c];
    g.all_quads = g.all_quads && R.face_offsets[f + 1] - R.face_offsets[f] == 4;
    g.edge_end.push_back(fv[t.corner_next[c]]);
    g.diagonal.push_back(fv[t.corner_next[t.corner_next[c]]]);
    g.face.push_back(f);
    const uint32_t in = t.corner_prev[c];
    if (cut(in)) {
      g.edge_end.push_back(fv[in]);
      break;
    }
    c = t.corner_twin[in];
    if (c == start) break;
  }
  g.manifold = g.face.size() == n || g.boundary;
  const bool fan = g.face.size() == n;  // the span is the vertex's only fan
  // One fan cut by boundaries or sharp edges, or several fans (non-manifold)?
  const bool manifold_vertex = fan || !torn(t, fv, v);
  if (!o_.inf_sharp_patches || !manifold_vertex) {
    sharp = g.boundary && g.face.size() == 1;
  } else {
    const SharpEdges e = sharp_edges(L, v);
    const float vs = R.vertex_sharpness[v];
    const bool corner_tag = n == 1 && vs >= kInf;
    const bool crease = e.inf == 2 && vs < kInf;
    sharp = corner_tag || (cut_sharp ? !crease : vs >= kInf);
    if (!sharp && e.boundary && n == 1) sharp = true;  // OpenSubdiv's legacy smooth corner
  }
}

// The common regular case, told without walking the ring: four faces (refined levels are all
// quads), none across a boundary or a torn edge, no sharpness.
bool plain_interior_walk(const Level& L, const RefinedLevel& R, uint32_t v) {
  const Topo& t = L.topo;
  if (R.vertex_sharpness[v] != 0.0f || t.vertex_offsets[v + 1] - t.vertex_offsets[v] != 4 ||
      !t.quads)
    return false;
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i], tw = t.corner_twin[c];
    if (tw >= kNonManifold || R.face_vertices[tw] == v || L.corner_sharpness[c] != 0.0f)
      return false;
  }
  return true;
}

// The same, remembered (a plain vertex has no sharp edge, so nothing cuts its ring either).
bool plain_interior(const Level& L, const RefinedLevel& R, uint32_t v) {
  uint8_t& x = L.vinfo[v];
  if (!(x & Level::kPlainKnown))
    x |= uint8_t(Level::kPlainKnown |
                 (plain_interior_walk(L, R, v) ? Level::kPlain | Level::kCutsKnown : 0));
  return x & Level::kPlain;
}

// Regular: the limit surface around the vertex is the B-spline of its ring (interior valence 4,
// regular boundary with two faces, corner with one face under the corner rule), with no sharp
// feature of its own.
bool Builder::regular_vertex(Level& L, const RefinedLevel& R, uint32_t v) const {
  const Topo& t = L.topo;
  if (plain_interior(L, R, v)) return true;
  const RingView g = ring(L, R, v);
  if (!g.manifold || !g.all_quads) return false;
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]})
      if (t.corner_twin[h] != kNone && L.corner_sharpness[h] > 0.0f) return false;
  }
  const float vs = R.vertex_sharpness[v];
  const size_t nf = g.faces;
  if (!g.boundary) return nf == 4 && vs == 0.0f;
  if (nf == 2) return vs == 0.0f;
  return nf == 1 && vs >= kInf;
}

// A single-crease face: a quad of interior valence-4 corners whose edge j runs along a semi-sharp
// crease that goes straight through both of its ends with one sharpness (the two crease edges at
// each end are opposite in its ring), the other two corners plain. Returns j, or -1.
int Builder::single_crease(Level& L, const RefinedLevel& R, uint32_t f, float& sharpness) const {
  const Topo& t = L.topo;
  const uint32_t b = R.face_offsets[f];
  if (R.face_offsets[f + 1] - b != 4) return -1;
  bool any = false;  // the crease runs along one of the face's own edges
  for (uint32_t i = 0; i < 4 && !any; ++i) any = L.corner_sharpness[b + i] > 0.0f;
  if (!any) return -1;
  int kind[4];  // 0 plain, 1 crease end, -1 neither
  float s_at[4] = {};
  for (uint32_t i = 0; i < 4; ++i) {
    const uint32_t v = R.face_vertices[b + i];
    const RingView g = ring(L, R, v);
    kind[i] = -1;
    if (!g.manifold || !g.all_quads || g.boundary || g.faces != 4 || R.vertex_sharpness[v] != 0)
      continue;
    // Sharp edges by their position in the ring (interior: one outgoing half-edge per edge).
    int count = 0, first = -1, second = -1;
    float s0 = 0, s1 = 0;
    for (uint32_t k = t.vertex_offsets[v]; k < t.vertex_offsets[v + 1]; ++k) {
      const uint32_t c = t.vertex_corners[k];
      const float x = L.corner_sharpness[c];
      if (x <= 0) continue;
      const uint32_t end = R.face_vertices[t.corner_next[c]];
      int m = -1;
      for (uint32_t q = 0; q < 4; ++q)
        if (g.edge_end[q] == end) m = int(q);
      (count == 0 ? first : second) = m;
      (count == 0 ? s0 : s1) = x;
      ++count;
    }
    if (count == 0) {
      kind[i] = 0;
    } else if (count == 2 && s0 == s1 && s0 < kInf && first >= 0 && second >= 0 &&
               (first - second + 4) % 4 == 2) {
      kind[i] = 1, s_at[i] = s0;
    }
  }
  for (int j = 0; j < 4; ++j) {
    const int n1 = (j + 1) % 4, n2 = (j + 2) % 4, n3 = (j + 3) % 4;
    if (kind[j] == 1 && kind[n1] == 1 && kind[n2] == 0 && kind[n3] == 0 && s_at[j] == s_at[n1] &&
        L.corner_sharpness[b + uint32_t(j)] == s_at[j]) {
      sharpness = s_at[j];
      return j;
    }
  }
  return -1;
}

// With infinitely sharp patches: regular when every span between infinitely sharp (or boundary)
// edges is a regular boundary (two faces, crease rule) or a regular corner (one face, corner
// rule), with nothing semi-sharp.
bool Builder::regular_vertex_inf(Level& L, const RefinedLevel& R, uint32_t v) const {
  const Topo& t = L.topo;
  if (plain_interior(L, R, v)) return true;
  const RingView g = ring(L, R, v);
  if (!g.manifold || !g.all_quads) return false;
  const SharpEdges e = sharp_edges(L, v);
  const float vs = R.vertex_sharpness[v];
  if (e.semi > 0 || (vs > 0.0f && vs < kInf)) return false;
  if (e.inf == 0) return g.faces == 4 && vs == 0.0f;
  if (!cuts_at_inf_sharp(L, R, v)) return false;  // a dart
  const size_t want = vs >= kInf || e.inf >= 3 ? 1 : 2;
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    bool sharp = false;
    span(L, R, t.vertex_corners[i], sharp, span_scratch_);
    if (span_scratch_.face.size() != want) return false;
  }
  return true;
}

// The four corners of quad f in ptex order (corner s at ptex square corner s).
void Builder::aligned_corners(const Level& L, const RefinedLevel& R, uint32_t f,
                              uint32_t c[4]) const {
  const uint32_t b = R.face_offsets[f];
  const uint32_t rot = L.param[f].rot;
  for (uint32_t s = 0; s < 4; ++s) c[s] = b + (s + 4 - rot) % 4;  // corner ids
}

void Builder::request(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
                      std::vector<uint8_t>& requested) {
  const RefinedLevel& R = S.level;
  const size_t nv = R.vertex_count(), nf = R.face_count();
  Level& L = levels_.emplace_back();

  // Depth wanted around each vertex.
  L.rem.assign(nv, 0);
  if (k == 0) {
    for (size_t v = 0; v < nv; ++v)
      L.rem[v] = uint8_t(depth_.empty() ? o_.depth : std::min<int>(depth_[v], o_.depth));
  } else {
    const Level& P = levels_[k - 1];
    auto dec = [](int d) { return uint8_t(d > 0 ? d - 1 : 0); };
    size_t i = 0;
    for (uint32_t f : S.parent_faces) {
      int d = 0;
      for (uint32_t c = P.level->face_offsets[f]; c < P.level->face_offsets[f + 1]; ++c)
        d = std::max<int>(d, P.rem[P.level->face_vertices[c]]);
      L.rem[i++] = dec(d);
    }
    for (uint32_t e : S.parent_edges)
      L.rem[i++] = dec(std::max(P.rem[P.level->edge_vertices[2 * size_t(e)]],
                                P.rem[P.level->edge_vertices[2 * size_t(e) + 1]]));
    for (uint32_t v : S.parent_vertices) L.rem[i++] = dec(P.rem[v]);
  }

  // Which faces this level covers, and their ptex placement.
  L.owned.assign(nf, 0);
  L.param.resize(nf);
  if (k == 0) {
    ptex_first_ = ptex_offsets(cage_);  // level 0 is the cage
    for (uint32_t f = 0; f < nf; ++f) {
      L.owned[f] = !R.face_hole[f];
      L.param[f].ptex = ptex_first_[f];
    }
  } else {
    const Level& P = levels_[k - 1];
    uint32_t child = 0;
    for (uint32_t f = 0; f < nf; ++f) {
      const uint32_t pf = S.face_parent[f];
      child = f > 0 && S.face_parent[f - 1] == pf ? child + 1 : 0;
      L.owned[f] = P.requested[pf] && !R.face_hole[f];
      const Level::Face& pp = P.param[pf];
      Level::Face& cp = L.param[f];
      if (k == 1 && P.level->face_offsets[pf + 1] - P.level->face_offsets[pf] != 4) {
        cp.ptex = pp.ptex + child;  // a non-quad's corner quad is a ptex face of its own
        cp.corner = uint8_t(child);
        cp.rot = 0;
      } else {
        const uint32_t q = (child + pp.rot) % 4;
        cp.ptex = pp.ptex;
        cp.corner = pp.corner;
        cp.rot = uint8_t(q);
        cp.depth = uint8_t(pp.depth + 1);
        cp.u = uint16_t(2 * pp.u + (q == 1 || q == 2));
        cp.v = uint16_t(2 * pp.v + (q >= 2));
      }
    }
  }

  if (!roles_.empty()) {
    if (k == 0) {
      L.role.assign(roles_.begin(), roles_.end());
    } else {
      L.role.resize(nf);
      for (uint32_t f = 0; f < nf; ++f) L.role[f] = levels_[k - 1].role[S.face_parent[f]];
    }
  }
  L.level = &R;
  if (h_) {  // where each vertex's depth comes from: itself, or what it was made from
    L.src_offsets.assign(1, 0);
    if (k == 0) {
      for (uint32_t v = 0; v < nv; ++v) L.src.push_back(v), L.src_offsets.push_back(v + 1);
    } else {
      const Level& P = levels_[k - 1];
      const RefinedLevel& PR = *P.level;
      for (uint32_t f : S.parent_faces)
        append_union(L.src, L.src_offsets, P,
                     std::span(PR.face_vertices.data() + PR.face_offsets[f],
                               PR.face_offsets[f + 1] - PR.face_offsets[f]));
      for (uint32_t e : S.parent_edges)
        append_union(L.src, L.src_offsets, P,
                     std::span(PR.edge_vertices.data() + 2 * size_t(e), 2));
      for (uint32_t v : S.parent_vertices) append_union(L.src, L.src_offsets, P, std::span(&v, 1));
    }
  }
  // A level where no vertex wants more depth refines nothing (faces are forced only at the
  // cage): its corner table, rings and tags wait for level_done, when level k - 1 is gone.
  L.deferred = k > 0 && std::all_of(L.rem.begin(), L.rem.end(), [](uint8_t d) { return d == 0; });
  if (!L.deferred) classify(k, S, adj, &requested);
  // Level k - 1 has given level k what it needs (depths, placement, sources).
  if (k > 0) {
    Level& P = levels_[k - 1];
    release(P.rem), release(P.requested), release(P.param), release(P.src), release(P.src_offsets);
    release(P.role);
  }
}

void Builder::classify(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
                       std::vector<uint8_t>* requested) {
  const RefinedLevel& R = S.level;
  const size_t nv = R.vertex_count(), nf = R.face_count();
  Level& L = levels_[k];
  L.topo = make_topo(R, adj);
  const Topo& t = L.topo;
  L.corner_sharpness = {adj.corner_edge, R.edge_sharpness.data()};
  L.vinfo.assign(nv, 0);
  // Irregular corners of covered faces; a face is refined while one of them wants depth.
  L.irregular.assign(nv, 0);
  std::vector<uint8_t> seen(nv, 0);
  L.requested.assign(nf, 0);
  L.force.assign(nf, 0);
  L.crease_edge.assign(nf, -1);
  L.crease_sharpness.assign(nf, 0.0f);
  auto tag = [&](uint32_t v) {
    if (!seen[v])
      seen[v] = 1, L.irregular[v] = o_.inf_sharp_patches ? !regular_vertex_inf(L, R, v)
                                                         : !regular_vertex(L, R, v);
  };
  for (uint32_t f = 0; f < nf; ++f) {
    if (!L.owned[f]) continue;
    const uint32_t b = R.face_offsets[f], e = R.face_offsets[f + 1];
    if (o_.single_crease_patches) {
      float sharp = 0;
      const int j = single_crease(L, R, f, sharp);
      if (j >= 0) {
        L.crease_edge[f] = int8_t(j), L.crease_sharpness[f] = sharp;
        for (uint32_t c = b; c < e; ++c) tag(R.face_vertices[c]);  // for their other faces
        continue;  // an exact patch as it is: never refined for its own sake
      }
    }
    // Non-quads go down once, and so do the faces next to them: patches need quads all round
    // their corners.
    bool force = e - b != 4 && k == 0, want = false;
    for (uint32_t c = b; c < e; ++c) {
      const uint32_t v = R.face_vertices[c];
      tag(v);
      want = want || (L.irregular[v] && L.rem[v] > 0);
      if (k == 0 && !force)
        for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1] && !force; ++i) {
          const uint32_t g = t.corner_face[t.vertex_corners[i]];
          force = R.face_offsets[g + 1] - R.face_offsets[g] != 4;
        }
    }
    L.force[f] = force;
    L.requested[f] = (want || force) && k < size_t(kMaxDepth) && (L.role.empty() || L.role[f]);
    if (requested) (*requested)[f] = L.requested[f];
  }
}

void Builder::level_done(size_t k, const SparseLevel& S, const LevelAdjacency& adj) {
  // Level k - 1 is gone (refine_sparse drops it before this call): its end caps can be made.
  emit_pending_caps();
  if (levels_[k].deferred) classify(k, S, adj, nullptr);
  emit(k, S);
  // What the next level needs stays (depths, requests, placement, sources); the rest goes.
  Level& L = levels_[k];
  L.topo = {};
  release(L.ring_slot), release(L.ring_edge), release(L.ring_diag), release(L.ring_face);
  release(L.vinfo), release(L.irregular), release(L.owned), release(L.crease_edge);
  release(L.crease_sharpness), release(L.force);
  L.corner_sharpness = {};
}

void GregoryCap::finish_topology(uint32_t first, uint32_t count) {
  // The union of the corners and rings in the order met, deduplicated through the slot map (a
  // stale slot never names a matching entry: the support's ids are distinct).
  support.clear();
  if (slots.size() < count) slots.resize(count);
  auto take = [&](uint32_t id) {
    if (id - first >= count) throw std::logic_error("patches: end-cap point off level");
    const uint32_t s = slots[id - first];
    if (s < support.size() && support[s] == id) return;
    slots[id - first] = uint32_t(support.size());
    support.push_back(id);
  };
  for (const Corner& k : c) {
    take(k.v);
    for (const uint32_t id : k.ring) take(id);
  }
  for (int i = 0; i < 4; ++i)
    for (Terms* t : {&p[i], &ep[i], &em[i]}) t->reset(support, slots.data(), first, count);
  const double pi = std::numbers::pi;
  for (Corner& k : c) {
    k.valence = k.faces + (k.boundary ? 1 : 0);
    k.regular = (k.faces << (k.boundary ? 1 : 0)) == 4 && !k.sharp;
    const double angle = k.regular ? 0.5 * pi : (k.boundary ? pi : 2.0 * pi) / std::max(k.faces, 1);
    k.cos_angle = k.regular ? 0.0 : std::cos(angle);
  }
  for (int i = 0; i < 4; ++i) {
    Corner& k = c[i];
    const Corner &next = c[(i + 1) & 3], &prev = c[(i + 3) & 3];
    k.fp_regular = k.regular && next.regular;
    k.fm_regular = k.regular && prev.regular;
    if (!k.boundary) continue;
    k.ep_on_boundary = k.face_in_ring == 0;
    k.em_on_boundary = k.face_in_ring == k.faces - 1;
    if (k.faces > 1) {
      // One of the corner's patch edges is a boundary: its two face points coincide.
      if (k.ep_on_boundary) k.fp_regular = k.fm_regular, k.fp_copied = !k.fp_regular;
      if (k.em_on_boundary) k.fm_regular = k.fp_regular, k.fm_copied = !k.fm_regular;
    } else {
      k.fp_regular = k.fm_regular = true;
    }
  }
}

// Tangent scale of OpenSubdiv's Gregory points: 16/n / (c + 5 + sqrt((c + 9)(c + 1))), c =
// cos(2 pi / n) (its table for n < 30 holds the same values).
double tangent_coefficient(int n) {
  const double ct = std::cos(2.0 * std::numbers::pi / n);
  return 16.0 / n / (ct + 5.0 + std::sqrt((ct + 9.0) * (ct + 1.0)));
}

void GregoryCap::edge_points(int i) {
  const Corner& k = c[i];
  const uint32_t v = k.v, next = c[(i + 1) & 3].v, prev = c[(i + 3) & 3].v;
  const std::vector<uint32_t>& r = k.ring;
  if (k.regular && !k.boundary) {
    p[i].add(v, 4.0 / 9.0);
    for (int m = 0; m < 4; ++m) p[i].add(r[2 * m], 1.0 / 9.0), p[i].add(r[2 * m + 1], 1.0 / 36.0);
    const int e_p = 2 * k.face_in_ring, e_m = 2 * ((k.face_in_ring + 1) & 3);
    const int o_p = 2 * ((k.face_in_ring + 2) & 3), o_m = 2 * ((k.face_in_ring + 3) & 3);
    ep[i].add(v, 4.0 / 9.0), ep[i].add(r[e_p], 2.0 / 9.0), ep[i].add(r[e_m], 1.0 / 9.0);
    ep[i].add(r[o_m], 1.0 / 9.0), ep[i].add(r[e_p + 1], 1.0 / 18.0);
    ep[i].add(r[o_m + 1], 1.0 / 18.0);
    em[i].add(v, 4.0 / 9.0), em[i].add(r[e_m], 2.0 / 9.0), em[i].add(r[e_p], 1.0 / 9.0);
    em[i].add(r[o_p], 1.0 / 9.0), em[i].add(r[e_p + 1], 1.0 / 18.0);
    em[i].add(r[e_m + 1], 1.0 / 18.0);
  } else if (k.regular) {  // regular boundary: two faces
    Terms& on = k.ep_on_boundary ? ep[i] : em[i];
    Terms& in = k.ep_on_boundary ? em[i] : ep[i];
    p[i].add(v, 2.0 / 3.0), p[i].add(r[0], 1.0 / 6.0), p[i].add(r[4], 1.0 / 6.0);
    on.add(v, 2.0 / 3.0), on.add(r[k.ep_on_boundary ? 0 : 4], 1.0 / 3.0);
    in.add(v, 4.0 / 9.0), in.add(r[2], 2.0 / 9.0), in.add(r[0], 1.0 / 9.0);
    in.add(r[4], 1.0 / 9.0), in.add(r[1], 1.0 / 18.0), in.add(r[3], 1.0 / 18.0);
  } else if (k.sharp || (k.boundary && k.faces == 1)) {
    // A sharp corner interpolates; a smooth one-face boundary follows its crease curve.
    if (k.sharp) {
      p[i].add(v, 1.0);
    } else {
      p[i].add(v, 4.0 / 6.0), p[i].add(next, 1.0 / 6.0), p[i].add(prev, 1.0 / 6.0);
    }
    ep[i].add(v, 2.0 / 3.0), ep[i].add(next, 1.0 / 3.0);
    em[i].add(v, 2.0 / 3.0), em[i].add(prev, 1.0 / 3.0);
  } else if (!k.boundary) {
    // Smooth interior: the limit position, and the limit tangent along each patch edge scaled
    // by OpenSubdiv's eigenvalue coefficient.
    const int n = k.valence;
    const double pc = 1.0 / (n * (n + 5.0)), tc = tangent_coefficient(n) * 0.5 / (n + 5.0);
    const double th = 2.0 * std::numbers::pi / n;
    std::vector<double> w(2 * size_t(n), 0.0);  // tangent along ring edge 0
    for (int m = 0; m < n; ++m) {
      const int mp = (m + n - 1) % n, mn = (m + 1) % n;
      const double cm = tc * std::cos(th * m);
      w[2 * mp] += 2 * cm, w[2 * mp + 1] += cm, w[2 * m] += 4 * cm, w[2 * m + 1] += cm;
      w[2 * mn] += 2 * cm;
    }
    p[i].add(v, n / (n + 5.0)), ep[i].add(v, n / (n + 5.0)), em[i].add(v, n / (n + 5.0));
    for (int m = 0; m < 2 * n; ++m) {
      const double pw = (m & 1) ? pc : 4 * pc;
      // Ep is the tangent rotated onto edge face_in_ring, Em onto the next edge.
      const int sp = (m + 2 * (n - k.face_in_ring)) % (2 * n);
      const int sm = (m + 2 * (2 * n - k.face_in_ring - 1)) % (2 * n);
      p[i].add(r[m], pw);
      ep[i].add(r[m], pw + w[sp]);
      em[i].add(r[m], pw + w[sm]);
    }
  } else {
    // Smooth boundary with three or more faces.
    const int nf = k.faces, n = k.valence, N = 2 * n - 1;
    const double th = std::numbers::pi / nf, ct = std::cos(th), st = std::sin(th);
    const double d = 1.0 / (3.0 * nf + ct);
    std::vector<double> pw(2 * size_t(n), 0.0), tw(2 * size_t(n), 0.0);
    pw[0] = 4.0 / 6.0, pw[1] = 1.0 / 6.0, pw[N] = 1.0 / 6.0;
    const double alpha0 = -((1.0 + 2.0 * ct) * std::sqrt(1.0 + ct)) * d / std::sqrt(1.0 - ct);
    tw[0] = -4.0 * st * d / 3.0, tw[1] = alpha0 / 3.0, tw[2] = st * d / 3.0, tw[N] = alpha0 / 3.0;
    for (int m = 1; m < n - 1; ++m) {
      tw[1 + 2 * m] = 4.0 * std::sin(th * m) * d / 3.0;
      tw[2 + 2 * m] = (std::sin(th * m) + std::sin(th * (m + 1))) * d / 3.0;
    }
    // Weight index 0 is the corner, index m >= 1 ring point m - 1.
    auto put = [&](Terms& out, const std::vector<double>& wt) {
      out.add(v, wt[0]);
      for (int m = 1; m <= N; ++m) out.add(r[size_t(m) - 1], wt[size_t(m)]);
    };
    put(p[i], pw);
    auto along = [&](int edge, Terms& out) {
      const double a = th * edge, ca = std::cos(a), sa = std::sin(a);
      std::vector<double> wt(2 * size_t(n));
      for (int m = 0; m <= N; ++m) wt[size_t(m)] = tw[size_t(m)] * sa;
      wt[0] += pw[0];
      wt[1] += pw[1] + ca / 6.0;
      wt[size_t(N)] += pw[size_t(N)] - ca / 6.0;
      put(out, wt);
    };
    if (k.ep_on_boundary)
      ep[i].add(v, 2.0 / 3.0), ep[i].add(r[0], 1.0 / 3.0);
    else
      along(k.face_in_ring, ep[i]);
    if (k.em_on_boundary)
      em[i].add(v, 2.0 / 3.0), em[i].add(r[size_t(N) - 1], 1.0 / 3.0);
    else
      along((k.face_in_ring + 1) % n, em[i]);
  }
}

uint32_t GregoryCap::emit_face_point(int i, bool plus, uint32_t p_row, uint32_t e_near,
                                     uint32_t e_far, StencilTable& table,
                                     detail::SharedWeights& shared) const {
  const Corner& k = c[i];
  const int far = plus ? (i + 1) & 3 : (i + 3) & 3;
  uint32_t ids[8];  // at most 3 corner points and 4 ring points
  float row[8];
  uint32_t terms = 0;
  auto put = [&](uint32_t id, double w) {
    if (w != 0.0) ids[terms] = id, row[terms++] = float(w);
  };
  if (plus ? k.fp_regular : k.fm_regular) {
    put(k.v, 4.0 / 9.0), put(c[(i + 3) & 3].v, 2.0 / 9.0), put(c[(i + 1) & 3].v, 2.0 / 9.0);
    put(c[(i + 2) & 3].v, 1.0 / 9.0);
  } else {
    // Loop et al.'s face point: the corner's limit point and the two edge points meeting the
    // patch edge, and the rotation of the ring across it.
    const double cn = k.cos_angle, cf = c[far].cos_angle, sign = plus ? 1.0 : -1.0;
    put(kCapRef | p_row, cf / 3.0);
    put(kCapRef | e_near, (3.0 - 2.0 * cn - cf) / 3.0);
    put(kCapRef | e_far, 2.0 * cn / 3.0);
    const int n = k.valence, edge = plus ? k.face_in_ring : (k.face_in_ring + 1) % n;
    const int prev = (edge + n - 1) % n, next = (edge + 1) % n;
    put(k.ring[2 * size_t(prev)], -sign / 9.0);
    put(k.ring[2 * size_t(prev) + 1], -sign / 18.0);
    put(k.ring[2 * size_t(edge) + 1], sign / 18.0);
    put(k.ring[2 * size_t(next)], sign / 9.0);
  }
  table.indices.insert(table.indices.end(), ids, ids + terms);
  table.weight_offsets.push_back(shared.add(table.weights, row, terms));
  table.offsets.push_back(uint32_t(table.indices.size()));
  return uint32_t(table.size() - 1);
}

// Room in the table's arrays for this level's patches, so they grow once a level instead of
// doubling (each doubling a copy into fresh pages, beside the old array).
// Room in v for `more` elements beyond its size (exactly: no doubling).
template <class V>
void reserve_more(V& v, size_t more) {
  if (v.capacity() < v.size() + more) v.reserve(v.size() + more);
}

void Builder::reserve_output(const Level& L, const RefinedLevel& R) {
  size_t regular = 0, caps = 0;
  for (uint32_t f = 0; f < R.face_count(); ++f) {
    if (!L.owned[f] || (L.requested[f] && !h_) || (!L.role.empty() && L.role[f] < 2)) continue;
    const uint32_t b = R.face_offsets[f];
    if (R.face_offsets[f + 1] - b != 4 || L.force[f]) continue;
    bool reg = L.crease_edge[f] >= 0;
    if (!reg) {
      reg = true;
      for (uint32_t c = b; c < b + 4; ++c) reg = reg && !L.irregular[R.face_vertices[c]];
    }
    ++(reg ? regular : caps);
  }
  // The counts are exact for this level (regular and caps are the patches emit makes). A
  // level's regular patches go to arrays of their own, sized exactly and joined in build(),
  // when the levels' topology is gone: no room is held ahead of the levels to come, and no
  // array is copied while two levels are held (room guessed a few patches short copied car L6's
  // 1.4 MB of points at its last level, its peak).
  level_points_.emplace_back().reserve(16 * regular);
  level_params_.emplace_back().reserve(regular);
  reserve_more(out_.gregory_params, caps);
}

void Builder::reserve_caps(size_t caps) {
  PatchTable& out = out_;
  reserve_more(out.gregory_points, 20 * caps);
  // Rows and entries at the rate of the end caps so far; before any, the rate every shared cage
  // shows (8.0-8.3 corner rows of about 60 entries and 8 face rows of about 40 per end cap: a
  // corner's three points are shared by the end caps around it). The margin is smaller than the
  // patches': a rate too low doubles an array, too high is held to the end.
  const size_t made = out.gregory_points.size() / 20;
  auto rate = [&](size_t so_far, size_t first_guess_x4) {
    return made ? (so_far * caps + made - 1) / made : (first_guess_x4 * caps + 3) / 4;
  };
  auto room_caps = [](auto& v, size_t more) {
    if (v.capacity() < v.size() + more) v.reserve(v.size() + more + more / 16);
  };
  for (StencilTable* g : {&out.gregory_stencils, &out.gregory_face_stencils}) {
    const bool corner = g == &out.gregory_stencils;
    const size_t rows = rate(g->size(), corner ? 33 : 32);
    room_caps(g->offsets, rows), room_caps(g->weight_offsets, rows);
    room_caps(g->indices, rate(g->indices.size(), corner ? 240 : 160));
    // One shared row per corner row of the level (emit_cap empties it at the level's first).
    if (corner && shared_.capacity() < rows) shared_.reserve(rows + rows / 16);
  }
}

void Builder::emit(size_t k, const SparseLevel& S) {
  const auto t0 = std::chrono::steady_clock::now();
  PatchTable& out = out_;
  PatchStats* stats = stats_;
  if (stats && stats->regular_by_level.size() <= k) {
    stats->regular_by_level.resize(k + 1, 0);
    stats->gregory_by_level.resize(k + 1, 0);
  }
  std::vector<std::vector<uint32_t>>& node_of_level = node_of_level_;
  static constexpr int kPos[4][2] = {{1, 1}, {2, 1}, {2, 2}, {1, 2}};
  static constexpr int kD1[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};  // towards corner i + 1
  static constexpr int kD2[4][2] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};  // towards corner i - 1
  {
    Level& L = levels_[k];
    const RefinedLevel& R = S.level;
    const Topo& t = L.topo;
    const uint32_t off = level_offsets_.back();
    std::vector<uint32_t>& node_of = node_of_level.emplace_back();
    if (h_) {
      // Nodes: every face this level covers; a child of the node of the face it came from.
      node_of.assign(R.face_count(), kNone);
      for (uint32_t f = 0; f < R.face_count(); ++f) {
        if (!L.owned[f]) continue;
        const uint32_t n = uint32_t(h_->node_level.size());
        node_of[f] = n;
        h_->node_level.push_back(uint8_t(k));
        h_->node_force.push_back(L.force[f]);
        h_->node_patch.push_back(kNone);
        h_->node_first_child.push_back(kNone);
        h_->node_children.push_back(0);
        h_->node_neighbours.insert(h_->node_neighbours.end(), {kNone, kNone, kNone, kNone});
        // Depth sources of the irregular corners (none for a single-crease face).
        std::vector<uint32_t> irregular;
        for (uint32_t c = R.face_offsets[f]; c < R.face_offsets[f + 1]; ++c)
          if (L.irregular[R.face_vertices[c]] && L.crease_edge[f] < 0)
            irregular.push_back(R.face_vertices[c]);
        append_union(h_->node_src, h_->node_src_offsets, L, irregular);
        if (k == 0) {
          h_->roots.push_back(n);
        } else {
          const uint32_t parent = node_of_level[k - 1][S.face_parent[f]];
          if (h_->node_first_child[parent] == kNone) h_->node_first_child[parent] = n;
          ++h_->node_children[parent];
        }
      }
    }
    reserve_output(L, R);
    size_t regular_before = 0;  // the hierarchy's regular index of this level's first patch
    for (size_t i = 0; i + 1 < level_params_.size(); ++i) regular_before += level_params_[i].size();
    for (uint32_t f = 0; f < R.face_count(); ++f) {
      if (!L.owned[f] || (L.requested[f] && !h_) || (!L.role.empty() && L.role[f] < 2)) continue;
      if (R.face_offsets[f + 1] - R.face_offsets[f] != 4 || L.force[f]) {
        if (h_) continue;  // a node without a patch of its own: always refined
        throw std::logic_error("patches: a non-quad face was left unrefined");
      }
      uint32_t corner[4], a[4];
      aligned_corners(L, R, f, corner);
      const bool crease = L.crease_edge[f] >= 0;
      bool regular = true;
      for (int i = 0; i < 4; ++i) {
        a[i] = R.face_vertices[corner[i]];
        regular = regular && (crease || !L.irregular[a[i]]);
      }
      PatchParam pp;
      const Level::Face& fp = L.param[f];
      pp.ptex = fp.ptex, pp.u = fp.u, pp.v = fp.v, pp.depth = fp.depth;
      pp.level = uint8_t(k), pp.base_face = base_face(fp.ptex), pp.corner = fp.corner;
      for (int e = 0; e < 4; ++e) {
        const uint32_t tw = t.corner_twin[corner[e]];
        const bool sharp_cut = o_.inf_sharp_patches && L.corner_sharpness[corner[e]] >= kInf &&
                               regular && cuts_at_inf_sharp(L, R, a[e]);
        if (tw == kNone || sharp_cut) pp.boundary |= uint8_t(1u << e);
        if (tw < kNonManifold) {
          const uint32_t g = t.corner_face[tw];
          if (L.owned[g] && L.requested[g]) pp.transition |= uint8_t(1u << e);
          if (h_ && L.owned[g])
            h_->node_neighbours[4 * size_t(node_of[f]) + size_t(e)] = node_of[g];
        }
      }
      if (h_)
        h_->node_patch[node_of[f]] = regular
                                         ? uint32_t(regular_before + level_params_.back().size())
                                         : kPatchGregory | uint32_t(out.gregory_params.size());
      bool plain4 = regular && !crease;
      for (int i = 0; i < 4 && plain4; ++i) plain4 = plain_interior(L, R, a[i]);
      if (plain4) {
        // The common case: four plain interior corners, so no boundary, no phantom point, and
        // each corner's three other faces are reached through the twins from the patch face.
        // Points are put as the general case below puts them (same values, same order).
        const uint32_t* fv = R.face_vertices.data();
        uint32_t grid[16];
        for (int i = 0; i < 4; ++i) {
          const uint32_t c1 = t.corner_twin[t.corner_prev[corner[i]]];
          const uint32_t c2 = t.corner_twin[t.corner_prev[c1]];
          const uint32_t c3 = t.corner_twin[t.corner_prev[c2]];
          const int x = kPos[i][0], y = kPos[i][1];
          const int* d1 = kD1[i];
          const int* d2 = kD2[i];
          auto put = [&](int px, int py, uint32_t p) { grid[4 * py + px] = off + p; };
          put(x, y, a[i]);
          put(x - d1[0], y - d1[1], fv[t.corner_next[c2]]);
          put(x - d2[0], y - d2[1], fv[t.corner_next[c3]]);
          put(x - d1[0] - d2[0], y - d1[1] - d2[1], fv[t.corner_next[t.corner_next[c2]]]);
          put(x + d2[0] - d1[0], y + d2[1] - d1[1], fv[t.corner_next[t.corner_next[c1]]]);
          put(x + d1[0] - d2[0], y + d1[1] - d2[1], fv[t.corner_next[t.corner_next[c3]]]);
        }
        pp.type = PatchType::regular;
        level_points_.back().insert(level_points_.back().end(), grid, grid + 16);
        level_params_.back().push_back(pp);
        if (stats) ++stats->regular_by_level[k];
      } else if (regular) {
        RingView rings[4];
        Ring* spans = spans_;
        int in_ring[4];
        bool cut[4], plain[4];
        uint32_t near_edge[4][4], near_diag[4][4];  // plain corners' rings, from the patch face
        // Rings are cached in growing arrays: make all four before holding views into them.
        // Plain interior corners (valence 4, no sharpness, quads) need no cached ring: their
        // faces are reached through the twins, starting at the patch face.
        for (int i = 0; i < 4; ++i) {
          plain[i] = plain_interior(L, R, a[i]);
          cut[i] = !plain[i] && cuts_at_inf_sharp(L, R, a[i]);
          if (!cut[i] && !plain[i]) ring(L, R, a[i]);
        }
        const uint32_t* fv = R.face_vertices.data();
        for (int i = 0; i < 4; ++i) {
          if (plain[i]) {
            uint32_t c = corner[i];
            for (int m = 0; m < 4; ++m) {
              const uint32_t n = t.corner_next[c];
              near_edge[i][m] = fv[n], near_diag[i][m] = fv[t.corner_next[n]];
              c = t.corner_twin[t.corner_prev[c]];
            }
            RingView& g = rings[i];
            g.edge_end = near_edge[i], g.diagonal = near_diag[i], g.face = nullptr;
            g.faces = 4, g.boundary = false, g.manifold = g.all_quads = true;
            in_ring[i] = 0;
            continue;
          }
          if (cut[i]) {
            // Cut at infinitely sharp edges: the patch sees its span, as a boundary.
            bool sharp = false;
            span(L, R, corner[i], sharp, spans[i]);
            RingView& g = rings[i];
            g.edge_end = spans[i].edge_end.data();
            g.diagonal = spans[i].diagonal.data();
            g.face = spans[i].face.data();
            g.faces = uint32_t(spans[i].face.size());
            g.boundary = spans[i].boundary;
            g.manifold = g.all_quads = true;
          } else {
            rings[i] = ring(L, R, a[i]);
          }
          in_ring[i] = rings[i].index_of(f);
          if (in_ring[i] < 0) throw std::logic_error("patches: face missing in ring");
        }
        pp.type = crease ? PatchType::single_crease : PatchType::regular;
        if (crease) {
          pp.crease_edge = uint8_t((L.crease_edge[f] + L.param[f].rot) % 4);
          pp.sharpness = L.crease_sharpness[f];
        }
        uint32_t grid[16];
        bool have[16] = {};
        auto put = [&](int x, int y, uint32_t p) {
          grid[4 * y + x] = off + p;
          have[4 * y + x] = true;
        };
        for (int i = 0; i < 4; ++i) {
          const RingView& g = rings[i];
          const size_t j = size_t(in_ring[i]);
          const int x = kPos[i][0], y = kPos[i][1];
          const int* d1 = kD1[i];
          const int* d2 = kD2[i];
          auto edge = [&](size_t m, int px, int py) {
            const size_t id = (j + m) % 4;
            if (id < g.edges()) put(px, py, g.edge_end[id]);
          };
          auto diag = [&](size_t m, int px, int py) {
            const size_t id = (j + m) % 4;
            if (id < g.faces) put(px, py, g.diagonal[id]);
          };
          put(x, y, a[i]);
          edge(2, x - d1[0], y - d1[1]);
          edge(3, x - d2[0], y - d2[1]);
          diag(2, x - d1[0] - d2[0], y - d1[1] - d2[1]);
          diag(1, x + d2[0] - d1[0], y + d2[1] - d1[1]);
          diag(3, x + d1[0] - d2[0], y + d1[1] - d2[1]);
        }
        for (int y = 0; y < 4; ++y)
          for (int x = 0; x < 4; ++x) {
            if (have[4 * y + x]) continue;
            const bool phantom = (y == 0 && (pp.boundary & 1)) || (x == 3 && (pp.boundary & 2)) ||
                                 (y == 3 && (pp.boundary & 4)) || (x == 0 && (pp.boundary & 8));
            if (!phantom) throw std::logic_error("patches: a regular patch misses a point");
            grid[4 * y + x] = off + a[0];
          }
        level_points_.back().insert(level_points_.back().end(), grid, grid + 16);
        level_params_.back().push_back(pp);
        if (stats) ++stats->regular_by_level[k];
      } else {
        pp.type = PatchType::gregory;
        // Its corners' fans, for emit_pending_caps.
        for (int i = 0; i < 4; ++i) {
          PendingCorner cc;
          const Ring& g = spans_[i];
          bool sharp = false;
          span(L, R, corner[i], sharp, spans_[i]);
          if (!g.all_quads) throw std::logic_error("patches: an end cap next to a non-quad");
          const uint32_t nf = uint32_t(g.face.size());
          cc.a = a[i];
          const auto least = std::min_element(g.face.begin(), g.face.end());
          cc.fan = *least, cc.fan_at = uint32_t(least - g.face.begin());
          cc.faces = nf & 0x3fffffffu;  // a level's faces are fewer than 2^30 (corners are 32-bit)
          cc.boundary = g.boundary, cc.sharp = sharp;
          cc.face_in_ring = uint32_t(std::find(g.face.begin(), g.face.end(), f) - g.face.begin());
          // The same fan met again: its ring is the kept one turned to start where this one
          // does (a boundary fan's always starts at its boundary).
          const uint64_t key = uint64_t(off + a[i]) << 32 | cc.fan;
          const auto it = nf >= kLongFan ? long_fans_.find(key) : long_fans_.end();
          if (it != long_fans_.end() && (!g.boundary || it->second.second == cc.fan_at)) {
            cc.ring_at = it->second.first;
            cc.ring_rot = (it->second.second + nf - cc.fan_at) % nf;
          } else {
            if (pending_rings_.size() > UINT32_MAX - 2 * size_t(nf) - 1)
              throw InputError("patches: end-cap rings of more than 2^32 points");
            cc.ring_at = uint32_t(pending_rings_.size());
            if (nf >= kLongFan) long_fans_[key] = {cc.ring_at, cc.fan_at};
            for (size_t m = 0; m < nf; ++m) {
              pending_rings_.push_back(off + g.edge_end[m]);
              pending_rings_.push_back(off + g.diagonal[m]);
            }
            if (g.boundary) pending_rings_.push_back(off + g.edge_end.back());
          }
          pending_corners_.push_back(cc);
        }
        out.gregory_params.push_back(pp);
        if (stats) ++stats->gregory_by_level[k];
      }
    }
  }
  if (pending_corners_.size() / 4 > (pending_levels_.empty() ? 0 : pending_levels_.back().caps_end))
    pending_levels_.push_back({uint32_t(k), level_offsets_.back(), uint32_t(S.level.vertex_count()),
                               pending_corners_.size() / 4});
  level_offsets_.push_back(level_offsets_.back() + uint32_t(S.level.vertex_count()));
  emit_ms_ += ms_since(t0);
}

void Builder::emit_pending_caps() {
  GregoryCap& cap = cap_;
  size_t first = 0;
  for (const PendingLevel& pl : pending_levels_) {
    reserve_caps(pl.caps_end - first);
    for (size_t e = first; e < pl.caps_end; ++e) {
      cap.reset();
      uint32_t a[4];
      for (int i = 0; i < 4; ++i) {
        const PendingCorner& pc = pending_corners_[4 * e + size_t(i)];
        GregoryCap::Corner& cc = cap.c[i];
        a[i] = pc.a;
        cc.v = pl.first_point + pc.a;
        cc.fan = pc.fan, cc.fan_at = int(pc.fan_at), cc.faces = int(pc.faces);
        cc.face_in_ring = int(pc.face_in_ring), cc.boundary = pc.boundary, cc.sharp = pc.sharp;
        // The kept ring turned by ring_rot faces (a boundary ring's last point is never turned:
        // boundary rings are shared only unturned).
        cc.ring.resize(2 * size_t(pc.faces) + pc.boundary);
        pending_rings_.copy(pc.ring_at, cc.ring.size(), cc.ring.data());
        std::rotate(cc.ring.begin(), cc.ring.begin() + 2 * long(pc.ring_rot),
                    cc.ring.begin() + 2 * long(pc.faces));
      }
      cap.finish_topology(pl.first_point, pl.points);
      uint32_t ids[20];
      emit_cap(pl.level, pl.points, a, ids);
      out_.gregory_points.insert(out_.gregory_points.end(), ids, ids + 20);
    }
    first = pl.caps_end;
  }
  pending_corners_.release(), pending_rings_.release(), release(pending_levels_);
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>>().swap(long_fans_);
}

void Builder::emit_cap(size_t k, uint32_t count, const uint32_t a[4], uint32_t ids[20]) {
  GregoryCap& cap = cap_;
  StencilTable& corners = out_.gregory_stencils;
  if (shared_level_ != k) {
    shared_head_.assign(count, kNone);
    shared_.clear();
    shared_level_ = k;
  }
  auto find = [&](uint32_t v, uint32_t fan, uint32_t to) {
    for (uint32_t e = shared_head_[v]; e != kNone; e = shared_[e].next)
      if (shared_[e].fan == fan && shared_[e].to == to) return shared_[e].row;
    return kNone;
  };
  uint32_t rows[4][3];  // P, Ep, Em of each corner
  for (int i = 0; i < 4; ++i) {
    const GregoryCap::Corner& c = cap.c[i];
    // Ep runs along ring edge face_in_ring, Em along the next; an interior fan's ring starts at
    // the patch's face, so its edges are counted from the fan's smallest face (not by their far
    // ends: two edges may join the same two points).
    auto edge = [&](int m) {
      return uint32_t(c.boundary ? m : (m - c.fan_at + 2 * c.faces) % c.faces);
    };
    const uint32_t to[3] = {kNone, edge(c.face_in_ring), edge(c.face_in_ring + 1)};
    bool made = false;
    for (int j = 0; j < 3; ++j) {
      rows[i][j] = find(a[i], c.fan, to[j]);
      if (rows[i][j] != kNone) continue;
      if (!made) cap.edge_points(i), made = true;
      const Terms& t = j == 0 ? cap.p[i] : j == 1 ? cap.ep[i] : cap.em[i];
      rows[i][j] = cap.emit_row(t, corners, corner_weights_[j]);
      shared_.push_back({c.fan, to[j], rows[i][j], shared_head_[a[i]]});
      shared_head_[a[i]] = uint32_t(shared_.size() - 1);
    }
  }
  StencilTable& faces = out_.gregory_face_stencils;
  for (int i = 0; i < 4; ++i) {
    const GregoryCap::Corner& c = cap.c[i];
    const int next = (i + 1) & 3, prev = (i + 3) & 3;
    uint32_t fp = kNone, fm = kNone;
    // On a boundary patch edge both face points are the same point.
    if (!c.fp_copied)
      fp = cap.emit_face_point(i, true, rows[i][0], rows[i][1], rows[next][2], faces,
                               face_weights_[0]);
    if (!c.fm_copied)
      fm = cap.emit_face_point(i, false, rows[i][0], rows[i][2], rows[prev][1], faces,
                               face_weights_[1]);
    if (c.fp_copied) fp = fm;
    if (c.fm_copied) fm = fp;
    ids[5 * i] = rows[i][0], ids[5 * i + 1] = rows[i][1], ids[5 * i + 2] = rows[i][2];
    ids[5 * i + 3] = kCapRef | fp, ids[5 * i + 4] = kCapRef | fm;
  }
}

// End-cap points come after every level's, corner points first: their ids, counted from 0 in
// each table and marked kCapRef where they could be taken for something else, become global.
void resolve_cap_points(PatchTable& t) {
  const uint64_t corners = t.level_offsets.back(), faces = corners + t.gregory_stencils.size();
  if (faces + t.gregory_face_stencils.size() >= kCapRef)
    throw InputError("patches: more than 2^31 points");
  for (uint32_t& p : t.gregory_points)
    p = uint32_t(p & kCapRef ? faces + (p & ~kCapRef) : corners + p);
  for (uint32_t& p : t.gregory_face_stencils.indices)
    if (p & kCapRef) p = uint32_t(corners + (p & ~kCapRef));
}

// prune_points gives a level's spare room back only past this many bytes.
constexpr size_t kShrinkBytes = size_t(4) << 20;

// Drops the refined points no patch uses, directly or through a later level's stencils (the
// sparse refinement makes whole rings around what it refines; its lean runs already leave out
// the rows nothing can read, so every shared cage's whole-cage build needs all that is left, and
// then nothing is renumbered). Cage points stay: they are the input. Renumbers in place, keeping
// each level's order (the regular patches' points are each level's array, not yet joined).
// O(stencil entries).
void prune_points(PatchTable& t, std::span<std::vector<uint32_t>> regular_points) {
  const size_t nl = t.level_offsets.size() - 1;  // levels, the cage included
  std::vector<uint8_t> need(t.level_offsets.back(), 0);
  for (const std::vector<uint32_t>& level : regular_points)
    for (const uint32_t p : level) need[p] = 1;
  for (const uint32_t p : t.gregory_stencils.indices) need[p] = 1;
  for (const uint32_t p : t.gregory_face_stencils.indices)
    if (!(p & kCapRef)) need[p] = 1;
  for (size_t k = nl - 1; k >= 1; --k) {
    const StencilTable& s = t.level_stencils[k - 1];
    const uint32_t base = t.level_offsets[k], prev = t.level_offsets[k - 1];
    for (size_t i = 0; i < s.size(); ++i)
      if (need[base + i])
        for (uint32_t j = s.offsets[i]; j < s.offsets[i + 1]; ++j) need[prev + s.indices[j]] = 1;
  }
  // Every point needed: the ids stay as they are.
  if (std::all_of(need.begin() + t.level_offsets[1], need.end(), [](uint8_t x) { return x != 0; }))
    return;
  // New global ids; the cage keeps its own.
  std::vector<uint32_t> id(t.level_offsets.back(), kNone);
  std::vector<uint32_t> offsets(nl + 1, 0);
  for (uint32_t p = 0; p < t.level_offsets[1]; ++p) id[p] = p;
  offsets[1] = t.level_offsets[1];
  for (size_t k = 1; k < nl; ++k) {
    StencilTable& s = t.level_stencils[k - 1];
    const uint32_t base = t.level_offsets[k], prev = t.level_offsets[k - 1];
    const size_t n = s.size();
    const bool shared = s.shared();
    uint32_t kept = 0, at = 0, begin = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t end = s.offsets[i + 1];  // read before the compaction writes over it
      if (!need[base + i]) {
        begin = end;
        continue;
      }
      id[base + i] = offsets[k] + kept;
      for (uint32_t j = begin; j < end; ++j, ++at) {
        s.indices[at] = id[prev + s.indices[j]] - offsets[k - 1];
        if (!shared) s.weights[at] = s.weights[j];
      }
      if (shared) s.weight_offsets[kept] = s.weight_offsets[i];
      s.offsets[++kept] = at;
      begin = end;
    }
    s.offsets.resize(kept + 1), s.indices.resize(at);
    if (shared)
      s.weight_offsets.resize(kept);
    else
      s.weights.resize(at);
    // Giving the room back means a copy into fresh pages (the kernel's page faults cost more
    // than the copy): only when it frees enough to matter. Region tables are copied into the
    // merged table anyway.
    if ((s.indices.capacity() - at) * sizeof(uint32_t) > kShrinkBytes) {
      s.offsets.shrink_to_fit(), s.indices.shrink_to_fit(), s.weights.shrink_to_fit();
      s.weight_offsets.shrink_to_fit();
    }
    offsets[k + 1] = offsets[k] + kept;
  }
  for (std::vector<uint32_t>& level : regular_points)
    for (uint32_t& p : level) p = id[p];
  for (uint32_t& p : t.gregory_stencils.indices) p = id[p];
  for (uint32_t& p : t.gregory_face_stencils.indices)
    if (!(p & kCapRef)) p = id[p];
  t.level_offsets = std::move(offsets);
}

void Builder::build(PatchTable& out, SparseRefinement& r, PatchStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  // The walking state goes first: the table is finished with only itself held.
  release(levels_);
  emit_pending_caps();
  release(shared_), release(shared_head_), cap_ = GregoryCap{};
  out = std::move(out_);
  out.options = o_.subdiv;
  out.level_offsets = std::move(level_offsets_);
  out.level_stencils = std::move(r.stencils);
  prune_points(out, level_points_);
  // The levels' regular patches joined, each level's arrays freed as they are copied.
  size_t n = 0;
  for (const std::vector<PatchParam>& p : level_params_) n += p.size();
  out.regular_points.reserve(16 * n), out.regular_params.reserve(n);
  for (size_t k = 0; k < level_params_.size(); ++k) {
    out.regular_points.insert(out.regular_points.end(), level_points_[k].begin(),
                              level_points_[k].end());
    out.regular_params.insert(out.regular_params.end(), level_params_[k].begin(),
                              level_params_[k].end());
    release(level_points_[k]), release(level_params_[k]);
  }
  out.ptex_count = ptex_first_.back();
  out.ptex_of_face = std::move(ptex_first_);
  resolve_cap_points(out);
  if (stats) {
    stats->regular_by_level.resize(out.level_offsets.size() - 1, 0);
    stats->gregory_by_level.resize(out.level_offsets.size() - 1, 0);
    stats->points = out.point_count();
    stats->patches_ms = emit_ms_ + ms_since(t0);
  }
}

}  // namespace

std::vector<float> PatchTable::points(std::span<const float> cage) const {
  std::vector<float> out(3 * point_count());
  points(cage, out);
  return out;
}

void PatchTable::points(std::span<const float> cage, std::span<float> out) const {
  if (selection)
    throw InputError("patches: a selection has no points of its own; use its hierarchy's");
  if (cage.size() != 3 * size_t(level_offsets.at(1)))
    throw InputError(fmt::format("patches: {} cage coordinates for {} points", cage.size(),
                                 3 * size_t(level_offsets.at(1))));
  if (out.size() != 3 * point_count())
    throw InputError(
        fmt::format("patches: room for {} coordinates, {} needed", out.size(), 3 * point_count()));
  std::copy(cage.begin(), cage.end(), out.begin());
  for (size_t k = 0; k < level_stencils.size(); ++k)
    apply_stencils(level_stencils[k], out.data() + 3 * size_t(level_offsets[k]),
                   out.data() + 3 * size_t(level_offsets[k + 1]), 3);
  const size_t corners = level_offsets.back(), faces = corners + gregory_stencils.size();
  if (gregory_stencils.size())
    apply_stencils(gregory_stencils, out.data(), out.data() + 3 * corners, 3);
  if (gregory_face_stencils.size())
    apply_stencils(gregory_face_stencils, out.data(), out.data() + 3 * faces, 3);
}

namespace {

void check_depth(const PatchOptions& options) {
  if (options.depth < 0 || options.depth > 12)
    throw InputError(fmt::format("patches: depth {} out of range (0-12)", options.depth));
}

// Runs the isolation with `b` deciding each level (and emitting its patches); the levels are
// dropped as it goes, only the stencils come back.
SparseRefinement isolate(const Mesh& cage, const PatchOptions& options, Builder& b) {
  return refine_sparse(
      cage, options.subdiv,
      [&](size_t k, const SparseLevel& S, const LevelAdjacency& a, std::vector<uint8_t>& req) {
        b.request(k, S, a, req);
      },
      false,
      [&](size_t k, const SparseLevel& S, const LevelAdjacency& a) { b.level_done(k, S, a); });
}

}  // namespace

PatchHierarchy build_patch_hierarchy(const Mesh& cage, const PatchOptions& options) {
  check_depth(options);
  PatchHierarchy h;
  Builder b(cage, options, {}, &h);
  SparseRefinement r = isolate(cage, options, b);
  b.build(h.table, r, nullptr);
  return h;
}

PatchTable select_patches(const PatchHierarchy& h, std::span<const uint8_t> vertex_depth) {
  const PatchTable& full = h.table;
  const size_t nv = full.level_offsets.size() > 1 ? full.level_offsets[1] : 0;
  if (vertex_depth.size() != nv)
    throw InputError(
        fmt::format("select patches: {} depths for {} cage vertices", vertex_depth.size(), nv));
  const size_t nn = h.node_count();
  // Pass 1: which nodes go deeper.
  std::vector<uint8_t> refined(nn, 0);
  std::vector<uint32_t> stack(h.roots.rbegin(), h.roots.rend()), leaves;
  while (!stack.empty()) {
    const uint32_t n = stack.back();
    stack.pop_back();
    bool deeper = h.node_force[n] != 0;
    for (uint32_t i = h.node_src_offsets[n]; i < h.node_src_offsets[n + 1] && !deeper; ++i)
      deeper = vertex_depth[h.node_src[i]] > h.node_level[n];
    if (deeper && h.node_first_child[n] != kNone) {
      refined[n] = 1;
      for (uint32_t c = h.node_children[n]; c-- > 0;) stack.push_back(h.node_first_child[n] + c);
    } else {
      if (h.node_patch[n] == kNone) throw std::logic_error("select patches: a node has no patch");
      leaves.push_back(n);
    }
  }
  // Pass 2: copy the leaves' patches, with their transition bits for this selection.
  PatchTable out;
  out.selection = true;
  out.options = full.options;
  out.level_offsets = full.level_offsets;
  out.ptex_count = full.ptex_count;
  out.ptex_of_face = full.ptex_of_face;
  for (const uint32_t n : leaves) {
    const uint32_t p = h.node_patch[n];
    const bool cap = p & kPatchGregory;
    const uint32_t i = p & ~kPatchGregory;
    PatchParam pp = cap ? full.gregory_params[i] : full.regular_params[i];
    pp.transition = 0;
    for (int e = 0; e < 4; ++e) {
      const uint32_t g = h.node_neighbours[4 * size_t(n) + size_t(e)];
      if (g != kNone && refined[g]) pp.transition |= uint8_t(1u << e);
    }
    if (cap) {
      out.gregory_params.push_back(pp);
      out.gregory_points.insert(out.gregory_points.end(),
                                full.gregory_points.begin() + 20 * long(i),
                                full.gregory_points.begin() + 20 * long(i) + 20);
    } else {
      out.regular_params.push_back(pp);
      out.regular_points.insert(out.regular_points.end(),
                                full.regular_points.begin() + 16 * long(i),
                                full.regular_points.begin() + 16 * long(i) + 16);
    }
  }
  return out;
}

namespace {

// Region builds (cages of many faces): the cage is cut into regions of about `batch` faces,
// grown breadth-first so they stay compact, and each region is isolated on its own sub-cage:
// the region's faces (role 2: their patches are emitted), two rings of faces around them (role
// 1: refined where they want to be, since the region's patches need their transition bits and
// the rings those refinements make) and one more ring (role 0: context, never refined for its
// own sake, so that every vertex of a role-1 face has its whole ring and is classified as in the
// whole cage). Everything a region's patches use depends only on the faces within one ring of
// it (the support of a face's limit surface), so the patches and their points equal the whole
// cage's; the working memory is a region's instead of a whole level's. Each region's pruned
// table is appended level by level with its ids shifted; the points of a patch are rebased onto
// the final level offsets once every region is in. Points used by patches of two regions are
// computed by both (a thin seam).
constexpr uint32_t kDefaultBatch = 16384;
constexpr int kTrustedRings = 2, kContextRings = 1;

// One region on its way through the pipeline: cut, isolated, merged.
struct Region {
  uint32_t index = 0;
  size_t region_faces = 0;         // faces[0, region_faces) are the region's own (role 2)
  std::vector<uint32_t> faces;     // cage faces of the sub-cage, the region's first
  std::vector<uint32_t> vertices;  // cage vertex of each sub-cage vertex
  std::vector<uint8_t> roles, depth;
  Mesh mesh;  // the sub-cage (dropped once isolated)
  PatchTable table;
  PatchStats stats;
};

class RegionBuilder {
 public:
  RegionBuilder(const Mesh& cage, const PatchOptions& o, std::span<const uint8_t> depth)
      : cage_(cage), o_(o), depth_(depth) {
    const size_t nf = cage.face_count(), nv = cage.vertex_count(), nc = cage.corner_count();
    // Faces around each vertex (all the regions need of the cage's topology: 8 bytes a corner).
    vertex_face_offsets_.assign(nv + 1, 0);
    for (const uint32_t v : cage.face_vertices) ++vertex_face_offsets_[v + 1];
    for (size_t v = 0; v < nv; ++v) vertex_face_offsets_[v + 1] += vertex_face_offsets_[v];
    vertex_faces_.resize(nc);
    {
      std::vector<uint32_t> fill(vertex_face_offsets_.begin(), vertex_face_offsets_.end() - 1);
      for (uint32_t f = 0; f < nf; ++f)
        for (const uint32_t v : cage.face(f)) vertex_faces_[fill[v]++] = f;
    }
    // Crease tags by edge; each must be an edge of some face, as in the whole-cage build.
    for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
      const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
      Crease& c = creases_[edge_key(a, b)];
      c.sharpness = std::min(cage.crease_sharpness[i], kInf);  // a later tag wins
    }
    if (!creases_.empty()) {
      for (uint32_t f = 0; f < nf; ++f) {
        const std::span<const uint32_t> vs = cage.face(f);
        for (size_t j = 0; j < vs.size(); ++j)
          if (const auto it = creases_.find(edge_key(vs[j], vs[(j + 1) % vs.size()]));
              it != creases_.end())
            it->second.on_face = true;
      }
      for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
        const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
        if (!creases_[edge_key(a, b)].on_face)
          throw InputError(
              fmt::format("crease tag {} names vertices {} and {}, which share no edge", i, a, b));
      }
    }
    for (size_t i = 0; i < cage.corner_vertices.size(); ++i)  // a later tag wins
      corner_sharpness_[cage.corner_vertices[i]] = std::min(cage.corner_sharpness[i], kInf);
    face_state_.assign(nf, 0);
    for (const uint32_t f : cage.hole_faces) face_state_[f] |= kHole;
    vertex_local_.assign(nv, kNone);
    out_.options = o.subdiv;
    out_.ptex_of_face = ptex_offsets(cage);
    out_.ptex_count = out_.ptex_of_face.back();
  }

  PatchTable run(uint32_t batch, PatchStats* stats) {
    const size_t nf = cage_.face_count();
    size_t seed = 0, emitted = 0;
    uint32_t next = 0;
    // Regions are cut and merged in order (so the table does not depend on the thread count) and
    // isolated in parallel, a few in flight at a time (their memory stays bounded).
    const size_t tokens = 2 * size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    tbb::parallel_pipeline(
        tokens,
        // Shared pointers, so regions in flight are freed when a stage throws.
        tbb::make_filter<void, std::shared_ptr<Region>>(
            tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& fc) -> std::shared_ptr<Region> {
              while (seed < nf && (face_state_[seed] & kDone)) ++seed;
              if (seed == nf) {
                fc.stop();
                return nullptr;
              }
              auto r = std::make_shared<Region>();
              r->index = next++;
              grow(uint32_t(seed), batch, *r);
              extract(*r);
              return r;
            }) &
            tbb::make_filter<std::shared_ptr<Region>, std::shared_ptr<Region>>(
                tbb::filter_mode::parallel,
                [&](std::shared_ptr<Region> r) {
                  isolate_region(*r);
                  return r;
                }) &
            tbb::make_filter<std::shared_ptr<Region>, void>(
                tbb::filter_mode::serial_in_order, [&](const std::shared_ptr<Region>& r) {
                  emitted += r->region_faces;
                  merge(*r, stats);
                  if (emitted < nf) reserve(emitted, nf, r->region_faces);
                }));
    finish(stats);
    return std::move(out_);
  }

 private:
  // The region from `seed` (breadth-first over faces sharing a vertex) and its rings.
  void grow(uint32_t seed, uint32_t batch, Region& r) {
    std::vector<uint32_t>& faces = r.faces;
    auto add = [&](uint32_t f, uint8_t role) {
      face_state_[f] |= kCut;
      faces.push_back(f);
      r.roles.push_back(role);
    };
    const uint32_t* fv = cage_.face_vertices.data();
    auto around = [&](uint32_t f, auto&& visit) {
      for (uint32_t c = cage_.face_offsets[f]; c < cage_.face_offsets[f + 1]; ++c) {
        const uint32_t v = fv[c];
        for (uint32_t k = vertex_face_offsets_[v]; k < vertex_face_offsets_[v + 1]; ++k)
          visit(vertex_faces_[k]);
      }
    };
    add(seed, 2);
    face_state_[seed] |= kDone;
    for (size_t head = 0; head < faces.size() && faces.size() < batch; ++head)
      around(faces[head], [&](uint32_t g) {
        if (faces.size() < batch && !(face_state_[g] & (kCut | kDone))) {
          add(g, 2);
          face_state_[g] |= kDone;
        }
      });
    r.region_faces = faces.size();
    size_t begin = 0;
    for (int ring = 0; ring < kTrustedRings + kContextRings; ++ring) {
      const size_t end = faces.size();
      const uint8_t role = ring < kTrustedRings ? 1 : 0;
      for (size_t i = begin; i < end; ++i)
        around(faces[i], [&](uint32_t g) {
          if (!(face_state_[g] & kCut)) add(g, role);
        });
      begin = end;
    }
  }

  // The sub-cage: the region's faces and rings over their own vertices, with the cage's tags.
  void extract(Region& r) {
    Mesh& m = r.mesh;
    m.tags = cage_.tags;
    const std::vector<uint32_t>& faces = r.faces;
    std::vector<uint32_t>& verts = r.vertices;
    const uint32_t* fv = cage_.face_vertices.data();
    for (size_t i = 0; i < faces.size(); ++i) {
      const uint32_t f = faces[i];
      for (uint32_t c = cage_.face_offsets[f]; c < cage_.face_offsets[f + 1]; ++c) {
        const uint32_t v = fv[c];
        if (vertex_local_[v] == kNone) {
          vertex_local_[v] = uint32_t(verts.size());
          verts.push_back(v);
        }
        m.face_vertices.push_back(vertex_local_[v]);
      }
      m.face_offsets.push_back(uint32_t(m.face_vertices.size()));
      if (face_state_[f] & kHole) m.hole_faces.push_back(uint32_t(i));
    }
    if (!creases_.empty())
      for (const uint32_t f : faces) {  // every vertex has its id now
        const std::span<const uint32_t> vs = cage_.face(f);
        for (size_t j = 0; j < vs.size(); ++j) {
          const uint32_t a = vs[j], b = vs[(j + 1) % vs.size()];
          const auto it = creases_.find(edge_key(a, b));
          if (it == creases_.end() || it->second.region == r.index) continue;
          it->second.region = r.index;
          m.crease_edges.insert(m.crease_edges.end(), {vertex_local_[a], vertex_local_[b]});
          m.crease_sharpness.push_back(it->second.sharpness);
        }
      }
    m.positions.resize(3 * verts.size());
    for (size_t i = 0; i < verts.size(); ++i) {
      std::copy_n(&cage_.positions[3 * size_t(verts[i])], 3, &m.positions[3 * i]);
      if (corner_sharpness_.empty()) continue;
      const auto it = corner_sharpness_.find(verts[i]);
      if (it != corner_sharpness_.end() && it->second > 0.0f) {
        m.corner_vertices.push_back(uint32_t(i));
        m.corner_sharpness.push_back(it->second);
      }
    }
    if (!depth_.empty())
      for (const uint32_t v : verts) r.depth.push_back(depth_[v]);
    for (const uint32_t f : faces) face_state_[f] &= uint8_t(~kCut);
    for (const uint32_t v : verts) vertex_local_[v] = kNone;
  }

  // Touches nothing shared: regions are isolated in parallel.
  void isolate_region(Region& r) const {
    const auto t0 = std::chrono::steady_clock::now();
    {
      Builder b(r.mesh, o_, r.depth);
      b.set_roles(r.roles);
      b.set_stats(&r.stats);
      SparseRefinement s = isolate(r.mesh, o_, b);
      b.build(r.table, s, &r.stats);
    }
    r.stats.refine_ms = ms_since(t0) - r.stats.patches_ms;
    r.mesh = Mesh{};
  }

  // Appends src's rows' weights to dst (shared: src's pool after dst's, each region's rows keep
  // their own copy of a row they share with another region's).
  static void append_weights(const StencilTable& src, StencilTable& dst) {
    const uint32_t at = uint32_t(dst.weights.size());
    for (size_t i = 0; i < src.size(); ++i) dst.weight_offsets.push_back(at + src.weight_start(i));
    dst.weights.insert(dst.weights.end(), src.weights.begin(), src.weights.end());
  }

  // Appends a region's table: level-k rows after the earlier regions' (ids shifted by their
  // counts), patch points as ids within their level (rebased in finish()).
  void merge(const Region& r, PatchStats* stats) {
    const PatchTable& t = r.table;
    const PatchStats& ps = r.stats;
    const std::vector<uint32_t>& verts = r.vertices;
    const std::vector<uint32_t>& faces = r.faces;
    const size_t nl = t.level_offsets.size() - 1;
    if (out_.level_stencils.size() < nl - 1) out_.level_stencils.resize(nl - 1);
    if (count_.size() < nl) count_.resize(nl, 0);
    const std::vector<uint32_t> base(count_);  // this region's first id in each level
    for (size_t k = 1; k < nl; ++k) {
      const StencilTable& src = t.level_stencils[k - 1];
      StencilTable& dst = out_.level_stencils[k - 1];
      const uint32_t shift = uint32_t(dst.indices.size());
      for (size_t i = 1; i < src.offsets.size(); ++i) dst.offsets.push_back(shift + src.offsets[i]);
      if (k == 1) {
        for (const uint32_t p : src.indices) dst.indices.push_back(verts[p]);
      } else {
        for (const uint32_t p : src.indices) dst.indices.push_back(base[k - 1] + p);
      }
      append_weights(src, dst);
      count_[k] += uint32_t(src.size());
    }
    // A level-k patch's points are all level-k points.
    auto local = [&](uint32_t p, uint32_t k) {
      if (p < t.level_offsets[k] || p >= t.level_offsets[k + 1])
        throw std::logic_error("patches: a region's patch reads another level");
      return k == 0 ? verts[p] : base[k] + (p - t.level_offsets[k]);
    };
    auto place = [&](PatchParam pp) {
      const uint32_t f = faces[pp.base_face];
      pp.ptex = out_.ptex_of_face[f] + (pp.ptex - t.ptex_of_face[pp.base_face]);
      pp.base_face = f;
      return pp;
    };
    for (size_t i = 0; i < t.regular_params.size(); ++i) {
      const PatchParam& pp = t.regular_params[i];
      for (size_t j = 16 * i; j < 16 * i + 16; ++j)
        out_.regular_points.push_back(local(t.regular_points[j], pp.level));
      out_.regular_params.push_back(place(pp));
    }
    // End-cap points: corner rows after the earlier regions' corner rows, face rows after
    // theirs (marked kCapRef until finish()); a row's level is its end caps' (all of a cap's
    // points are of its level).
    const StencilTable &g = t.gregory_stencils, &gf = t.gregory_face_stencils;
    StencilTable &dg = out_.gregory_stencils, &dgf = out_.gregory_face_stencils;
    const uint32_t cap_base = t.level_offsets.back(), face_base = cap_base + uint32_t(g.size());
    const uint32_t corner_shift = uint32_t(dg.size()), face_shift = uint32_t(dgf.size());
    corner_level_.resize(corner_shift + g.size(), 0);
    face_level_.resize(face_shift + gf.size(), 0);
    for (size_t i = 0; i < t.gregory_params.size(); ++i) {
      const uint8_t k = t.gregory_params[i].level;
      for (size_t j = 20 * i; j < 20 * i + 20; ++j) {
        const uint32_t p = t.gregory_points[j];
        if (p < cap_base) throw std::logic_error("patches: an end cap reads a refined point");
        if (p < face_base) {
          corner_level_[corner_shift + p - cap_base] = k;
          out_.gregory_points.push_back(corner_shift + (p - cap_base));
        } else {
          face_level_[face_shift + p - face_base] = k;
          out_.gregory_points.push_back(kCapRef | (face_shift + (p - face_base)));
        }
      }
      out_.gregory_params.push_back(place(t.gregory_params[i]));
    }
    auto append = [&](const StencilTable& src, StencilTable& dst, const uint8_t* level) {
      const uint32_t shift = uint32_t(dst.indices.size());
      for (size_t row = 0; row < src.size(); ++row) {
        for (uint32_t j = src.offsets[row]; j < src.offsets[row + 1]; ++j) {
          const uint32_t p = src.indices[j];
          dst.indices.push_back(p >= cap_base ? kCapRef | (corner_shift + (p - cap_base))
                                              : local(p, level[row]));
        }
        dst.offsets.push_back(shift + src.offsets[row + 1]);
      }
      append_weights(src, dst);
    };
    append(g, dg, corner_level_.data() + corner_shift);  // data(): the arrays may be empty
    append(gf, dgf, face_level_.data() + face_shift);
    if (stats) {
      for (auto [to, from] : {std::pair{&stats->regular_by_level, &ps.regular_by_level},
                              std::pair{&stats->gregory_by_level, &ps.gregory_by_level}}) {
        if (to->size() < from->size()) to->resize(from->size(), 0);
        for (size_t k = 0; k < from->size(); ++k) (*to)[k] += (*from)[k];
      }
      stats->patches_ms += ps.patches_ms;
      stats->refine_ms += ps.refine_ms;
    }
  }

  // Room for the whole table at the rate of the regions merged so far, once a tenth of the cage
  // is in (the first region alone misjudges features that are few and far between: a rate off
  // by more than the margin doubled an array late, a copy beside the old one at the build's
  // peak); until then the arrays double while they are small. Afterwards an array is given room
  // again only when the next regions might not fit, as late as possible, when the rate is known
  // best. The room is held to the end: it is part of the build's peak.
  void reserve(size_t emitted, size_t faces, size_t last_region) {
    if (10 * emitted < faces) return;
    const double scale = double(faces) / double(emitted);
    const bool first = !reserved_;
    reserved_ = true;
    auto grow = [&](auto& v) {
      const double want = double(v.size()) * scale;
      const double next = 2.0 * double(v.size()) * double(last_region) / double(emitted);
      if (first ? double(v.capacity()) < 1.05 * want
                : double(v.capacity()) < double(v.size()) + next)
        v.reserve(size_t(1.05 * want + next) + 64);
    };
    for (StencilTable& st : out_.level_stencils)
      grow(st.offsets), grow(st.indices), grow(st.weight_offsets);
    for (StencilTable* g : {&out_.gregory_stencils, &out_.gregory_face_stencils})
      grow(g->offsets), grow(g->indices), grow(g->weight_offsets);
    grow(out_.regular_points), grow(out_.regular_params);
    grow(out_.gregory_points), grow(out_.gregory_params);
  }

  void finish(PatchStats* stats) {
    PatchTable& t = out_;
    t.level_offsets.assign(1, 0);
    t.level_offsets.push_back(uint32_t(cage_.vertex_count()));
    for (size_t k = 1; k < count_.size(); ++k) {
      if (uint64_t(t.level_offsets.back()) + count_[k] >= kNone)
        throw InputError("patches: more than 2^32 points");
      t.level_offsets.push_back(t.level_offsets.back() + count_[k]);
    }
    for (size_t i = 0; i < t.regular_params.size(); ++i) {
      const uint32_t shift = t.level_offsets[t.regular_params[i].level];
      if (t.regular_params[i].level > 0)
        for (size_t j = 16 * i; j < 16 * i + 16; ++j) t.regular_points[j] += shift;
    }
    for (StencilTable* g : {&t.gregory_stencils, &t.gregory_face_stencils}) {
      const std::vector<uint8_t>& level = g == &t.gregory_stencils ? corner_level_ : face_level_;
      for (size_t r = 0; r < g->size(); ++r)
        if (level[r] > 0)
          for (uint32_t j = g->offsets[r]; j < g->offsets[r + 1]; ++j)
            if (!(g->indices[j] & kCapRef)) g->indices[j] += t.level_offsets[level[r]];
    }
    resolve_cap_points(t);
    if (stats) {
      stats->regular_by_level.resize(t.level_offsets.size() - 1, 0);
      stats->gregory_by_level.resize(t.level_offsets.size() - 1, 0);
      stats->points = t.point_count();
    }
  }

  static uint64_t edge_key(uint32_t a, uint32_t b) {
    return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a;
  }
  struct Crease {
    float sharpness = 0;
    uint32_t region = kNone;  // the last region that took it
    bool on_face = false;
  };

  const Mesh& cage_;
  PatchOptions o_;
  std::span<const uint8_t> depth_;
  std::vector<uint32_t> vertex_face_offsets_, vertex_faces_;
  std::unordered_map<uint64_t, Crease> creases_;
  std::unordered_map<uint32_t, float> corner_sharpness_;  // tagged cage vertices
  // Per cage face: kDone once a region has taken it as its own, kCut while in the region being
  // cut, kHole for a hole.
  static constexpr uint8_t kDone = 1, kCut = 2, kHole = 4;
  std::vector<uint8_t> face_state_;
  std::vector<uint32_t> vertex_local_;              // kNone outside the region being cut
  std::vector<uint32_t> count_{0};                  // points per level so far
  bool reserved_ = false;                           // room made for the whole table
  std::vector<uint8_t> corner_level_, face_level_;  // level of each merged end-cap row
  PatchTable out_;
};

}  // namespace

PatchTable build_patches(const Mesh& cage, const PatchOptions& options,
                         std::span<const uint8_t> vertex_depth, PatchStats* stats) {
  check_depth(options);
  if (!vertex_depth.empty() && vertex_depth.size() != cage.vertex_count())
    throw InputError(fmt::format("patches: {} vertex depths for {} vertices", vertex_depth.size(),
                                 cage.vertex_count()));
  const auto t0 = std::chrono::steady_clock::now();
  if (stats) *stats = {};
  const size_t nf = cage.face_count();
  const uint32_t batch = options.batch_faces ? options.batch_faces : kDefaultBatch;
  if (options.batch_faces ? nf > batch : nf > 2 * size_t(batch)) {
    validate(cage, "cage");
    RegionBuilder rb(cage, options, vertex_depth);
    return rb.run(batch, stats);  // the stats' times: summed over the regions (thread time)
  }
  Builder b(cage, options, vertex_depth);
  b.set_stats(stats);
  SparseRefinement r = isolate(cage, options, b);
  PatchTable out;
  b.build(out, r, stats);
  // Patches are emitted while the refinement runs: refine_ms is the rest.
  if (stats) stats->refine_ms = ms_since(t0) - stats->patches_ms;
  return out;
}

}  // namespace limn
