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

namespace {

constexpr float kInf = kInfiniteSharpness;
constexpr int kMaxChannels = 16;

// Sizes a vector to n elements of `value`, dropping any old buffer first so a level's arrays
// never hold two copies at once.
template <class T, class A>
void refill(std::vector<T, A>& v, size_t n, T value = T()) {
  if (v.capacity() < n) std::vector<T, A>().swap(v);
  v.assign(n, value);
}

bool sharp(float s) {
  return s > 0.0f;
}
bool semi_sharp(float s) {
  return s > 0.0f && s < kInf;
}

float decrement(float s) {
  if (s <= 0.0f) return 0.0f;
  if (s >= kInf) return kInf;
  return s > 1.0f ? s - 1.0f : 0.0f;
}

enum Rule : uint8_t { kSmooth = 1, kDart = 2, kCrease = 4, kCorner = 8 };

Rule vertex_rule(float vertex_sharpness, int sharp_edges) {
  if (sharp(vertex_sharpness)) return kCorner;
  return sharp_edges > 2 ? kCorner : static_cast<Rule>(1 << sharp_edges);
}

// Sharpness of the child edges around a vertex (Sdc::Crease::SubdivideEdgeSharpnessesAround-
// Vertex): uniform decrements; Chaikin blends each semi-sharp edge with the mean of the others.
void child_edge_sharpness(const SubdivOptions& o, const float* parent, int n, float* child) {
  if (o.crease_method != CreaseMethod::chaikin || n < 2) {
    for (int i = 0; i < n; ++i) child[i] = decrement(parent[i]);
    return;
  }
  float sum = 0.0f;
  int count = 0;
  for (int i = 0; i < n; ++i)
    if (semi_sharp(parent[i])) sum += parent[i], ++count;
  for (int i = 0; i < n; ++i) {
    const float p = parent[i];
    if (!sharp(p)) {
      child[i] = 0.0f;
    } else if (p >= kInf) {
      child[i] = kInf;
    } else if (count == 1) {
      child[i] = decrement(p);
    } else {
      const float others = (sum - p) / static_cast<float>(count - 1);
      const float c = (0.75f * p + 0.25f * others) - 1.0f;
      child[i] = sharp(c) ? c : 0.0f;
    }
  }
}

// Sdc::Crease::ComputeFractionalWeightAtVertex.
float fractional_weight(const SubdivOptions& o, float pv, float cv, const float* pe,
                        const float* ce, int n) {
  int count = 0;
  float sum = 0.0f;
  if (sharp(pv) && !sharp(cv)) count = 1, sum = pv;
  for (int i = 0; i < n; ++i) {
    const bool transition = o.crease_method == CreaseMethod::chaikin
                                ? sharp(pe[i]) && !sharp(ce[i])
                                : sharp(pe[i]) && pe[i] <= 1.0f;
    if (transition) sum += pe[i], ++count;
  }
  if (count == 0) return 0.0f;
  const float w = sum / static_cast<float>(count);
  return w > 1.0f ? 1.0f : w;
}

// A stencil under construction: weighted parent vertices, merged per vertex as they are added
// (stencils hold a handful of distinct vertices, so a linear scan beats sorting). A 64-bit
// filter of the vertices seen skips the scan for most new vertices: regular stencils have no
// repeats at all.
struct Terms {
  std::vector<uint32_t> idx;
  std::vector<double> w;
  size_t n = 0;
  uint64_t seen = 0;
  Terms() : idx(64), w(64) {}
  [[gnu::always_inline]] inline void add(uint32_t v, double weight) {
    const uint64_t bit = uint64_t(1) << ((v * 0x9E3779B1u) >> 26);
    if (seen & bit) {
      uint32_t* ix = idx.data();
      for (size_t i = 0; i < n; ++i)
        if (ix[i] == v) {
          w[i] += weight;
          return;
        }
    }
    seen |= bit;
    if (n == idx.size()) grow();
    idx[n] = v, w[n] = weight, ++n;
  }
  void grow() {
    idx.resize(2 * n);
    w.resize(2 * n);
  }
  void scale(double s) {
    for (size_t i = 0; i < n; ++i) w[i] *= s;
  }
  void append(const Terms& other, double s) {
    for (size_t i = 0; i < other.n; ++i) add(other.idx[i], other.w[i] * s);
  }
  void clear() { n = 0, seen = 0; }
  // Appends the stencil (inserted, not resized and overwritten: a zero fill per stencil cost
  // as much as computing it).
  void emit(StencilTable& table) {
    const size_t base = table.indices.size();
    if (base + n > table.indices.capacity()) {
      table.indices.reserve(2 * (base + n));
      table.weights.reserve(2 * (base + n));
    }
    float inline_w[kMaxInline];
    std::vector<float> big;
    float* wf = inline_w;
    if (n > kMaxInline) big.resize(n), wf = big.data();
    for (size_t i = 0; i < n; ++i) wf[i] = static_cast<float>(w[i]);
    table.indices.insert(table.indices.end(), idx.data(), idx.data() + n);
    table.weights.insert(table.weights.end(), wf, wf + n);
    table.offsets.push_back(static_cast<uint32_t>(base + n));
    clear();
  }
  static constexpr size_t kMaxInline = 32;
};

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

// Level 0 sharpness: tags, then boundary, non-manifold and corner sharpening.
void init_cage_level(const Mesh& cage, const SubdivOptions& o, const Adj& adj, RefinedLevel& L) {
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
  // The non-manifold test OpenSubdiv's tagging uses: faces around the vertex do not form a
  // single fan (or a non-manifold edge touches it).
  auto count_edges = [&](uint32_t v, int& nm_edges, int& boundary) {
    for (uint32_t k = adj.veo[v]; k < adj.veo[v + 1]; ++k) {
      nm_edges += adj.edge_non_manifold[adj.ve[k]];
      boundary += adj.edge_face_count(adj.ve[k]) == 1;
    }
  };
  std::vector<uint8_t> vertex_nm(nv, 0);
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t nedges = adj.vertex_edge_count(v), nfaces = adj.vertex_face_count(v);
    int nm_edges = 0, boundary = 0;
    count_edges(v, nm_edges, boundary);
    vertex_nm[v] = nm_edges > 0 || adj.vertex_non_manifold[v] ||
                   (nfaces != nedges && (nfaces + 1 != nedges || boundary != 2));
  }
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
      if (exclude)
        for (uint32_t i = adj.vco[v]; i < adj.vco[v + 1]; ++i)
          L.face_hole[adj.face_of(adj.vc[i])] = 1;
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

// The stencil of every child point, from the rules. One instance per thread: it owns scratch.
class Rules {
 public:
  Rules(const SubdivOptions& o, const RefinedLevel& P, const Adj& a, const Selection& sel)
      : o_(o), P_(P), a_(a), l_{P, a}, sel_(sel) {}

