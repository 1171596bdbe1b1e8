// The patch-table builder's state and types, shared by its parts: classification
// (patch_classify.cpp), emission (patch_emit.cpp), Gregory end caps (patch_caps.cpp), the whole
// build and the hierarchy (patches.cpp) and region builds (patch_regions.cpp). Internal header of
// the subdiv layer.
#pragma once

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

namespace limn::patch_detail {

constexpr int kMaxDepth = 16;
constexpr float kInf = kInfiniteSharpness;

// The faces around each vertex of `cage`, ascending (CSR: offsets has vertex_count() + 1
// entries); what region builds and the channel's blocks need of the topology, 8 bytes a corner.
inline void vertex_faces(const Mesh& cage, std::vector<uint32_t>& offsets,
                         std::vector<uint32_t>& faces) {
  const size_t nv = cage.vertex_count(), nf = cage.face_count();
  offsets.assign(nv + 1, 0);
  for (const uint32_t v : cage.face_vertices) ++offsets[v + 1];
  for (size_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  faces.resize(cage.corner_count());
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (uint32_t f = 0; f < nf; ++f)
    for (const uint32_t v : cage.face(f)) faces[fill[v]++] = f;
}

// First ptex face of each cage face (one per quad, one per corner of any other face), and the
// total at the end.
inline std::vector<uint32_t> ptex_offsets(const Mesh& cage) {
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

inline Topo make_topo(const RefinedLevel& R, const LevelAdjacency& a) {
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
  std::vector<uint8_t> sharp_corner;       // per vertex, when given: its end-cap corners are
                                           // sharp whatever its ring (set_sharp_corners)
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

// Names a face of a level by where it lies: its ptex face and origin (unique within a level).
inline uint64_t face_key(uint32_t ptex, uint32_t u, uint32_t v) {
  return uint64_t(ptex) << 32 | uint64_t(u) << 16 | v;
}

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

// What a replayed build (face-varying patches) follows: the faces to refine, level 0's by their
// cage ptex face (the first of a non-quad's), the others' as per-level sorted face_key()s; and
// per cage vertex whether its end-cap corners are sharp (may be empty).
struct Replay {
  std::vector<uint8_t> cage;
  std::vector<std::vector<uint64_t>> keys;
  std::vector<uint8_t> sharp_corners;
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
  /// Refines exactly the faces another build refined (face-varying patches follow their vertex
  /// patches). Region builds give the cage's first ptex face of each of their sub-cage's faces,
  /// as the replay names them.
  void set_replay(const Replay* replay, std::span<const uint32_t> cage_ptex = {}) {
    replay_ = replay, replay_ptex_ = cage_ptex;
  }
  /// Cage vertices (and the vertex points refined from them) whose end-cap corners are sharp
  /// whatever their ring shows (face-varying values at non-manifold vertices, as OpenSubdiv).
  void set_sharp_corners(std::span<const uint8_t> v) { sharp_corners_ = v; }

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
  const Replay* replay_ = nullptr;
  std::span<const uint32_t> replay_ptex_;
  std::span<const uint8_t> sharp_corners_;
  bool replayed(size_t k, const Level::Face& f) const;
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
  void add_nodes(size_t k, const SparseLevel& S, std::vector<uint32_t>& node_of);
  void emit_regular(size_t k, Level& L, const RefinedLevel& R, uint32_t f, const uint32_t corner[4],
                    const uint32_t a[4], uint32_t off, PatchParam& pp);
  void emit_gregory(size_t k, Level& L, const RefinedLevel& R, uint32_t f, const uint32_t corner[4],
                    const uint32_t a[4], uint32_t off, PatchParam& pp);
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

// The common regular case, told without walking the ring: four faces (refined levels are all
// quads), none across a boundary or a torn edge, no sharpness.
inline bool plain_interior_walk(const Level& L, const RefinedLevel& R, uint32_t v) {
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
inline bool plain_interior(const Level& L, const RefinedLevel& R, uint32_t v) {
  uint8_t& x = L.vinfo[v];
  if (!(x & Level::kPlainKnown))
    x |= uint8_t(Level::kPlainKnown |
                 (plain_interior_walk(L, R, v) ? Level::kPlain | Level::kCutsKnown : 0));
  return x & Level::kPlain;
}

// Room in v for `more` elements beyond its size (exactly: no doubling).
template <class V>
void reserve_more(V& v, size_t more) {
  if (v.capacity() < v.size() + more) v.reserve(v.size() + more);
}

/// End-cap points marked as references into the table's Gregory rows are made real (see
/// GregoryCap); the table's point counts and levels are finished.
void resolve_cap_points(PatchTable& t);
/// Joins the levels' regular points into the table and drops the points no patch reads.
void prune_points(PatchTable& t, std::span<std::vector<uint32_t>> regular_points);
/// build_patches (whole cage or regions, as it chooses) refining as `replay` says.
PatchTable build_replayed(const Mesh& cage, const PatchOptions& options, const Replay& replay);
/// Throws InputError for an isolation depth out of range.
void check_depth(const PatchOptions& options);
/// The sparse refinement of the cage that `b` requests and emits patches from.
SparseRefinement isolate(const Mesh& cage, const PatchOptions& options, Builder& b);

}  // namespace limn::patch_detail
