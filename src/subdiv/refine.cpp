// Catmull-Clark refinement with OpenSubdiv's Sdc rules, as per-level stencil tables: uniform,
// sparse (per-vertex / per-face depth) and lean (points of the last level only).
//
// References for the rules (facts, not code): OpenSubdiv 3.5 Sdc (catmarkScheme.h, scheme.h,
// crease.cpp) and Far::TopologyRefinerFactory's tagging: boundary and non-manifold edges are
// infinitely sharp; with edge-and-corner interpolation a vertex with one face and two edges is an
// infinitely sharp corner; a vertex's rule is Corner when it is sharp, else Smooth/Dart/Crease/
// Corner by its count of sharp edges; when a rule changes between parent and child the masks are
// blended by the fractional weight of the sharpness that decayed to zero.
//
// OpenSubdiv computes edge and vertex points from the new face points; limn expands those into
// the previous level's vertices, so every stencil reads one level only and levels can be applied
// (or flattened) independently.
//
// Topology: the cage's adjacency is built from its faces (build_adj). A uniformly refined
// level's adjacency is derived from its parent's in closed form, without any search: child
// face c is parent corner c, child corner 4c+i, child edges are one per parent corner (face
// point to edge point) then two per parent edge (edge point to each end's vertex point). Sparse
// levels get theirs in closed form too (sparse_child_adj), with one corner per selected face.
#include "limn/subdiv/refine.hpp"
#include "corner_twins.hpp"
#include "face_varying.hpp"
#include "refine_levels.hpp"
#include "rules.hpp"
#include "shared_weights.hpp"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <span>
#include <stdexcept>

#include "core/cpu.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "limn/mesh/topology.hpp"

#if LIMN_X86_SIMD
#include <immintrin.h>
#endif

