// What uniform refinement (refine.cpp), sparse refinement (refine_sparse.cpp) and the stencil
// tables (stencils.cpp) share: a level's adjacency, the selection of parent components a step
// refines, and the steps both kinds of refinement take. Internal header of the subdiv layer.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "limn/subdiv/refine.hpp"

namespace limn::refine_detail {

// Sizes a vector to n elements of `value`, dropping any old buffer first so a level's arrays
// never hold two copies at once.
template <class T, class A>
void refill(std::vector<T, A>& v, size_t n, T value = T()) {
  if (v.capacity() < n) std::vector<T, A>().swap(v);
  v.assign(n, value);
}

inline bool sharp(float s) {
  return s > 0.0f;
}

// Adjacency of one level as flat CSR arrays. On quad levels (every level after the first, and
// all-quad cages) corners are implicit: corner i of face f is 4f + i.
// Allocates like std::allocator but leaves elements made by resize() uninitialised: the
// adjacency arrays are written in full right after they are sized, so zero-filling them first
// only costs a pass over each.
template <class T>
struct NoInit : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = NoInit<U>;
  };
  NoInit() = default;
  template <class U>
  NoInit(const NoInit<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... A>
  void construct(U* p, A&&... a) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
};
using Ids = std::vector<uint32_t, NoInit<uint32_t>>;

struct Adj {
  bool quads = false;
  Ids corner_face;                           // per corner; empty on quad levels
  Ids corner_edge;                           // per corner: the edge of its outgoing half-edge
  Ids eco{0}, ec;                            // edge -> the corners on it (one per face)
  Ids vco{0}, vc;                            // vertex -> the corners at it (one per face)
  Ids veo{0}, ve;                            // vertex -> its edges
  std::vector<uint8_t> edge_non_manifold;    // from build_adj only (the cage)
  std::vector<uint8_t> vertex_non_manifold;  // faces around it are not one fan (build_adj)

  uint32_t face_of(uint32_t c) const { return quads ? c >> 2 : corner_face[c]; }
  uint32_t edge_face_count(uint32_t e) const { return eco[e + 1] - eco[e]; }
  uint32_t vertex_face_count(uint32_t v) const { return vco[v + 1] - vco[v]; }
  uint32_t vertex_edge_count(uint32_t v) const { return veo[v + 1] - veo[v]; }
};

// A level's faces and edges together with its adjacency.
struct LevelRef {
  const RefinedLevel& L;
  const Adj& a;
  [[gnu::always_inline]] uint32_t next(uint32_t c) const {
    if (a.quads) return (c & ~3u) | ((c + 1) & 3u);
    const uint32_t f = a.corner_face[c];
    return c + 1 == L.face_offsets[f + 1] ? L.face_offsets[f] : c + 1;
  }
  [[gnu::always_inline]] uint32_t prev(uint32_t c) const {
    if (a.quads) return (c & ~3u) | ((c + 3) & 3u);
    const uint32_t f = a.corner_face[c];
    return c == L.face_offsets[f] ? L.face_offsets[f + 1] - 1 : c - 1;
  }
  // The corner two steps on from c in its face, which must be a quad.
  [[gnu::always_inline]] uint32_t opposite_in_quad(uint32_t c) const {
    if (a.quads) return (c & ~3u) | ((c + 2) & 3u);
    const uint32_t b = L.face_offsets[a.corner_face[c]];
    return b + ((c - b + 2) & 3u);
  }
  uint32_t other_end(uint32_t e, uint32_t v) const {
    const uint32_t x = L.edge_vertices[2 * size_t(e)];
    return x == v ? L.edge_vertices[2 * size_t(e) + 1] : x;
  }
  uint32_t face_size(uint32_t f) const { return L.face_offsets[f + 1] - L.face_offsets[f]; }
};

// The parent components one refinement step gives children to, and where those children land.
// Uniform refinement selects everything (`all`, no lists); sparse refinement lists them in
// ascending order. Child vertices are numbered by blocks: face points of faces[], then edge
// points of edges[], then vertex points of vertices[].
struct Selection {
  bool all = true;
  uint32_t nf = 0, ne = 0, nv = 0;               // counts (also when all)
  std::vector<uint32_t> faces, edges, vertices;  // when !all
  std::vector<uint32_t> edge_slot, vertex_slot;  // parent edge/vertex -> index in edges/vertices
  // Sparse levels: the parent vertices whose children are made (`near`): a selected face gets
  // its child quads at these corners only, and the selected edges and vertices are those at them.
  const uint8_t* near = nullptr;
  uint32_t face(uint32_t i) const { return all ? i : faces[i]; }
  uint32_t edge(uint32_t i) const { return all ? i : edges[i]; }
  uint32_t vertex(uint32_t i) const { return all ? i : vertices[i]; }
  uint32_t eslot(uint32_t e) const { return all ? e : edge_slot[e]; }
  uint32_t vslot(uint32_t v) const { return all ? v : vertex_slot[v]; }
  size_t points() const { return size_t(nf) + ne + nv; }
  static Selection everything(const RefinedLevel& P) {
    Selection s;
    s.nf = static_cast<uint32_t>(P.face_count());
    s.ne = static_cast<uint32_t>(P.edge_count());
    s.nv = static_cast<uint32_t>(P.vertex_count());
    return s;
  }
};

/// The cage as level 0, with its adjacency and tags. `excluded`, when given, gets per vertex 1
/// where boundary interpolation "none" made the vertex's faces holes.
Adj cage_level(const Mesh& cage, const SubdivOptions& o, RefinedLevel& L0,
               std::vector<uint8_t>* excluded = nullptr);
/// Sharpness in the child of parent edge e's half at its end v (Chaikin needs v's other edges;
/// pe and ce are scratch).
float half_sharpness_at(const SubdivOptions& o, const RefinedLevel& P, const Adj& pa, size_t e,
                        uint32_t v, std::vector<float>& pe, std::vector<float>& ce);
/// Child vertex sharpness: vertex points inherit their parent's, decayed.
void child_vertex_sharpness(const RefinedLevel& P, const Selection& sel, RefinedLevel& C);
/// All the child points' stencils as one table, rows sharing their weights (see StencilTable).
/// With `keep`, only points i with keep[i] get their stencil; the others get empty rows.
StencilTable build_stencils(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                            const Selection& sel, const uint8_t* keep = nullptr);
/// Applies stencils [b, e) of `table` serially to `channels` floats per point; out gets
/// table.size() points.
void apply_serial(const StencilTable& table, size_t b, size_t e, const float* in, float* out,
                  int channels);
/// The cage's positions pushed through the first `level` tables of a chain.
std::vector<float> apply_chain(const std::vector<StencilTable>& tables, const Mesh& cage,
                               int level);

}  // namespace limn::refine_detail