  // Appends the stencil of child point i (block numbering) to `out`.
  void point(size_t i, StencilTable& out) {
    compute(i);
    acc_.emit(out);
  }
  // The stencil of child point i, kept until write(): returns its size.
  size_t compute(size_t i) {
    acc_.clear();
    if (i < sel_.nf) {
      face_point(sel_.face(uint32_t(i)), 1.0, acc_);
    } else if (i < size_t(sel_.nf) + sel_.ne) {
      edge_point(sel_.edge(uint32_t(i - sel_.nf)));
    } else {
      vertex_point(sel_.vertex(uint32_t(i - sel_.nf - sel_.ne)));
    }
    return acc_.n;
  }
  void write(uint32_t* indices, float* weights) const {
    for (size_t k = 0; k < acc_.n; ++k)
      indices[k] = acc_.idx[k], weights[k] = static_cast<float>(acc_.w[k]);
  }

 private:
  void face_point(uint32_t f, double w, Terms& t) const {
    const uint32_t b = P_.face_offsets[f], n = P_.face_offsets[f + 1] - b;
    const double wi = w / double(n);
    for (uint32_t c = b; c < b + n; ++c) t.add(P_.face_vertices[c], wi);
  }

  // Smooth edge mask, blended with the midpoint by `blend` (the sharp mask's weight).
  void smooth_edge(uint32_t e, uint32_t a, uint32_t b, double blend) {
    const uint32_t k0 = a_.eco[e], nfe = a_.eco[e + 1] - k0;
    double vw = 0.25, fw = nfe == 2 ? 0.25 : 0.5 / nfe;
    if (nfe == 2) {
      const uint32_t ca = a_.ec[k0], cb = a_.ec[k0 + 1];
      const uint32_t fa = a_.face_of(ca), fb = a_.face_of(cb);
      // Refined levels are all quads: no face sizes to read.
      const bool ta = !a_.quads && l_.face_size(fa) == 3, tb = !a_.quads && l_.face_size(fb) == 3;
      if (o_.smooth_triangles && (ta || tb)) {
        const double w0 = ta ? 0.470 : 0.25, w1 = tb ? 0.470 : 0.25;
        fw = 0.5 * (double(float(w0)) + double(float(w1)));
        vw = 0.5 * (1.0 - 2.0 * fw);
      } else if (blend == 0.0 && (a_.quads || (l_.face_size(fa) == 4 && l_.face_size(fb) == 4))) {
        // Two quads: 3/8 on the ends, 1/16 on the far vertices of each face.
        acc_.add(a, 0.375), acc_.add(b, 0.375);
        for (uint32_t c : {ca, cb}) {
          const uint32_t n2 = l_.opposite_in_quad(c);
          acc_.add(P_.face_vertices[n2], 0.0625);
          acc_.add(P_.face_vertices[l_.prev(c)], 0.0625);
        }
        return;
      }
    }
    acc_.add(a, blend * 0.5 + (1.0 - blend) * vw);
    acc_.add(b, blend * 0.5 + (1.0 - blend) * vw);
    for (uint32_t i = 0; i < nfe; ++i)
      face_point(a_.face_of(a_.ec[k0 + i]), fw * (1.0 - blend), acc_);
  }