namespace limn {

namespace refine_detail {

// Adjacency straight from the faces, without a corner table: corners are sorted by vertex, then
// each vertex groups the half-edges between it and its higher-numbered neighbours into edges, so
// edges are numbered by their lower end. Sets the level's edge list.
Adj build_adj(RefinedLevel& L, size_t nv) {
  const size_t nf = L.face_count(), nc = L.face_vertices.size();
  const uint32_t* fv = L.face_vertices.data();
  Adj a;
  a.quads = true;
  for (size_t f = 0; f < nf && a.quads; ++f) a.quads = L.face_offsets[f + 1] == 4 * (f + 1);
  if (!a.quads) {
    a.corner_face.resize(nc);
    for (size_t f = 0; f < nf; ++f)
      for (uint32_t c = L.face_offsets[f]; c < L.face_offsets[f + 1]; ++c)
        a.corner_face[c] = uint32_t(f);
  }
  const LevelRef lr{L, a};
  a.vco.assign(nv + 1, 0);
  for (size_t c = 0; c < nc; ++c) ++a.vco[fv[c] + 1];
  for (size_t v = 0; v < nv; ++v) a.vco[v + 1] += a.vco[v];
  a.vc.resize(nc);
  {
    std::vector<uint32_t> fill(a.vco.begin(), a.vco.end() - 1);
    for (size_t c = 0; c < nc; ++c) a.vc[fill[fv[c]]++] = uint32_t(c);
  }
  // Half-edge h runs from fv[h] to fv[next(h)]. Around v: its outgoing half-edges, and the
  // incoming ones (the corner before each of v's corners).
  a.corner_edge.assign(nc, kNone);
  std::vector<uint32_t> twin(nc, kNone);
  a.ec.clear();
  a.ec.reserve(nc);
  a.eco.assign(1, 0);
  a.eco.reserve(nc / 2 + 2);
  L.edge_vertices.clear();
  L.edge_vertices.reserve(nc + 4);
  a.edge_non_manifold.clear();
  std::vector<std::pair<uint32_t, uint32_t>> cand;  // (other end, half-edge)
  for (uint32_t v = 0; v < nv; ++v) {
    cand.clear();
    for (uint32_t i = a.vco[v]; i < a.vco[v + 1]; ++i) {
      const uint32_t c = a.vc[i], p = lr.prev(c);
      if (const uint32_t b = fv[lr.next(c)]; b > v) cand.emplace_back(b, c);
      if (const uint32_t u = fv[p]; u > v) cand.emplace_back(u, p);
    }
    for (size_t i = 1; i < cand.size(); ++i)  // a handful of entries: insertion sort
      for (size_t j = i; j > 0 && cand[j] < cand[j - 1]; --j) std::swap(cand[j], cand[j - 1]);
    for (size_t i = 0; i < cand.size();) {
      size_t j = i;
      while (j < cand.size() && cand[j].first == cand[i].first) ++j;
      const uint32_t e = uint32_t(a.eco.size() - 1);
      L.edge_vertices.insert(L.edge_vertices.end(), {v, cand[i].first});
      for (size_t k = i; k < j; ++k)
        a.corner_edge[cand[k].second] = e, a.ec.push_back(cand[k].second);
      a.eco.push_back(uint32_t(a.ec.size()));
      // More than two faces, or two that disagree on its direction: OpenSubdiv cannot order
      // faces around such an edge and treats it as non-manifold (infinitely sharp).
      const uint32_t h0 = cand[i].second, h1 = j - i == 2 ? cand[i + 1].second : kNone;
      const bool opposite = h1 != kNone && fv[h0] != fv[h1];
      a.edge_non_manifold.push_back(j - i > 2 || (j - i == 2 && !opposite));
      if (opposite) {
        twin[h0] = h1, twin[h1] = h0;
      } else if (j - i >= 2) {
        for (size_t k = i; k < j; ++k) twin[cand[k].second] = kNonManifold;
      }
      i = j;
    }
  }
  const size_t ne = a.eco.size() - 1;
  // A vertex is manifold when walking across its edges from one face visits all of its faces
  // (starting from a boundary corner, if any): two fans sharing only the vertex are not.
  a.vertex_non_manifold.assign(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t b = a.vco[v], n = a.vco[v + 1] - b;
    if (n == 0) continue;
    uint32_t start = a.vc[b];
    for (uint32_t i = b; i < b + n; ++i)
      if (twin[a.vc[i]] == kNone) start = a.vc[i];
    uint32_t c = start, seen = 0;
    do {
      ++seen;
      const uint32_t tw = twin[lr.prev(c)];
      if (tw >= kNonManifold || fv[tw] != v) break;  // boundary or torn edge
      c = tw;
    } while (c != start && seen <= n);
    a.vertex_non_manifold[v] = seen != n;
  }
  a.veo.assign(nv + 1, 0);
  for (size_t e = 0; e < ne; ++e) {
    ++a.veo[L.edge_vertices[2 * e] + 1];
    ++a.veo[L.edge_vertices[2 * e + 1] + 1];
  }
  for (size_t v = 0; v < nv; ++v) a.veo[v + 1] += a.veo[v];
  a.ve.resize(2 * ne);
  std::vector<uint32_t> fill(a.veo.begin(), a.veo.end() - 1);
  for (size_t e = 0; e < ne; ++e) {
    a.ve[fill[L.edge_vertices[2 * e]]++] = uint32_t(e);
    a.ve[fill[L.edge_vertices[2 * e + 1]]++] = uint32_t(e);
  }
  return a;
}

// The faces of the uniformly refined child (each parent corner c becomes quad c: vertex point,
// edge point of the outgoing edge, face point, edge point of the incoming edge); with `edges`
// the child's edge list, and with `ca` its adjacency too, all in closed form.
void derive_child(const RefinedLevel& P, const Adj& pa, RefinedLevel& C, bool edges, Adj* ca) {
  const LevelRef pl{P, pa};
  const uint32_t F = uint32_t(P.face_count()), E = uint32_t(P.edge_count()),
                 V = uint32_t(P.vertex_count()), NC = uint32_t(P.face_vertices.size());
  const uint32_t* fv = P.face_vertices.data();
  const uint32_t* ev = P.edge_vertices.data();
  const uint32_t* ce = pa.corner_edge.data();
  constexpr size_t kGrain = 1 << 13;
  auto half = [&](uint32_t e, uint32_t v) { return NC + 2 * e + (ev[2 * size_t(e)] == v ? 0 : 1); };

  refill(C.face_offsets, size_t(NC) + 1);
  refill(C.face_vertices, 4 * size_t(NC));
  refill(C.face_hole, NC);
  if (ca) {
    ca->quads = true;
    ca->corner_face.clear();
    refill(ca->corner_edge, 4 * size_t(NC));
  }
  parallel_range(F, kGrain, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
        const uint32_t p = pl.prev(c), e0 = ce[c], e1 = ce[p];
        uint32_t* q = &C.face_vertices[4 * size_t(c)];
        q[0] = F + E + fv[c], q[1] = F + e0, q[2] = uint32_t(f), q[3] = F + e1;
        C.face_offsets[c] = 4 * c;
        C.face_hole[c] = P.face_hole[f];
        if (ca) {
          uint32_t* k = &ca->corner_edge[4 * size_t(c)];
          k[0] = half(e0, fv[c]), k[1] = c, k[2] = p, k[3] = half(e1, fv[c]);
        }
      }
    }
  });
  C.face_offsets[NC] = 4 * NC;
  if (!ca && !edges) return;

  const size_t NE = size_t(NC) + 2 * size_t(E);
  refill(C.edge_vertices, 2 * NE);
  if (ca) {
    refill(ca->eco, NE + 1);
    refill(ca->ec, 4 * size_t(NC));
    refill(ca->vco, size_t(F) + E + V + 1);
    refill(ca->vc, 4 * size_t(NC));
    refill(ca->veo, size_t(F) + E + V + 1);
    refill(ca->ve, 2 * NE);
    ca->edge_non_manifold.clear();
  }
  // Per parent face: the interior edges (one per corner) and the face point's rings.
  parallel_range(F, kGrain, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      const uint32_t o = P.face_offsets[f];
      for (uint32_t c = o; c < P.face_offsets[f + 1]; ++c) {
        C.edge_vertices[2 * size_t(c)] = uint32_t(f);
        C.edge_vertices[2 * size_t(c) + 1] = F + ce[c];
      }
      if (!ca) continue;
      ca->vco[f] = o;
      ca->veo[f] = o;
      for (uint32_t c = o; c < P.face_offsets[f + 1]; ++c) {
        ca->eco[c] = 2 * c;
        ca->ec[2 * size_t(c)] = 4 * c + 1;
        ca->ec[2 * size_t(c) + 1] = 4 * pl.next(c) + 2;
        ca->vc[c] = 4 * c + 2;
        ca->ve[c] = c;
      }
    }
  });
  // Per parent edge: its two halves and the edge point's rings.
  parallel_range(E, kGrain, [&](size_t b, size_t e_end) {
    for (size_t e = b; e < e_end; ++e) {
      if (!ca) {
        for (uint32_t j = 0; j < 2; ++j) {
          const size_t id = size_t(NC) + 2 * e + j;
          C.edge_vertices[2 * id] = F + uint32_t(e);
          C.edge_vertices[2 * id + 1] = F + E + ev[2 * e + j];
        }
        continue;
      }
      const uint32_t k0 = pa.eco[e], m = pa.eco[e + 1] - k0;
      const size_t vbase = size_t(NC) + 2 * size_t(k0);  // ep(e)'s corners
      ca->vco[F + e] = uint32_t(vbase);
      const size_t ebase = size_t(NC) + 2 * e + k0;  // ep(e)'s edges
      ca->veo[F + e] = uint32_t(ebase);
      ca->ve[ebase] = uint32_t(NC + 2 * e);
      ca->ve[ebase + 1] = uint32_t(NC + 2 * e + 1);
      for (uint32_t j = 0; j < 2; ++j) {
        const size_t id = size_t(NC) + 2 * e + j;
        const uint32_t a = ev[2 * e + j];
        C.edge_vertices[2 * id] = F + uint32_t(e);
        C.edge_vertices[2 * id + 1] = F + E + a;
        const size_t o = 2 * size_t(NC) + 2 * size_t(k0) + size_t(j) * m;
        ca->eco[id] = uint32_t(o);
        for (uint32_t i = 0; i < m; ++i) {
          const uint32_t c = pa.ec[k0 + i];
          ca->ec[o + i] = fv[c] == a ? 4 * c : 4 * pl.next(c) + 3;
        }
      }
      for (uint32_t i = 0; i < m; ++i) {
        const uint32_t c = pa.ec[k0 + i];
        ca->vc[vbase + 2 * i] = 4 * c + 1;
        ca->vc[vbase + 2 * i + 1] = 4 * pl.next(c) + 3;
        ca->ve[ebase + 2 + i] = c;
      }
    }
  });
  if (!ca) return;
  // Per parent vertex: the vertex point's rings.
  parallel_range(V, kGrain, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) {
      const uint32_t c0 = pa.vco[v], e0 = pa.veo[v];
      const size_t cbase = 3 * size_t(NC) + c0, ebase = 2 * size_t(NC) + 2 * size_t(E) + e0;
      ca->vco[F + E + v] = uint32_t(cbase);
      ca->veo[F + E + v] = uint32_t(ebase);
      for (uint32_t i = c0; i < pa.vco[v + 1]; ++i) ca->vc[cbase + (i - c0)] = 4 * pa.vc[i];
      for (uint32_t i = e0; i < pa.veo[v + 1]; ++i)
        ca->ve[ebase + (i - e0)] = half(pa.ve[i], uint32_t(v));
    }
  });
  ca->eco[NE] = 4 * NC;
  ca->vco[size_t(F) + E + V] = 4 * NC;
  ca->veo[size_t(F) + E + V] = uint32_t(2 * NE);
}

