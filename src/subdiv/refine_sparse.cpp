// Sparse (feature-adaptive) refinement: of each level, only the faces a request names and the
// rings around them, each level's adjacency in closed form (sparse_child_adj), its stencils only
// for the points read later when the levels are not kept.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

#include "core/parallel.hpp"
#include "corner_twins.hpp"
#include "limn/subdiv/refine.hpp"
#include "refine_levels.hpp"

namespace limn {

using namespace refine_detail;

namespace {

// Sparse child levels make, of each selected parent face, only the child quads at its `near`
// corners (sel.near): those are the children whose points a requested face's children see
// (each child of a requested face, and the ring around each of its vertices), and the other
// children of the faces around it would be made only to be dropped. Quad at parent corner c
// (vertex v, near): V(v), E(c's edge), F, E(prev's edge). Child edges: first the halves of the
// selected parent edges (edge point to the vertex point of a near end; an edge's first end's
// half first), then one per parent corner whose edge is selected (its edge point to the face
// point), in parent face and corner order; so every list is the part of what refining the faces
// whole would give that touches near corners, in the same order.
struct SparseChildEdges {
  std::vector<uint32_t> half;  // per selected parent edge: its first half's child edge
  uint32_t halves = 0;         // type-A edges (halves); type-B edges follow
};

// The child edge of selected parent edge ei's half at end `end` (which must be near).
inline uint32_t half_edge(const SparseChildEdges& ce, const RefinedLevel& P, const Selection& sel,
                          uint32_t ei, uint32_t end) {
  const uint32_t e = sel.edge(ei), x = P.edge_vertices[2 * size_t(e)];
  return ce.half[ei] + (end != x && sel.near[x] ? 1u : 0u);
}

// Child edge sharpness on a sparse child: only the halves of parent edges can be sharp.
void table_edge_sharpness(const SubdivOptions& o, const RefinedLevel& P, const Adj& pa,
                          const Selection& sel, const SparseChildEdges& ce, RefinedLevel& C) {
  const size_t ne = C.edge_vertices.size() / 2;
  C.edge_sharpness.assign(ne, 0.0f);
  std::vector<float> pe, cs;
  for (uint32_t ei = 0; ei < sel.ne; ++ei) {
    const uint32_t e = sel.edge(ei);
    if (!sharp(P.edge_sharpness[e])) continue;
    for (int j = 0; j < 2; ++j) {
      const uint32_t end = P.edge_vertices[2 * size_t(e) + size_t(j)];
      if (sel.near[end])
        C.edge_sharpness[half_edge(ce, P, sel, ei, end)] =
            half_sharpness_at(o, P, pa, e, end, pe, cs);
    }
  }
}

// Child faces of the selected parent faces at their near corners (sparse levels).
void selected_child_faces(const RefinedLevel& P, const Adj& pa, const Selection& sel,
                          RefinedLevel& C) {
  const LevelRef pl{P, pa};
  const uint32_t F = sel.nf, E = sel.ne;
  const uint32_t* pfv = P.face_vertices.data();
  size_t Q = 0;
  for (uint32_t fi = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) Q += sel.near[pfv[c]];
  }
  // Sized once and written in place: the arrays are most of a level.
  C.face_offsets.resize(Q + 1);
  C.face_vertices.resize(4 * Q);
  C.face_hole.resize(Q);
  uint32_t* fo = C.face_offsets.data();
  uint32_t* fv = C.face_vertices.data();
  uint8_t* hole = C.face_hole.data();
  size_t q = 0;
  fo[0] = 0;
  for (uint32_t fi = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
      if (!sel.near[pfv[c]]) continue;
      fv[4 * q] = F + E + sel.vslot(pfv[c]);
      fv[4 * q + 1] = F + sel.eslot(pa.corner_edge[c]);
      fv[4 * q + 2] = fi;
      fv[4 * q + 3] = F + sel.eslot(pa.corner_edge[pl.prev(c)]);
      fo[q + 1] = uint32_t(4 * (q + 1));
      hole[q] = P.face_hole[f];
      ++q;
    }
  }
}