  float child_half_sharpness(uint32_t e, uint32_t v) {
    return half_sharpness_at(o_, P_, a_, e, v, pe_, ce_);
  }

  void edge_point(uint32_t e) {
    const uint32_t a = P_.edge_vertices[2 * size_t(e)], b = P_.edge_vertices[2 * size_t(e) + 1];
    const float s = P_.edge_sharpness[e];
    if (!sharp(s)) return smooth_edge(e, a, b, 0.0);
    // The child rule of the edge point: its two halves' decayed sharpness.
    const int sharp_halves =
        int(sharp(child_half_sharpness(e, a))) + int(sharp(child_half_sharpness(e, b)));
    if (vertex_rule(0.0f, sharp_halves) == kCrease) {
      acc_.add(a, 0.5), acc_.add(b, 0.5);
    } else {
      smooth_edge(e, a, b, double(s));
    }
  }

  void smooth_vertex(uint32_t v, Terms& m) const {
    const uint32_t k0 = a_.veo[v], n = a_.veo[v + 1] - k0;
    const uint32_t s0 = a_.vco[v], nfaces = a_.vco[v + 1] - s0;
    if (nfaces != n)
      throw InputError(fmt::format(
          "vertex {} needs the smooth rule but is on a boundary or non-manifold (internal "
          "tagging error)",
          v));
    const double dn = n, w = 1.0 / (dn * dn);
    bool quads = a_.quads;
    if (!quads) {
      quads = true;
      for (uint32_t i = 0; i < nfaces && quads; ++i)
        quads = l_.face_size(a_.face_of(a_.vc[s0 + i])) == 4;
    }
    if (quads) {
      // Every face a quad: v, the edge neighbours and the face diagonals, merged in closed form.
      m.add(v, (dn - 2.0) / dn + 0.25 / dn);
      for (uint32_t k = 0; k < n; ++k) m.add(l_.other_end(a_.ve[k0 + k], v), 1.5 * w);
      for (uint32_t i = 0; i < nfaces; ++i)
        m.add(P_.face_vertices[l_.opposite_in_quad(a_.vc[s0 + i])], 0.25 * w);
      return;
    }
    m.add(v, (dn - 2.0) / dn);
    for (uint32_t k = 0; k < n; ++k) m.add(l_.other_end(a_.ve[k0 + k], v), w);
    for (uint32_t i = 0; i < nfaces; ++i) face_point(a_.face_of(a_.vc[s0 + i]), w, m);
  }

  void sharp_vertex(uint32_t v, Rule r, const float* es, Terms& m) const {
    if (r != kCrease) {
      m.add(v, 1.0);
      return;
    }
    const uint32_t k0 = a_.veo[v], n = a_.veo[v + 1] - k0;
    m.add(v, 0.75);
    for (uint32_t k = 0; k < n; ++k)
      if (sharp(es[k])) m.add(l_.other_end(a_.ve[k0 + k], v), 0.125);
  }