// The non-manifold test OpenSubdiv's tagging uses: faces around the vertex do not form a single
// fan (or a non-manifold edge touches it).
bool cage_vertex_non_manifold(const Adj& adj, uint32_t v) {
  const uint32_t nedges = adj.vertex_edge_count(v), nfaces = adj.vertex_face_count(v);
  int nm_edges = 0, boundary = 0;
  for (uint32_t k = adj.veo[v]; k < adj.veo[v + 1]; ++k) {
    nm_edges += adj.edge_non_manifold[adj.ve[k]];
    boundary += adj.edge_face_count(adj.ve[k]) == 1;
  }
  return nm_edges > 0 || adj.vertex_non_manifold[v] ||
         (nfaces != nedges && (nfaces + 1 != nedges || boundary != 2));
}

// Level 0 sharpness: tags, then boundary, non-manifold and corner sharpening.
void init_cage_level(const Mesh& cage, const SubdivOptions& o, const Adj& adj, RefinedLevel& L,
                     std::vector<uint8_t>* excluded) {
  const LevelRef lr{L, adj};
  const size_t nv = cage.vertex_count(), ne = L.edge_vertices.size() / 2;
  L.edge_sharpness.assign(ne, 0.0f);
  for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
    const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
    uint32_t found = kNone;
    for (uint32_t k = adj.veo[a]; k < adj.veo[a + 1]; ++k)
      if (lr.other_end(adj.ve[k], a) == b) found = adj.ve[k];
    if (found == kNone)
      throw InputError(
          fmt::format("crease tag {} names vertices {} and {}, which share no edge", i, a, b));
    L.edge_sharpness[found] = std::min(cage.crease_sharpness[i], kInf);
  }
  L.face_hole.assign(cage.face_count(), 0);
  for (uint32_t f : cage.hole_faces) L.face_hole[f] = 1;
  if (excluded) excluded->assign(nv, 0);
  auto count_edges = [&](uint32_t v, int& nm_edges, int& boundary) {
    for (uint32_t k = adj.veo[v]; k < adj.veo[v + 1]; ++k) {
      nm_edges += adj.edge_non_manifold[adj.ve[k]];
      boundary += adj.edge_face_count(adj.ve[k]) == 1;
    }
  };
  std::vector<uint8_t> vertex_nm(nv, 0);
  for (uint32_t v = 0; v < nv; ++v) vertex_nm[v] = cage_vertex_non_manifold(adj, v);
  // Boundary interpolation "none": faces at a boundary vertex whose boundary edges are not all
  // explicitly infinitely sharp are excluded, as holes (tested before boundaries are sharpened).
  if (o.boundary == BoundaryInterpolation::none) {
    for (uint32_t v = 0; v < nv; ++v) {
      if (adj.vertex_edge_count(v) == adj.vertex_face_count(v) && !vertex_nm[v]) continue;
      bool exclude = false;
      for (uint32_t k = adj.veo[v]; k < adj.veo[v + 1] && !exclude; ++k) {
        const uint32_t e = adj.ve[k];
        exclude = adj.edge_face_count(e) == 1 && L.edge_sharpness[e] < kInf;
      }
      if (!exclude) continue;
      for (uint32_t i = adj.vco[v]; i < adj.vco[v + 1]; ++i)
        L.face_hole[adj.face_of(adj.vc[i])] = 1;
      if (excluded) (*excluded)[v] = 1;
    }
  }
  for (uint32_t e = 0; e < ne; ++e)
    if (adj.edge_face_count(e) == 1 || adj.edge_non_manifold[e]) L.edge_sharpness[e] = kInf;

  L.vertex_sharpness.assign(nv, 0.0f);
  for (size_t i = 0; i < cage.corner_vertices.size(); ++i)
    L.vertex_sharpness[cage.corner_vertices[i]] = std::min(cage.corner_sharpness[i], kInf);
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t nedges = adj.vertex_edge_count(v), nfaces = adj.vertex_face_count(v);
    int nm_edges = 0, boundary = 0;
    count_edges(v, nm_edges, boundary);
    if (nfaces == 0) {
      L.vertex_sharpness[v] = kInf;  // on no face: OpenSubdiv makes it an infinitely sharp corner
    } else if (nfaces == 1 && nedges == 2) {
      if (o.boundary == BoundaryInterpolation::edge_and_corner) L.vertex_sharpness[v] = kInf;
    } else if (vertex_nm[v]) {
      // Sharpened, except on an interior non-manifold crease: two opposing non-manifold edges
      // with extra "fins" (more faces than edges) and no boundary.
      if (!(nm_edges == 2 && boundary == 0 && nfaces > nedges)) L.vertex_sharpness[v] = kInf;
    }
  }
}