// The adjacency of a sparse child (faces from selected_child_faces) in closed form, like
// derive_child's for uniform levels: no search and no sort. A child edge has one corner per
// child quad that makes it, so an edge whose other side was not made is a boundary of the
// child level, as build_adj would find. Sets C.edge_vertices; `ce` gets the edge numbering.
Adj sparse_child_adj(const RefinedLevel& P, const Adj& pa, const Selection& sel, RefinedLevel& C,
                     SparseChildEdges& ce) {
  const LevelRef pl{P, pa};
  const uint32_t F = sel.nf, E = sel.ne, V = sel.nv;
  const uint32_t Q = uint32_t(C.face_count()), nvc = F + E + V;
  const uint32_t* pfv = P.face_vertices.data();
  const uint8_t* near = sel.near;
  Adj a;
  a.quads = true;
  // Parent face -> its first child quad; parent corner -> its quad (kNone: not near).
  std::vector<uint32_t> first_quad(P.face_count(), kNone);
  for (uint32_t fi = 0, q = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    first_quad[f] = q;
    for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) q += near[pfv[c]];
  }
  // Halves: per selected edge, one per near end.
  ce.half.resize(E);
  uint32_t halves = 0;
  for (uint32_t ei = 0; ei < E; ++ei) {
    const uint32_t e = sel.edge(ei);
    ce.half[ei] = halves;
    halves += near[P.edge_vertices[2 * size_t(e)]] + near[P.edge_vertices[2 * size_t(e) + 1]];
  }
  ce.halves = halves;
  // Type-B edges: parent corners whose edge has a near end.
  uint32_t spokes = 0;
  for (uint32_t fi = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c)
      spokes += (near[pfv[c]] | near[pfv[pl.next(c)]]) != 0;
  }
  const uint32_t ne = halves + spokes;
  C.edge_vertices.resize(2 * size_t(ne));
  a.corner_edge.resize(4 * size_t(Q));  // every corner is put below
  a.eco.assign(size_t(ne) + 1, 0);
  // Corners per half: one per selected face on the parent edge (all of its faces: they are
  // around the near end).
  for (uint32_t ei = 0; ei < E; ++ei) {
    const uint32_t e = sel.edge(ei);
    uint32_t n = 0;
    for (uint32_t j = pa.eco[e]; j < pa.eco[e + 1]; ++j)
      n += first_quad[pa.face_of(pa.ec[j])] != kNone;
    uint32_t h = ce.half[ei];
    for (int j = 0; j < 2; ++j) {
      const uint32_t end = P.edge_vertices[2 * size_t(e) + size_t(j)];
      if (!near[end]) continue;
      a.eco[h + 1] = n;
      C.edge_vertices[2 * size_t(h)] = F + ei,
                          C.edge_vertices[2 * size_t(h) + 1] = F + E + sel.vslot(end);
      ++h;
    }
  }
  // Spokes: one corner per child quad at either end of the parent corner's edge.
  {
    uint32_t s = halves;
    for (uint32_t fi = 0; fi < F; ++fi) {
      const uint32_t f = sel.face(fi);
      for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
        const uint32_t n = uint32_t(near[pfv[c]]) + near[pfv[pl.next(c)]];
        if (n) a.eco[++s] = n;
      }
    }
  }
  for (size_t e = 0; e < ne; ++e) a.eco[e + 1] += a.eco[e];
  a.ec.resize(a.eco.back());
  std::vector<uint32_t> fill(a.eco.begin(), a.eco.end() - 1);
  auto put = [&](uint32_t e, uint32_t corner) {
    a.corner_edge[corner] = e;
    a.ec[fill[e]++] = corner;
  };
  uint32_t s = halves;
  for (uint32_t fi = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    const uint32_t b = P.face_offsets[f], n = P.face_offsets[f + 1] - b;
    const uint32_t q0 = first_quad[f];  // the quad of the face's first near corner
    for (uint32_t i = 0, before = 0; i < n; before += near[pfv[b + i]], ++i) {
      const uint32_t c = b + i, cn = pl.next(c);
      const bool has_q = near[pfv[c]], has_qn = near[pfv[cn]];
      if (!has_q && !has_qn) continue;
      // Quads of c and of next(c), counted among the face's near corners.
      const uint32_t q = q0 + before, qn = i + 1 == n ? q0 : q0 + before + has_q;
      const uint32_t ei = sel.eslot(pa.corner_edge[c]);
      const uint32_t e = s++;
      C.edge_vertices[2 * size_t(e)] = fi, C.edge_vertices[2 * size_t(e) + 1] = F + ei;
      if (has_q) put(e, 4 * q + 1);    // E(c) -> F in quad q
      if (has_qn) put(e, 4 * qn + 2);  // F -> E(c) in the next corner's quad
      // V(start) -> E(c) in quad q, E(c) -> V(end) in quad qn: the halves of the parent edge.
      if (has_q) put(half_edge(ce, P, sel, ei, pfv[c]), 4 * q);
      if (has_qn) put(half_edge(ce, P, sel, ei, pfv[cn]), 4 * qn + 3);
    }
  }
  // Vertex -> corners and vertex -> edges, by counting.
  const uint32_t* cfv = C.face_vertices.data();
  a.vco.assign(size_t(nvc) + 1, 0);
  for (size_t c = 0; c < 4 * size_t(Q); ++c) ++a.vco[cfv[c] + 1];
  for (size_t v = 0; v < nvc; ++v) a.vco[v + 1] += a.vco[v];
  a.vc.resize(4 * size_t(Q));
  fill.assign(a.vco.begin(), a.vco.end() - 1);
  for (uint32_t c = 0; c < 4 * Q; ++c) a.vc[fill[cfv[c]]++] = c;
  // Vertex -> edges waits for the level's request (sparse_vertex_edges): only a level that
  // refines something reads it, and the last, largest level does not.
  return a;
}