  void vertex_point(uint32_t v) {
    const uint32_t k0 = a_.veo[v], n = a_.veo[v + 1] - k0;
    if (n == 0) {  // on no face: stays where it is (its ring is empty)
      acc_.add(v, 1.0);
      return;
    }
    const float pv = P_.vertex_sharpness[v];
    int sharp_edges = 0;
    for (uint32_t k = 0; k < n; ++k) sharp_edges += sharp(P_.edge_sharpness[a_.ve[k0 + k]]);
    const Rule prule = vertex_rule(pv, sharp_edges);
    if (prule == kSmooth || prule == kDart) return smooth_vertex(v, acc_);
    const float cv = decrement(pv);
    pe_.resize(n), ce_.resize(n);
    for (uint32_t k = 0; k < n; ++k) pe_[k] = P_.edge_sharpness[a_.ve[k0 + k]];
    sharp_vertex(v, prule, pe_.data(), acc_);
    child_edge_sharpness(o_, pe_.data(), int(n), ce_.data());
    int child_sharp = 0;
    for (uint32_t k = 0; k < n; ++k) child_sharp += sharp(ce_[k]);
    const Rule crule = vertex_rule(cv, child_sharp);
    if (crule == prule) return;
    cmask_.clear();
    if (crule == kSmooth || crule == kDart) {
      smooth_vertex(v, cmask_);
    } else {
      sharp_vertex(v, crule, ce_.data(), cmask_);
    }
    const double pw = fractional_weight(o_, pv, cv, pe_.data(), ce_.data(), int(n));
    acc_.scale(pw);
    acc_.append(cmask_, 1.0 - pw);
  }

  const SubdivOptions& o_;
  const RefinedLevel& P_;
  const Adj& a_;
  LevelRef l_;
  const Selection& sel_;
  Terms acc_, cmask_;
  std::vector<float> pe_, ce_;
};

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
    Rules rules(o, P, a, sel);
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
                            const Selection& sel, const uint8_t* keep = nullptr) {
  const size_t n = sel.points();
  StencilTable out;
  // Writes the computed row's k indices to `indices` and its weights to `pool` (through
  // `shared`, `row` holding them first); returns where they start in the pool.
  auto write_row = [](const Rules& rules, size_t k, uint32_t* indices, std::vector<float>& row,
                      detail::SharedWeights& shared, std::vector<float>& pool) {
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
    Rules rules(o, P, a, sel);
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
    Rules rules(o, P, a, sel);
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
    Rules rules(o, P, a, sel);
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

// The cage as level 0, with its adjacency and tags.
Adj cage_level(const Mesh& cage, const SubdivOptions& o, RefinedLevel& L0) {
  validate(cage, "cage");
  L0.face_offsets = cage.face_offsets;
  L0.face_vertices = cage.face_vertices;
  Adj a = build_adj(L0, cage.vertex_count());
  init_cage_level(cage, o, a, L0);
  return a;
}

}  // namespace

namespace {

#if LIMN_X86_SIMD
// Three channels in one 4-wide double vector: one fused multiply-add per stencil entry, and
// the sum stays in double (a valence-360 vertex sums ~1000 terms). Chosen at run time, so the
// library still runs on x86-64 processors without AVX2.
// One point's three floats as four doubles (lane 3 zero), without reading past the point.
__attribute__((target("avx2,fma"), always_inline)) inline __m256d load3_avx2(const float* s) {
  double xy;
  std::memcpy(&xy, s, sizeof xy);
  return _mm256_cvtps_pd(_mm_insert_ps(_mm_castpd_ps(_mm_set_sd(xy)), _mm_load_ss(s + 2), 0x20));
}

__attribute__((target("avx2,fma"))) void apply3_avx2(const StencilTable& t, size_t b, size_t e,
                                                     const float* in, float* out) {
  const uint32_t* off = t.offsets.data();
  for (size_t i = b; i < e; ++i) {
    const uint32_t* idx = t.indices.data() + off[i];
    const float* w = t.row_weights(i);
    const uint32_t n = off[i + 1] - off[i];
    // Two accumulators halve the chain of dependent additions per stencil.
    __m256d a0 = _mm256_setzero_pd(), a1 = _mm256_setzero_pd();
    uint32_t j = 0;
    for (; j + 1 < n; j += 2) {
      a0 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j])), load3_avx2(in + 3 * size_t(idx[j])), a0);
      a1 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j + 1])),
                           load3_avx2(in + 3 * size_t(idx[j + 1])), a1);
    }
    if (j < n)
      a0 = _mm256_fmadd_pd(_mm256_set1_pd(double(w[j])), load3_avx2(in + 3 * size_t(idx[j])), a0);
    const __m256d acc = _mm256_add_pd(a0, a1);
    const __m128 r = _mm256_cvtpd_ps(acc);
    float* o = out + 3 * i;
    const double xy = _mm_cvtsd_f64(_mm_castps_pd(r));  // x and y, stored without alignment
    std::memcpy(o, &xy, sizeof xy);
    o[2] = _mm_cvtss_f32(_mm_movehl_ps(r, r));
  }
}
#endif