// Sharpness in the child of parent edge e's half at its end v (Chaikin needs v's other edges;
// pe and ce are scratch).
float half_sharpness_at(const SubdivOptions& o, const RefinedLevel& P, const Adj& pa, size_t e,
                        uint32_t v, std::vector<float>& pe, std::vector<float>& ce) {
  const float s = P.edge_sharpness[e];
  if (!sharp(s) || o.crease_method != CreaseMethod::chaikin) return decrement(s);
  const uint32_t k0 = pa.veo[v], n = pa.veo[v + 1] - k0;
  pe.resize(n), ce.resize(n);
  uint32_t self = 0;
  for (uint32_t k = 0; k < n; ++k) {
    pe[k] = P.edge_sharpness[pa.ve[k0 + k]];
    if (pa.ve[k0 + k] == e) self = k;
  }
  child_edge_sharpness(o, pe.data(), int(n), ce.data());
  return ce[self];
}

// The same for half j (at end edge_vertices[2e+j]).
float half_sharpness(const SubdivOptions& o, const RefinedLevel& P, const Adj& pa, size_t e,
                     uint32_t j, std::vector<float>& pe, std::vector<float>& ce) {
  return half_sharpness_at(o, P, pa, e, P.edge_vertices[2 * e + j], pe, ce);
}

constexpr size_t kStencilChunk = 1 << 14;