// Vertex -> edges of a sparse level, by counting over its edges (each list in edge order).
void sparse_vertex_edges(const RefinedLevel& C, Adj& a) {
  const size_t nv = C.vertex_count(), ne = C.edge_vertices.size() / 2;
  a.veo.assign(nv + 1, 0);
  for (size_t e = 0; e < ne; ++e)
    ++a.veo[C.edge_vertices[2 * e] + 1], ++a.veo[C.edge_vertices[2 * e + 1] + 1];
  for (size_t v = 0; v < nv; ++v) a.veo[v + 1] += a.veo[v];
  a.ve.resize(2 * ne);
  std::vector<uint32_t> fill(a.veo.begin(), a.veo.end() - 1);
  for (uint32_t e = 0; e < ne; ++e) {
    a.ve[fill[C.edge_vertices[2 * size_t(e)]]++] = e;
    a.ve[fill[C.edge_vertices[2 * size_t(e) + 1]]++] = e;
  }
}

}  // namespace

std::vector<float> SparseRefinement::positions(const Mesh& cage, int level) const {
  if (level < 0 || level >= int(levels.size()))
    throw InputError(fmt::format("sparse refinement: level {} not refined", level));
  return apply_chain(stencils, cage, level);
}

namespace {
constexpr int kMaxSparseDepth = 16;
SparseRefinement refine_sparse_impl(const Mesh& cage, const SubdivOptions& options,
                                    const SparseRequest& request, std::vector<uint8_t> vertex_depth,
                                    std::vector<uint8_t> face_depth, bool keep_levels,
                                    const SparseLevelDone& level_done);
}  // namespace

SparseRefinement refine_sparse(const Mesh& cage, std::span<const uint8_t> vertex_depth,
                               std::span<const uint8_t> face_depth, const SubdivOptions& options) {
  const size_t nv0 = cage.vertex_count(), nf0 = cage.face_count();
  if (!vertex_depth.empty() && vertex_depth.size() != nv0)
    throw InputError(fmt::format("sparse refinement: {} vertex depths for {} vertices",
                                 vertex_depth.size(), nv0));
  if (!face_depth.empty() && face_depth.size() != nf0)
    throw InputError(
        fmt::format("sparse refinement: {} face depths for {} faces", face_depth.size(), nf0));
  for (std::span<const uint8_t> d : {vertex_depth, face_depth})
    for (size_t i = 0; i < d.size(); ++i)
      if (d[i] > kMaxSparseDepth)
        throw InputError(
            fmt::format("sparse refinement: depth {} of element {} out of range (0-{})", d[i], i,
                        kMaxSparseDepth));

  std::vector<uint8_t> vd(nv0, 0), fd(nf0, 0);
  std::copy(vertex_depth.begin(), vertex_depth.end(), vd.begin());
  std::copy(face_depth.begin(), face_depth.end(), fd.begin());
  // A face is requested while it, or one of its vertices, has levels left.
  auto request = [](size_t, const SparseLevel& P, const LevelAdjacency&,
                    std::vector<uint8_t>& requested) {
    const RefinedLevel& PL = P.level;
    for (size_t f = 0; f < PL.face_count(); ++f) {
      bool want = P.face_depth[f] > 0;
      for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1] && !want; ++c)
        want = P.vertex_depth[PL.face_vertices[c]] > 0;
      requested[f] = want;
    }
  };
  return refine_sparse_impl(cage, options, request, std::move(vd), std::move(fd), true, {});
}