// Applies stencils [b, e) serially; out gets table.size() points.
void apply_serial(const StencilTable& table, size_t b, size_t e, const float* in, float* out,
                  int channels) {
  const uint32_t* off = table.offsets.data();
  const size_t ch = size_t(channels);
  // Sums in double: a valence-360 vertex sums ~1000 terms, and float accumulation alone would
  // cost ~1e-6 of the model's size per level.
  if (channels == 3) {
#if LIMN_X86_SIMD
    if (cpu::features().avx2_fma) return apply3_avx2(table, b, e, in, out);
#endif
    for (size_t i = b; i < e; ++i) {
      const uint32_t* idx = table.indices.data() + off[i];
      const float* w = table.row_weights(i);
      double x = 0, y = 0, z = 0;
      for (uint32_t j = 0; j < off[i + 1] - off[i]; ++j) {
        const float* s = in + 3 * size_t(idx[j]);
        const double wj = w[j];
        x += wj * s[0], y += wj * s[1], z += wj * s[2];
      }
      float* o = out + 3 * i;
      o[0] = float(x), o[1] = float(y), o[2] = float(z);
    }
    return;
  }
  double acc[kMaxChannels];
  for (size_t i = b; i < e; ++i) {
    const uint32_t* idx = table.indices.data() + off[i];
    const float* w = table.row_weights(i);
    for (size_t k = 0; k < ch; ++k) acc[k] = 0.0;
    for (uint32_t j = 0; j < off[i + 1] - off[i]; ++j) {
      const float* s = in + size_t(idx[j]) * ch;
      const double wj = w[j];
      for (size_t k = 0; k < ch; ++k) acc[k] += wj * s[k];
    }
    float* o = out + i * ch;
    for (size_t k = 0; k < ch; ++k) o[k] = static_cast<float>(acc[k]);
  }
}

}  // namespace

void apply_stencils(const StencilTable& table, const float* in, float* out, int channels) {
  if (channels < 1 || channels > kMaxChannels)
    throw std::invalid_argument(
        fmt::format("apply_stencils: {} channels (1-{})", channels, kMaxChannels));
  parallel_range(table.size(), 4096,
                 [&](size_t b, size_t e) { apply_serial(table, b, e, in, out, channels); });
}

SubdivOptions subdiv_options(const Mesh& mesh) {
  SubdivOptions o;
  if (mesh.tags.boundary != BoundaryInterpolation::unset) o.boundary = mesh.tags.boundary;
  if (mesh.tags.crease_method != CreaseMethod::unset) o.crease_method = mesh.tags.crease_method;
  o.smooth_triangles = mesh.tags.smooth_triangles;
  return o;
}