// Calls body(first point, table) for consecutive chunks of kStencilChunk child points, in
// parallel; each table holds its chunk's stencils and is reused for the thread's next chunk.
template <class Body>
void for_stencil_chunks(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                        const Selection& sel, Body&& body) {
  constexpr size_t chunk = kStencilChunk;
  const size_t n = sel.points(), chunks = (n + chunk - 1) / chunk;
  // Per-thread tables keep their memory from chunk to chunk, so streaming a level through them
  // touches no fresh pages.
  tbb::enumerable_thread_specific<StencilTable> scratch;
  auto run = [&](size_t c) {
    VertexRules rules(o, P, a, sel);
    StencilTable& t = scratch.local();
    const size_t b = c * chunk, e = std::min(n, b + chunk);
    t.offsets.clear();
    t.indices.clear();
    t.weights.clear();
    t.offsets.reserve(e - b + 1);
    t.indices.reserve(8 * (e - b));
    t.weights.reserve(8 * (e - b));
    t.offsets.push_back(0);
    for (size_t i = b; i < e; ++i) rules.point(i, t);
    body(b, t);
  };
  if (chunks <= 1) {
    if (n) run(0);
    return;
  }
  tbb::parallel_for(size_t(0), chunks, run);
}

// At least the entries of the kept rows (every point a mask can read, counted once per face or
// edge it comes through: a face point its face's vertices, an edge point its ends and the other
// vertices of its faces, a vertex point itself, its edge neighbours and the other vertices of
// its faces), so the serial build's room is a close bound and never grows by doubling (the
// build's peak heap is a level's tables and two levels' topology).
size_t entry_bound(const RefinedLevel& P, const Adj& a, const Selection& sel, const uint8_t* keep) {
  const LevelRef l{P, a};
  size_t total = 64, i = 0;
  for (uint32_t j = 0; j < sel.nf; ++j, ++i)
    if (!keep || keep[i]) total += l.face_size(sel.face(j));
  for (uint32_t j = 0; j < sel.ne; ++j, ++i) {
    if (keep && !keep[i]) continue;
    const uint32_t e = sel.edge(j);
    total += 2;
    for (uint32_t k = a.eco[e]; k < a.eco[e + 1]; ++k) total += l.face_size(a.face_of(a.ec[k])) - 2;
  }
  for (uint32_t j = 0; j < sel.nv; ++j, ++i) {
    if (keep && !keep[i]) continue;
    const uint32_t v = sel.vertex(j);
    total += 1 + a.vertex_edge_count(v);
    for (uint32_t k = a.vco[v]; k < a.vco[v + 1]; ++k) total += l.face_size(a.face_of(a.vc[k])) - 3;
  }
  return total;
}

// All the child points' stencils as one table, rows sharing their weights (see StencilTable).
// Large levels take two parallel passes (sizes, then entries in place): computing each stencil
// twice costs less than holding (and first touching) the table twice; each chunk of the second
// pass shares weights within itself, and the chunks' pools are concatenated. With `keep`, only
// points i with keep[i] get their stencil; the others get empty rows.
StencilTable build_stencils(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                            const Selection& sel, const uint8_t* keep) {
  const size_t n = sel.points();
  StencilTable out;
  // Writes the computed row's k indices to `indices` and its weights to `pool` (through
  // `shared`, `row` holding them first); returns where they start in the pool.
  auto write_row = [](const VertexRules& rules, size_t k, uint32_t* indices,
                      std::vector<float>& row, detail::SharedWeights& shared,
                      std::vector<float>& pool) {
    if (row.size() < k) row.resize(std::max(k, size_t(64)));
    rules.write(indices, row.data());
    return shared.add(pool, row.data(), uint32_t(k));
  };
  if (n < 4 * kStencilChunk) {  // small: one serial pass, writing in place
    // Room reserved for the usual 4-9 terms a point (only address space: pages are touched as
    // the size grows in small steps just ahead of the writes), and no per-stencil append.
    out.offsets.resize(n + 1);
    out.weight_offsets.resize(n);
    out.indices.reserve(entry_bound(P, a, sel, keep));
    constexpr size_t kStep = 4096;
    size_t used = 0;
    VertexRules rules(o, P, a, sel);
    detail::SharedWeights shared;
    std::vector<float> row;
    for (size_t i = 0; i < n; ++i) {
      if (keep && !keep[i]) {
        out.offsets[i + 1] = uint32_t(used);
        continue;
      }
      const size_t k = rules.compute(i);
      if (used + k > out.indices.size()) {
        // In steps within the room reserved (the bound holds, so it never reallocates).
        size_t to = std::max(used + k, out.indices.size() + kStep);
        if (used + k <= out.indices.capacity()) to = std::min(to, out.indices.capacity());
        out.indices.resize(to);
      }
      out.weight_offsets[i] =
          write_row(rules, k, out.indices.data() + used, row, shared, out.weights);
      used += k;
      if (used > UINT32_MAX)
        throw InputError("refinement level needs more than 2^32 stencil entries");
      out.offsets[i + 1] = uint32_t(used);
    }
    out.indices.resize(used);
    return out;
  }
  refill(out.offsets, n + 1, 0u);
  std::vector<uint32_t> sizes;
  refill(sizes, n, 0u);
  parallel_range(n, kStencilChunk, [&](size_t b, size_t e) {
    VertexRules rules(o, P, a, sel);
    for (size_t i = b; i < e; ++i) sizes[i] = keep && !keep[i] ? 0 : uint32_t(rules.compute(i));
  });
  size_t total = 0;
  for (size_t i = 0; i < n; ++i) {
    total += sizes[i];
    if (total > UINT32_MAX)
      throw InputError("refinement level needs more than 2^32 stencil entries");
    out.offsets[i + 1] = uint32_t(total);
  }
  std::vector<uint32_t>().swap(sizes);
  refill(out.indices, total, 0u);
  refill(out.weight_offsets, n, 0u);
  const size_t chunks = (n + kStencilChunk - 1) / kStencilChunk;
  std::vector<std::vector<float>> pools(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    VertexRules rules(o, P, a, sel);
    detail::SharedWeights shared;
    std::vector<float> row;
    for (size_t i = c * kStencilChunk, e = std::min(n, i + kStencilChunk); i < e; ++i) {
      if (keep && !keep[i]) continue;
      const size_t k = rules.compute(i);
      out.weight_offsets[i] =
          write_row(rules, k, out.indices.data() + out.offsets[i], row, shared, pools[c]);
    }
  });
  std::vector<uint32_t> base(chunks + 1, 0);
  for (size_t c = 0; c < chunks; ++c) base[c + 1] = base[c] + uint32_t(pools[c].size());
  out.weights.reserve(base[chunks]);
  for (const std::vector<float>& p : pools)
    out.weights.insert(out.weights.end(), p.begin(), p.end());
  parallel_range(chunks, 1, [&](size_t cb, size_t ce) {
    for (size_t c = cb; c < ce; ++c)
      for (size_t i = c * kStencilChunk, e = std::min(n, i + kStencilChunk); i < e; ++i)
        out.weight_offsets[i] += base[c];
  });
  return out;
}