SparseRefinement refine_sparse(const Mesh& cage, const SubdivOptions& options,
                               const SparseRequest& request, bool keep_levels,
                               const SparseLevelDone& level_done) {
  return refine_sparse_impl(cage, options, request, std::vector<uint8_t>(cage.vertex_count(), 0),
                            std::vector<uint8_t>(cage.face_count(), 0), keep_levels, level_done);
}

namespace {

// Level k's selection: its refined faces, and the edges and vertices at their near corners
// (`near`: the vertices of requested faces), numbered in ascending order.
Selection select_refined(size_t k, const SparseLevel& P, const Adj& t,
                         const std::vector<uint8_t>& near) {
  const RefinedLevel& PL = P.level;
  const uint32_t ne = static_cast<uint32_t>(PL.edge_count()),
                 nv = static_cast<uint32_t>(PL.vertex_count()),
                 nf = static_cast<uint32_t>(PL.face_count());
  Selection sel;
  sel.all = false;
  sel.edge_slot.assign(ne, kNone);
  sel.vertex_slot.assign(nv, kNone);
  const LevelRef pl{PL, t};
  for (uint32_t f = 0; f < nf; ++f) {
    if (!P.face_refined[f]) continue;
    sel.faces.push_back(f);
    for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1]; ++c) {
      const uint32_t v = PL.face_vertices[c];
      if (!near[v]) continue;
      // The selection rule guarantees this (see the header); a failure is a bug in limn.
      if (!P.vertex_complete[v])
        throw std::logic_error(fmt::format(
            "sparse refinement: level {} vertex {} is refined without its whole ring", k, v));
      sel.vertex_slot[v] = 0;
      sel.edge_slot[t.corner_edge[c]] = 0;
      sel.edge_slot[t.corner_edge[pl.prev(c)]] = 0;
    }
  }
  sel.near = near.data();
  for (uint32_t e = 0; e < ne; ++e)
    if (sel.edge_slot[e] == 0)
      sel.edge_slot[e] = uint32_t(sel.edges.size()), sel.edges.push_back(e);
  for (uint32_t v = 0; v < nv; ++v)
    if (sel.vertex_slot[v] == 0)
      sel.vertex_slot[v] = uint32_t(sel.vertices.size()), sel.vertices.push_back(v);
  sel.nf = uint32_t(sel.faces.size());
  sel.ne = uint32_t(sel.edges.size());
  sel.nv = uint32_t(sel.vertices.size());
  return sel;
}

// The child level's provenance, completeness and depths left from level P's (whose selection is
// sel, near its near vertices); C.level's faces are made.
void child_state(const SparseLevel& P, const Adj& t, const Selection& sel,
                 const std::vector<uint8_t>& near, SparseLevel& C) {
  const RefinedLevel& PL = P.level;
  const size_t nvc = size_t(sel.nf) + sel.ne + sel.nv;
  C.vertex_complete.assign(nvc, 1);
  C.vertex_depth.assign(nvc, 0);
  for (uint32_t i = 0; i < sel.ne; ++i) {
    const uint32_t e = sel.edges[i];
    const uint32_t a = PL.edge_vertices[2 * size_t(e)], b = PL.edge_vertices[2 * size_t(e) + 1];
    // Its ring is the child quads at both ends of every face on the edge: both ends near
    // (then every face on it is refined, and the ends are complete).
    C.vertex_complete[sel.nf + i] = near[a] && near[b];
  }
  for (uint32_t i = 0; i < sel.nf; ++i) {  // a face point: the quads at all its corners
    const uint32_t f = sel.faces[i];
    bool whole = true;
    for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1] && whole; ++c)
      whole = near[PL.face_vertices[c]];
    C.vertex_complete[i] = whole;
  }
  for (uint32_t i = 0; i < sel.nv; ++i) {
    const uint32_t v = sel.vertices[i];
    bool whole = P.vertex_complete[v];
    for (uint32_t j = t.vco[v]; j < t.vco[v + 1] && whole; ++j)
      whole = P.face_refined[t.face_of(t.vc[j])];
    const size_t cv = size_t(sel.nf) + sel.ne + i;
    C.vertex_complete[cv] = whole;
    C.vertex_depth[cv] = P.vertex_depth[v] > 0 ? uint8_t(P.vertex_depth[v] - 1) : 0;
  }
  C.face_parent.resize(C.level.face_count());
  C.face_depth.resize(C.level.face_count());
  for (size_t q = 0; const uint32_t f : sel.faces) {
    const uint8_t d = P.face_depth[f] > 0 ? uint8_t(P.face_depth[f] - 1) : 0;
    for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1]; ++c)
      if (near[PL.face_vertices[c]]) C.face_parent[q] = f, C.face_depth[q] = d, ++q;
  }
}