StencilTable compose_stencils(const StencilTable& outer, const StencilTable& inner) {
  const size_t n = outer.size();
  // Dense scratch over the source points, cleared through the touched list: merging without
  // sorting the terms keeps composition linear in the entries. One scratch per thread; two
  // passes (sizes, then entries in place) so the table is never held twice.
  size_t sources = 0;
  for (uint32_t i : inner.indices) sources = std::max(sources, size_t(i) + 1);
  struct Scratch {
    std::vector<double> acc;
    std::vector<uint8_t> seen;
    std::vector<uint32_t> touched;
  };
  tbb::enumerable_thread_specific<Scratch> scratch([&] {
    Scratch s;
    s.acc.assign(sources, 0.0);
    s.seen.assign(sources, 0);
    return s;
  });
  // Merges point p's terms into s.touched (sorted, exact cancellations dropped).
  auto merge = [&](Scratch& s, size_t p) {
    s.touched.clear();
    const float* ow = outer.row_weights(p);
    for (uint32_t j = outer.offsets[p]; j < outer.offsets[p + 1]; ++j) {
      const uint32_t q = outer.indices[j];
      const double w = ow[j - outer.offsets[p]];
      const float* iw = inner.row_weights(q);
      for (uint32_t k = inner.offsets[q]; k < inner.offsets[q + 1]; ++k) {
        const uint32_t src = inner.indices[k];
        if (!s.seen[src]) s.seen[src] = 1, s.touched.push_back(src);
        s.acc[src] += w * double(iw[k - inner.offsets[q]]);
      }
    }
    std::sort(s.touched.begin(), s.touched.end());
    size_t kept = 0;
    for (uint32_t src : s.touched) {
      s.seen[src] = 0;
      if (s.acc[src] != 0.0)
        s.touched[kept++] = src;  // exact cancellation: nothing to read
      else
        s.acc[src] = 0.0;
    }
    s.touched.resize(kept);
  };
  StencilTable out;
  // Up to a million points: one pass into per-chunk parts, then one copy.
  if (n < (size_t(1) << 20)) {
    const size_t chunk = 2048, chunks = (n + chunk - 1) / chunk;
    std::vector<StencilTable> parts(chunks);
    parallel_range(chunks, 1, [&](size_t cb, size_t ce) {
      Scratch& s = scratch.local();
      for (size_t c = cb; c < ce; ++c) {
        StencilTable& t = parts[c];
        for (size_t p = c * chunk; p < std::min(n, (c + 1) * chunk); ++p) {
          merge(s, p);
          for (uint32_t src : s.touched) {
            t.indices.push_back(src);
            t.weights.push_back(static_cast<float>(s.acc[src]));
            s.acc[src] = 0.0;
          }
          t.offsets.push_back(uint32_t(t.indices.size()));
        }
      }
    });
    out.offsets.reserve(n + 1);
    for (const StencilTable& t : parts) {
      const size_t base = out.indices.size();
      if (base + t.indices.size() > UINT32_MAX)
        throw InputError("composed stencils need more than 2^32 entries");
      for (size_t i = 1; i < t.offsets.size(); ++i)
        out.offsets.push_back(uint32_t(base + t.offsets[i]));
      out.indices.insert(out.indices.end(), t.indices.begin(), t.indices.end());
      out.weights.insert(out.weights.end(), t.weights.begin(), t.weights.end());
    }
    return out;
  }
  refill(out.offsets, n + 1, 0u);
  std::vector<uint32_t> sizes;
  refill(sizes, n, 0u);
  parallel_range(n, 4096, [&](size_t b, size_t e) {
    Scratch& s = scratch.local();
    for (size_t p = b; p < e; ++p) {
      merge(s, p);
      sizes[p] = uint32_t(s.touched.size());
      for (uint32_t src : s.touched) s.acc[src] = 0.0;
    }
  });
  size_t total = 0;
  for (size_t p = 0; p < n; ++p) {
    total += sizes[p];
    if (total > UINT32_MAX) throw InputError("composed stencils need more than 2^32 entries");
    out.offsets[p + 1] = uint32_t(total);
  }
  std::vector<uint32_t>().swap(sizes);
  refill(out.indices, total, 0u);
  refill(out.weights, total, 0.0f);
  parallel_range(n, 4096, [&](size_t b, size_t e) {
    Scratch& s = scratch.local();
    for (size_t p = b; p < e; ++p) {
      merge(s, p);
      uint32_t* ix = out.indices.data() + out.offsets[p];
      float* wt = out.weights.data() + out.offsets[p];
      for (size_t i = 0; i < s.touched.size(); ++i) {
        const uint32_t src = s.touched[i];
        ix[i] = src, wt[i] = static_cast<float>(s.acc[src]);
        s.acc[src] = 0.0;
      }
    }
  });
  return out;
}

namespace {

StencilTable compose_chain(const std::vector<StencilTable>& tables, int level) {
  if (level < 1 || level > int(tables.size()))
    throw InputError(fmt::format("cage_stencils: level {} not refined", level));
  StencilTable flat = tables[0];
  for (int k = 1; k < level; ++k) flat = compose_stencils(tables[size_t(k)], flat);
  return flat;
}

}  // namespace

StencilTable cage_stencils(const UniformRefinement& r, int level) {
  return compose_chain(r.stencils, level);
}