// Child vertex sharpness: vertex points inherit their parent's, decayed.
void child_vertex_sharpness(const RefinedLevel& P, const Selection& sel, RefinedLevel& C) {
  refill(C.vertex_sharpness, sel.points(), 0.0f);
  const size_t base = size_t(sel.nf) + sel.ne;
  parallel_range(sel.nv, 1 << 16, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      C.vertex_sharpness[base + i] = decrement(P.vertex_sharpness[sel.vertex(uint32_t(i))]);
  });
}

// Child edge sharpness on a derived (uniform) child: only the halves of parent edges can be
// sharp; half j of parent edge e is child edge corners + 2e + j.
void derived_edge_sharpness(const SubdivOptions& o, const RefinedLevel& P, const Adj& pa,
                            RefinedLevel& C) {
  const size_t NC = P.face_vertices.size(), E = P.edge_count();
  refill(C.edge_sharpness, NC + 2 * E, 0.0f);
  parallel_range(E, 1 << 16, [&](size_t b, size_t end) {
    std::vector<float> pe, ce;
    for (size_t e = b; e < end; ++e)
      if (sharp(P.edge_sharpness[e]))
        for (uint32_t j = 0; j < 2; ++j)
          C.edge_sharpness[NC + 2 * e + j] = half_sharpness(o, P, pa, e, j, pe, ce);
  });
}

// The cage as level 0, with its adjacency and tags.
Adj cage_level(const Mesh& cage, const SubdivOptions& o, RefinedLevel& L0,
               std::vector<uint8_t>* excluded) {
  validate(cage, "cage");
  L0.face_offsets = cage.face_offsets;
  L0.face_vertices = cage.face_vertices;
  Adj a = build_adj(L0, cage.vertex_count());
  init_cage_level(cage, o, a, L0, excluded);
  return a;
}

}  // namespace refine_detail

using namespace refine_detail;

SubdivOptions subdiv_options(const Mesh& mesh) {
  SubdivOptions o;
  if (mesh.tags.boundary != BoundaryInterpolation::unset) o.boundary = mesh.tags.boundary;
  if (mesh.tags.crease_method != CreaseMethod::unset) o.crease_method = mesh.tags.crease_method;
  o.smooth_triangles = mesh.tags.smooth_triangles;
  if (mesh.tags.fvar_boundary >= 0 && mesh.tags.fvar_boundary <= 5)
    o.face_varying = static_cast<FVarInterpolation>(mesh.tags.fvar_boundary);
  return o;
}

std::vector<float> UniformRefinement::positions(const Mesh& cage, int level) const {
  return apply_chain(stencils, cage, level);
}