SparseRefinement refine_sparse_impl(const Mesh& cage, const SubdivOptions& options,
                                    const SparseRequest& request, std::vector<uint8_t> vertex_depth,
                                    std::vector<uint8_t> face_depth, bool keep_levels,
                                    const SparseLevelDone& level_done) {
  SparseRefinement r;
  r.options = options;
  r.levels.reserve(kMaxSparseDepth + 1);
  {
    SparseLevel& L0 = r.levels.emplace_back();
    L0.level.face_offsets = cage.face_offsets;
    L0.level.face_vertices = cage.face_vertices;
    L0.vertex_complete.assign(cage.vertex_count(), 1);
    L0.vertex_depth = std::move(vertex_depth);
    L0.face_depth = std::move(face_depth);
  }
  auto adj = std::make_unique<Adj>(cage_level(cage, options, r.levels[0].level));
  std::vector<uint8_t> requested;
  // Lean runs build level k's stencils after level k's request, only for the points that what
  // the caller takes from level k (the children of the faces requested at level k - 1) or level
  // k + 1's stencils can read: on isolation levels about 40% of the points only complete other
  // points' rings. Until then level k - 1 keeps its adjacency and selection.
  std::unique_ptr<Adj> padj;
  Selection psel;
  std::vector<uint8_t> prev_requested, keep;

  for (size_t k = 0;; ++k) {
    SparseLevel& P = r.levels[k];
    const RefinedLevel& PL = P.level;
    const Adj& t = *adj;
    const uint32_t nf = static_cast<uint32_t>(PL.face_count()),
                   nv = static_cast<uint32_t>(PL.vertex_count());
    // Requested faces, and the vertices they touch: every face around those is refined too, so
    // that each requested face's child points see whole rings.
    std::vector<uint8_t> near(nv, 0);
    bool any = false;
    requested.assign(nf, 0);
    const LevelAdjacency view{t.corner_edge, t.eco, t.ec, t.vco, t.vc, {}};
    request(k, P, view, requested);
    for (uint32_t f = 0; f < nf; ++f) {
      if (!requested[f]) continue;
      any = true;
      for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1]; ++c)
        near[PL.face_vertices[c]] = 1;
    }
    P.face_refined.assign(nf, 0);
    for (uint32_t v = 0; v < nv && any; ++v)
      if (near[v])
        for (uint32_t i = t.vco[v]; i < t.vco[v + 1]; ++i) P.face_refined[t.face_of(t.vc[i])] = 1;
    if (!keep_levels && k > 0) {
      // Bit 1: a vertex of a face the caller may take or that is refined; bit 2: on a face
      // around such a vertex (the ring a patch or a child stencil reads).
      keep.assign(nv, 0);
      for (uint32_t f = 0; f < nf; ++f)
        if (prev_requested[P.face_parent[f]] || P.face_refined[f])
          for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1]; ++c)
            keep[PL.face_vertices[c]] = 1;
      const uint32_t* fv = PL.face_vertices.data();
      for (uint32_t f = 0; f < nf; ++f) {  // refined levels are all quads
        const uint32_t* q = fv + 4 * size_t(f);
        if ((keep[q[0]] | keep[q[1]] | keep[q[2]] | keep[q[3]]) & 1)
          keep[q[0]] |= 2, keep[q[1]] |= 2, keep[q[2]] |= 2, keep[q[3]] |= 2;
      }
      for (uint8_t& x : keep) x >>= 1;
      if (!any) {
        // The last level: what only the next level's construction would read goes before its
        // stencils are built (the moment both levels and the new table are held).
        std::vector<uint32_t>().swap(P.level.edge_vertices);
        for (auto* v : {&P.vertex_complete, &P.vertex_depth, &P.face_depth, &P.face_refined})
          std::vector<uint8_t>().swap(*v);
      }
      // Level k holds the selection's lists (as its parent_*): lent to psel, not copied.
      psel.faces.swap(P.parent_faces), psel.edges.swap(P.parent_edges);
      psel.vertices.swap(P.parent_vertices);
      r.stencils.push_back(
          build_stencils(options, r.levels[k - 1].level, *padj, psel, keep.data()));
      psel.faces.swap(P.parent_faces), psel.edges.swap(P.parent_edges);
      psel.vertices.swap(P.parent_vertices);
      r.levels[k - 1] = SparseLevel{};
      padj.reset();
      psel = Selection{};
    }
    if (!any && !keep_levels)  // the last level's provenance, read by its stencils only
      for (auto* v : {&P.parent_faces, &P.parent_edges, &P.parent_vertices})
        std::vector<uint32_t>().swap(*v);
    if (level_done && !any && !keep_levels) {
      // The last level: its patches read corner twins, not edge -> corner lists, and nothing
      // reads it after them, so the lists (25 bytes a quad) go before the table grows.
      Ids twin(PL.face_vertices.size());
      detail::corner_twins(adj->eco, adj->ec, twin);
      Ids().swap(adj->eco), Ids().swap(adj->ec);
      LevelAdjacency last = view;
      last.edge_corner_offsets = {}, last.edge_corners = {}, last.corner_twin = twin;
      level_done(k, P, last);
    } else if (level_done) {
      level_done(k, P, view);
    }
    if (!keep_levels)  // level k's provenance: read by its request, stencils and patches only
      for (auto* v : {&P.parent_faces, &P.parent_edges, &P.parent_vertices, &P.face_parent})
        std::vector<uint32_t>().swap(*v);
    if (!any) {
      if (!keep_levels) r.levels[k] = SparseLevel{};
      break;
    }
    if (k == kMaxSparseDepth)
      throw InputError(fmt::format("sparse refinement: requests beyond level {}", kMaxSparseDepth));
    // Read by level k + 1's construction (and stencils), made once level k - 1 is gone.
    if (k > 0) sparse_vertex_edges(PL, *adj);

    Selection sel = select_refined(k, P, t, near);

    SparseLevel C;
    if (keep_levels) r.stencils.push_back(build_stencils(options, PL, t, sel));
    selected_child_faces(PL, t, sel, C.level);
    child_vertex_sharpness(PL, sel, C.level);
    // Provenance, completeness and the depths left (before the child adjacency: level k's
    // tags and depths can go first, the moment both levels are held).
    child_state(P, t, sel, near, C);
    if (!keep_levels)
      for (auto* v : {&P.vertex_complete, &P.vertex_depth, &P.face_depth, &P.face_refined})
        std::vector<uint8_t>().swap(*v);
    SparseChildEdges child_edges;
    auto cadj = std::make_unique<Adj>(sparse_child_adj(PL, t, sel, C.level, child_edges));
    table_edge_sharpness(options, PL, t, sel, child_edges, C.level);

    C.parent_faces = std::move(sel.faces);
    C.parent_edges = std::move(sel.edges);
    C.parent_vertices = std::move(sel.vertices);
    if (!keep_levels) {
      sel.near = nullptr;  // `near` is this level's
      // Swapped out, not `= {}` (the initializer-list assignment keeps the capacity).
      for (auto* v : {&sel.faces, &sel.edges, &sel.vertices, &sel.edge_slot, &sel.vertex_slot})
        std::vector<uint32_t>().swap(*v);
      psel = std::move(sel);
      padj = std::move(adj);
      Ids().swap(padj->corner_edge);  // level k + 1 is made: level k's stencils do not read it
      prev_requested.swap(requested);
    }
    r.levels.push_back(std::move(C));
    adj = std::move(cadj);
  }
  return r;
}

}  // namespace

}  // namespace limn