StencilTable cage_stencils(const SparseRefinement& r, int level) {
  return compose_chain(r.stencils, level);
}

namespace {

// The cage's positions pushed through the first `level` tables of a chain.
std::vector<float> apply_chain(const std::vector<StencilTable>& tables, const Mesh& cage,
                               int level) {
  std::vector<float> cur = cage.positions, next;
  for (int k = 0; k < level; ++k) {
    refill(next, 3 * tables[size_t(k)].size(), 0.0f);
    apply_stencils(tables[size_t(k)], cur.data(), next.data(), 3);
    cur.swap(next);
  }
  return cur;
}

}  // namespace

std::vector<float> UniformRefinement::positions(const Mesh& cage, int level) const {
  return apply_chain(stencils, cage, level);
}

UniformRefinement refine_uniform(const Mesh& cage, int depth, const SubdivOptions& options) {
  if (depth < 0 || depth > 8)
    throw InputError(fmt::format("refinement depth {} out of range (0-8)", depth));
  UniformRefinement r;
  r.options = options;
  r.levels.resize(size_t(depth) + 1);
  r.stencils.resize(size_t(depth));
  Adj a = cage_level(cage, options, r.levels[0]);
  for (size_t k = 0; k < size_t(depth); ++k) {
    const RefinedLevel& P = r.levels[k];
    RefinedLevel& C = r.levels[k + 1];
    const Selection all = Selection::everything(P);
    r.stencils[k] = build_stencils(options, P, a, all);
    Adj ca;
    const bool last = k + 1 == size_t(depth);
    derive_child(P, a, C, true, last ? nullptr : &ca);
    child_vertex_sharpness(P, all, C);
    derived_edge_sharpness(options, P, a, C);
    a = std::move(ca);
  }
  return r;
}

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
  if (depth == 0) {
    out.positions = cage.positions;
    for (size_t f = 0; f < cage.face_count(); ++f)
      if (!P.face_hole[f]) out.add_face(cage.face(f));
    out.crease_edges = cage.crease_edges, out.crease_sharpness = cage.crease_sharpness;
    out.corner_vertices = cage.corner_vertices, out.corner_sharpness = cage.corner_sharpness;
    if (stats) *stats = std::move(st);
    return out;
  }
  std::vector<float> pos = cage.positions, next;
  std::vector<float> pe, ce;
  for (int k = 0; k < depth; ++k) {
    const Selection all = Selection::everything(P);
    t0 = clock::now();
    // Stencils are built chunk by chunk, applied at once and dropped: never stored whole.
    refill(next, 3 * all.points(), 0.0f);
    std::vector<size_t> entries((all.points() + kStencilChunk - 1) / kStencilChunk, 0);
    for_stencil_chunks(options, P, pa, all, [&](size_t b, StencilTable& t) {
      apply_serial(t, 0, t.size(), pos.data(), next.data() + 3 * b, 3);
      entries[b / kStencilChunk] = t.indices.size();
    });
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
    const bool holes = std::find(C.face_hole.begin(), C.face_hole.end(), 1) != C.face_hole.end();
    if (holes) {
      size_t w = 0;
      for (size_t f = 0; f < C.face_hole.size(); ++f) {
        if (C.face_hole[f]) continue;
        std::copy_n(C.face_vertices.begin() + std::ptrdiff_t(4 * f), 4,
                    C.face_vertices.begin() + std::ptrdiff_t(4 * w));
        ++w;
      }
      C.face_vertices.resize(4 * w);
      C.face_offsets.resize(w + 1);
    }
    {
      RefinedLevel drop = std::move(P);
      Adj drop_adj = std::move(pa);
    }
    out.face_offsets = std::move(C.face_offsets);
    out.face_vertices = std::move(C.face_vertices);
    out.positions = std::move(pos);
    st.output_ms += ms_since(t0);
  }
  if (stats) *stats = std::move(st);
  return out;
}

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
                   nv = static_cast<uint32_t>(PL.vertex_count()),
                   ne = static_cast<uint32_t>(PL.edge_count());
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

    SparseLevel C;
    if (keep_levels) r.stencils.push_back(build_stencils(options, PL, t, sel));
    selected_child_faces(PL, t, sel, C.level);
    child_vertex_sharpness(PL, sel, C.level);
    // Provenance, completeness and the depths left (before the child adjacency: level k's
    // tags and depths can go first, the moment both levels are held).
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