UniformRefinement refine_uniform(const Mesh& cage, int depth, const SubdivOptions& options,
                                 std::span<const FaceVaryingInput> face_varying) {
  if (depth < 0 || depth > 8)
    throw InputError(fmt::format("refinement depth {} out of range (0-8)", depth));
  UniformRefinement r;
  r.options = options;
  r.levels.resize(size_t(depth) + 1);
  r.stencils.resize(size_t(depth));
  Adj a = cage_level(cage, options, r.levels[0]);
  // The last level's adjacency is kept only for face-varying limits.
  const bool want_limit =
      std::any_of(face_varying.begin(), face_varying.end(), [](auto& c) { return c.limit; });
  std::vector<FVarState> fvar;
  for (const FaceVaryingInput& in : face_varying) {
    fvar.push_back(fvar_cage_state(options, r.levels[0], a, in.corner_values, in.value_count));
    FaceVaryingLevels& out = r.face_varying.emplace_back();
    out.corner_values.emplace_back(in.corner_values.begin(), in.corner_values.end());
    out.value_counts.push_back(in.value_count);
  }
  for (size_t k = 0; k < size_t(depth); ++k) {
    const RefinedLevel& P = r.levels[k];
    RefinedLevel& C = r.levels[k + 1];
    const Selection all = Selection::everything(P);
    r.stencils[k] = build_stencils(options, P, a, all);
    for (size_t i = 0; i < fvar.size(); ++i) {
      FVarState child;
      FaceVaryingLevels& out = r.face_varying[i];
      out.stencils.push_back(fvar_refine(options, P, a, fvar[i], child));
      out.value_counts.push_back(child.value_count());
      // Level k's corner values (the caller's, on the cage) are kept once the step has read them.
      if (k > 0) out.corner_values[k] = std::move(fvar[i].corner_value);
      out.corner_values.emplace_back();
      fvar[i] = std::move(child);
    }
    Adj ca;
    const bool last = k + 1 == size_t(depth) && !want_limit;
    derive_child(P, a, C, true, last ? nullptr : &ca);
    child_vertex_sharpness(P, all, C);
    derived_edge_sharpness(options, P, a, C);
    a = std::move(ca);
  }
  const bool quads = r.levels.back().face_offsets.back() == 4 * r.levels.back().face_count();
  for (size_t i = 0; i < fvar.size(); ++i) {
    if (face_varying[i].limit && quads)
      r.face_varying[i].limit = fvar_limit(options, r.levels.back(), a, fvar[i]);
    if (depth > 0) r.face_varying[i].corner_values[size_t(depth)] = std::move(fvar[i].corner_value);
  }
  return r;
}

namespace {

// A face-varying channel subdivide_uniform carries to its output.
struct Carried {
  std::vector<float>* values_out;
  std::vector<uint32_t>* indices_out;
  std::vector<float> values;  // the current level's
  FVarState state;
  int width;
  bool unit;  // normals: renormalised at the end
};

void normalize3(std::vector<float>& v) {
  for (size_t i = 0; i + 2 < v.size(); i += 3) {
    const double l =
        std::sqrt(double(v[i]) * v[i] + double(v[i + 1]) * v[i + 1] + double(v[i + 2]) * v[i + 2]);
    if (l > 0.0)
      for (size_t k = 0; k < 3; ++k) v[i + k] = float(v[i + k] / l);
  }
}

}  // namespace

Mesh subdivide_uniform(const Mesh& cage, int depth, const SubdivOptions& options,
                       SubdivideStats* stats) {
  using clock = std::chrono::steady_clock;
  if (depth < 0 || depth > 8)
    throw InputError(fmt::format("refinement depth {} out of range (0-8)", depth));
  SubdivideStats st;
  auto t0 = clock::now();
  RefinedLevel P;
  Adj pa = cage_level(cage, options, P);
  st.levels.push_back({P.vertex_count(), P.face_count(), P.edge_count(), 0});
  st.topology_ms += ms_since(t0);
  Mesh out;
  out.tags = cage.tags;
  // UVs and per-corner normals ride along as face-varying channels, colours as vertex data.
  std::vector<Carried> carried;
  auto carry = [&](std::vector<float>& values_out, std::vector<uint32_t>& indices_out,
                   const std::vector<float>& values, const std::vector<uint32_t>& indices,
                   int width, bool unit) {
    if (indices.empty()) return;
    carried.push_back({&values_out, &indices_out, values,
                       fvar_cage_state(options, P, pa, indices, values.size() / size_t(width)),
                       width, unit});
  };
  carry(out.uvs, out.uv_indices, cage.uvs, cage.uv_indices, 2, false);
  carry(out.normals, out.normal_indices, cage.normals, cage.normal_indices, 3, true);
  std::vector<float> colors =
      cage.colors.size() == 4 * cage.vertex_count() ? cage.colors : std::vector<float>();
  // The output's faces and their channels' corners, holes dropped in place (the last level's
  // arrays are most of the peak: no second copy).
  auto emit_faces = [&](RefinedLevel& L) {
    // Writes never pass what is still to be read: face f's corners land at or before their own
    // place, its end offset at or before index f + 1 (equal to it until a hole is skipped).
    uint32_t w = 0, kept = 0;
    const size_t nf = L.face_count();
    for (size_t f = 0; f < nf; ++f) {
      const uint32_t b = L.face_offsets[f], e = L.face_offsets[f + 1];
      if (L.face_hole[f]) continue;
      for (uint32_t c = b; c < e; ++c, ++w) {
        L.face_vertices[w] = L.face_vertices[c];
        for (Carried& k : carried) k.state.corner_value[w] = k.state.corner_value[c];
      }
      L.face_offsets[++kept] = w;
    }
    L.face_offsets.resize(size_t(kept) + 1);
    L.face_vertices.resize(w);
    out.face_offsets = std::move(L.face_offsets);
    out.face_vertices = std::move(L.face_vertices);
    for (Carried& k : carried) {
      k.state.corner_value.resize(w);
      // Values are the level's own (on the cage: the caller's indices into its values).
      if (!k.state.source.empty())
        for (uint32_t& i : k.state.corner_value) i = k.state.source[i];
      *k.indices_out = std::move(k.state.corner_value);
      *k.values_out = std::move(k.values);
      if (k.unit) normalize3(*k.values_out);
    }
    out.colors = std::move(colors);
  };
  if (depth == 0) {
    out.positions = cage.positions;
    emit_faces(P);
    out.crease_edges = cage.crease_edges, out.crease_sharpness = cage.crease_sharpness;
    out.corner_vertices = cage.corner_vertices, out.corner_sharpness = cage.corner_sharpness;
    if (stats) *stats = std::move(st);
    return out;
  }
  std::vector<float> pos = cage.positions, next, next_colors;
  std::vector<float> pe, ce;
  for (int k = 0; k < depth; ++k) {
    const Selection all = Selection::everything(P);
    t0 = clock::now();
    // Stencils are built chunk by chunk, applied at once and dropped: never stored whole.
    refill(next, 3 * all.points(), 0.0f);
    if (!colors.empty()) refill(next_colors, 4 * all.points(), 0.0f);
    std::vector<size_t> entries((all.points() + kStencilChunk - 1) / kStencilChunk, 0);
    for_stencil_chunks(options, P, pa, all, [&](size_t b, StencilTable& t) {
      apply_serial(t, 0, t.size(), pos.data(), next.data() + 3 * b, 3);
      if (!colors.empty())
        apply_serial(t, 0, t.size(), colors.data(), next_colors.data() + 4 * b, 4);
      entries[b / kStencilChunk] = t.indices.size();
    });
    colors.swap(next_colors);
    for (Carried& c : carried) {
      FVarState child;
      c.values = fvar_refine_apply(options, P, pa, c.state, child, c.values.data(), c.width);
      c.state = std::move(child);
    }
    st.stencils_ms += ms_since(t0);
    t0 = clock::now();
    const size_t nc = P.face_vertices.size();
    SubdivideStats::Level counts{all.points(), nc, nc + 2 * P.edge_count(), 0};
    for (size_t n : entries) counts.stencil_entries += n;
    st.levels.push_back(counts);
    pos.swap(next);
    next = std::vector<float>();
    RefinedLevel C;
    if (k + 1 < depth) {
      Adj ca;
      derive_child(P, pa, C, true, &ca);
      child_vertex_sharpness(P, all, C);
      derived_edge_sharpness(options, P, pa, C);
      P = std::move(C);
      pa = std::move(ca);
      st.topology_ms += ms_since(t0);
      continue;
    }
    // The last level: faces without holes, and what sharpness is left as tags.
    derive_child(P, pa, C, false, nullptr);
    const uint32_t F = uint32_t(P.face_count()), E = uint32_t(P.edge_count());
    for (size_t e = 0; e < E; ++e) {
      if (!sharp(P.edge_sharpness[e])) continue;
      for (uint32_t j = 0; j < 2; ++j) {
        const float s = half_sharpness(options, P, pa, e, j, pe, ce);
        if (!sharp(s)) continue;
        out.crease_edges.insert(out.crease_edges.end(),
                                {F + uint32_t(e), F + E + P.edge_vertices[2 * e + j]});
        out.crease_sharpness.push_back(s);
      }
    }
    for (size_t v = 0; v < P.vertex_count(); ++v) {
      const float s = decrement(P.vertex_sharpness[v]);
      if (!sharp(s)) continue;
      out.corner_vertices.push_back(F + E + uint32_t(v));
      out.corner_sharpness.push_back(s);
    }
    {
      RefinedLevel drop = std::move(P);
      Adj drop_adj = std::move(pa);
    }
    const bool holes = std::find(C.face_hole.begin(), C.face_hole.end(), 1) != C.face_hole.end();
    if (holes || !carried.empty()) {
      emit_faces(C);
    } else {
      out.face_offsets = std::move(C.face_offsets);
      out.face_vertices = std::move(C.face_vertices);
      out.colors = std::move(colors);
    }
    out.positions = std::move(pos);
    st.output_ms += ms_since(t0);
  }
  if (stats) *stats = std::move(st);
  return out;
}

}  // namespace limn
