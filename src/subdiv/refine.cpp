// Uniform Catmull-Clark refinement with OpenSubdiv's Sdc rules, as per-level stencil tables.
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
#include "limn/subdiv/refine.hpp"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <span>
#include <stdexcept>

#include "limn/mesh/topology.hpp"

namespace limn {

namespace {

constexpr float kInf = kInfiniteSharpness;
constexpr int kMaxChannels = 16;

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

// A stencil under construction: weighted parent vertices, merged when finished.
struct Accum {
  std::vector<std::pair<uint32_t, double>> terms;
  void add(uint32_t v, double w) { terms.emplace_back(v, w); }
  void scale(double s) {
    for (auto& t : terms) t.second *= s;
  }
  void append(const Accum& other, double s) {
    for (const auto& t : other.terms) terms.emplace_back(t.first, t.second * s);
  }
  void clear() { terms.clear(); }
  void emit(StencilTable& table) {
    std::sort(terms.begin(), terms.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 0; i < terms.size();) {
      double w = 0.0;
      const uint32_t v = terms[i].first;
      for (; i < terms.size() && terms[i].first == v; ++i) w += terms[i].second;
      table.indices.push_back(v);
      table.weights.push_back(static_cast<float>(w));
    }
    table.offsets.push_back(static_cast<uint32_t>(table.indices.size()));
  }
};

// Adjacency of one level, as CSR arrays derived from its corner table.
struct Adjacency {
  Topology topo;
  std::vector<uint32_t> edge_face_offsets, edge_faces;      // faces on each edge
  std::vector<uint32_t> vertex_edge_offsets, vertex_edges;  // edges at each vertex
  std::vector<uint8_t> edge_non_manifold;

  Adjacency(size_t nv, const RefinedLevel& L)
      : topo(build_topology(nv, L.face_offsets, L.face_vertices)) {
    const size_t ne = topo.edge_count(), nc = L.face_vertices.size();
    edge_face_offsets.assign(ne + 1, 0);
    for (size_t c = 0; c < nc; ++c) ++edge_face_offsets[topo.corner_edge[c] + 1];
    for (size_t e = 0; e < ne; ++e) edge_face_offsets[e + 1] += edge_face_offsets[e];
    edge_faces.resize(nc);
    std::vector<uint32_t> fill(edge_face_offsets.begin(), edge_face_offsets.end() - 1);
    for (size_t c = 0; c < nc; ++c) edge_faces[fill[topo.corner_edge[c]]++] = topo.corner_face[c];

    vertex_edge_offsets.assign(nv + 1, 0);
    for (size_t e = 0; e < ne; ++e) {
      ++vertex_edge_offsets[topo.edge_vertices[2 * e] + 1];
      ++vertex_edge_offsets[topo.edge_vertices[2 * e + 1] + 1];
    }
    for (size_t v = 0; v < nv; ++v) vertex_edge_offsets[v + 1] += vertex_edge_offsets[v];
    vertex_edges.resize(2 * ne);
    fill.assign(vertex_edge_offsets.begin(), vertex_edge_offsets.end() - 1);
    for (size_t e = 0; e < ne; ++e) {
      vertex_edges[fill[topo.edge_vertices[2 * e]]++] = static_cast<uint32_t>(e);
      vertex_edges[fill[topo.edge_vertices[2 * e + 1]]++] = static_cast<uint32_t>(e);
    }
    // More than two faces, or two faces that disagree on orientation: OpenSubdiv cannot order
    // faces around such an edge and treats it as non-manifold (infinitely sharp).
    edge_non_manifold.assign(ne, 0);
    for (size_t c = 0; c < nc; ++c) {
      const uint32_t t = topo.corner_twin[c], e = topo.corner_edge[c];
      if (t == kNonManifold || (t != kNone && L.face_vertices[t] == L.face_vertices[c]))
        edge_non_manifold[e] = 1;
    }
  }
  uint32_t other_end(uint32_t e, uint32_t v) const {
    const uint32_t a = topo.edge_vertices[2 * size_t(e)];
    return a == v ? topo.edge_vertices[2 * size_t(e) + 1] : a;
  }
};

// Level 0 sharpness: tags, then boundary, non-manifold and corner sharpening.
void init_cage_level(const Mesh& cage, const SubdivOptions& o, const Adjacency& adj,
                     RefinedLevel& L) {
  const Topology& t = adj.topo;
  const size_t nv = cage.vertex_count(), ne = t.edge_count();
  L.edge_vertices = t.edge_vertices;
  L.edge_sharpness.assign(ne, 0.0f);
  for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
    const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
    uint32_t found = kNone;
    for (uint32_t k = adj.vertex_edge_offsets[a]; k < adj.vertex_edge_offsets[a + 1]; ++k)
      if (adj.other_end(adj.vertex_edges[k], a) == b) found = adj.vertex_edges[k];
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
    for (uint32_t k = adj.vertex_edge_offsets[v]; k < adj.vertex_edge_offsets[v + 1]; ++k) {
      nm_edges += adj.edge_non_manifold[adj.vertex_edges[k]];
      boundary += t.edge_faces[adj.vertex_edges[k]] == 1;
    }
  };
  std::vector<uint8_t> vertex_nm(nv, 0);
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t nedges = adj.vertex_edge_offsets[v + 1] - adj.vertex_edge_offsets[v];
    const uint32_t nfaces = t.vertex_face_count(v);
    int nm_edges = 0, boundary = 0;
    count_edges(v, nm_edges, boundary);
    vertex_nm[v] = nm_edges > 0 || (nfaces != nedges && (nfaces + 1 != nedges || boundary != 2));
  }
  // Boundary interpolation "none": faces at a boundary vertex whose boundary edges are not all
  // explicitly infinitely sharp are excluded, as holes (tested before boundaries are sharpened).
  if (o.boundary == BoundaryInterpolation::none) {
    for (uint32_t v = 0; v < nv; ++v) {
      const uint32_t k0 = adj.vertex_edge_offsets[v], nedges = adj.vertex_edge_offsets[v + 1] - k0;
      if (nedges == t.vertex_face_count(v) && !vertex_nm[v]) continue;
      bool exclude = false;
      for (uint32_t k = k0; k < k0 + nedges && !exclude; ++k) {
        const uint32_t e = adj.vertex_edges[k];
        exclude = t.edge_faces[e] == 1 && L.edge_sharpness[e] < kInf;
      }
      if (exclude)
        for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i)
          L.face_hole[t.corner_face[t.vertex_corners[i]]] = 1;
    }
  }
  for (size_t e = 0; e < ne; ++e)
    if (t.edge_faces[e] == 1 || adj.edge_non_manifold[e]) L.edge_sharpness[e] = kInf;

  L.vertex_sharpness.assign(nv, 0.0f);
  for (size_t i = 0; i < cage.corner_vertices.size(); ++i)
    L.vertex_sharpness[cage.corner_vertices[i]] = std::min(cage.corner_sharpness[i], kInf);
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t nedges = adj.vertex_edge_offsets[v + 1] - adj.vertex_edge_offsets[v];
    const uint32_t nfaces = t.vertex_face_count(v);
    int nm_edges = 0, boundary = 0;
    count_edges(v, nm_edges, boundary);
    if (nfaces == 1 && nedges == 2) {
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
  uint32_t face(uint32_t i) const { return all ? i : faces[i]; }
  uint32_t edge(uint32_t i) const { return all ? i : edges[i]; }
  uint32_t vertex(uint32_t i) const { return all ? i : vertices[i]; }
  uint32_t eslot(uint32_t e) const { return all ? e : edge_slot[e]; }
  uint32_t vslot(uint32_t v) const { return all ? v : vertex_slot[v]; }
  static Selection everything(const RefinedLevel& P) {
    Selection s;
    s.nf = static_cast<uint32_t>(P.face_count());
    s.ne = static_cast<uint32_t>(P.edge_count());
    s.nv = static_cast<uint32_t>(P.vertex_count());
    return s;
  }
};

// Builds level k+1 and the stencils from level k.
void refine_level(const SubdivOptions& o, const RefinedLevel& P, const Adjacency& adj,
                  const Selection& sel, RefinedLevel& C, StencilTable& S) {
  const Topology& t = adj.topo;
  const uint32_t F = sel.nf, E = sel.ne, NV = sel.nv;
  auto face_verts = [&](uint32_t f) {
    return std::span<const uint32_t>(P.face_vertices.data() + P.face_offsets[f],
                                     P.face_offsets[f + 1] - P.face_offsets[f]);
  };
  auto face_point = [&](uint32_t f, double w, Accum& acc) {
    const auto fv = face_verts(f);
    const double wi = w / static_cast<double>(fv.size());
    for (uint32_t v : fv) acc.add(v, wi);
  };

  S = StencilTable{};
  S.offsets.reserve(size_t(F) + E + NV + 1);
  Accum acc, cmask;

  // Face points: centroids.
  for (uint32_t i = 0; i < F; ++i) {
    acc.clear();
    face_point(sel.face(i), 1.0, acc);
    acc.emit(S);
  }

  // Edge points.
  for (uint32_t ei = 0; ei < E; ++ei) {
    const uint32_t e = sel.edge(ei);
    acc.clear();
    const uint32_t a = t.edge_vertices[2 * size_t(e)], b = t.edge_vertices[2 * size_t(e) + 1];
    const float s = P.edge_sharpness[e];
    const uint32_t f0 = adj.edge_face_offsets[e], nfe = adj.edge_face_offsets[e + 1] - f0;
    auto smooth = [&](double blend) {  // blend: weight of the sharp (midpoint) mask
      double vw = 0.25, fw = nfe == 2 ? 0.25 : 0.5 / nfe;
      std::vector<double> fws(nfe, fw);
      if (o.smooth_triangles && nfe == 2) {
        const uint32_t fa = adj.edge_faces[f0], fb = adj.edge_faces[f0 + 1];
        const bool ta = face_verts(fa).size() == 3, tb = face_verts(fb).size() == 3;
        if (ta || tb) {
          const double w0 = ta ? 0.470 : 0.25, w1 = tb ? 0.470 : 0.25;
          fw = 0.5 * (static_cast<double>(static_cast<float>(w0)) +
                      static_cast<double>(static_cast<float>(w1)));
          vw = 0.5 * (1.0 - 2.0 * fw);
          fws.assign(2, fw);
        }
      }
      acc.add(a, blend * 0.5 + (1.0 - blend) * vw);
      acc.add(b, blend * 0.5 + (1.0 - blend) * vw);
      for (uint32_t i = 0; i < nfe; ++i)
        face_point(adj.edge_faces[f0 + i], fws[i] * (1.0 - blend), acc);
    };
    if (!sharp(s)) {
      smooth(0.0);
    } else {
      // The child rule of the edge point: its two half-edges' decayed sharpness.
      float cs[2];
      for (int end = 0; end < 2; ++end) {
        const uint32_t v = end == 0 ? a : b;
        if (o.crease_method != CreaseMethod::chaikin) {
          cs[end] = decrement(s);
        } else {
          float buf_p[64], buf_c[64];
          std::vector<float> hp, hc;
          const uint32_t k0 = adj.vertex_edge_offsets[v], n = adj.vertex_edge_offsets[v + 1] - k0;
          float* pe = n <= 64 ? buf_p : (hp.resize(n), hp.data());
          float* ce = n <= 64 ? buf_c : (hc.resize(n), hc.data());
          uint32_t self = 0;
          for (uint32_t k = 0; k < n; ++k) {
            pe[k] = P.edge_sharpness[adj.vertex_edges[k0 + k]];
            if (adj.vertex_edges[k0 + k] == e) self = k;
          }
          child_edge_sharpness(o, pe, int(n), ce);
          cs[end] = ce[self];
        }
      }
      const Rule child = vertex_rule(0.0f, int(sharp(cs[0])) + int(sharp(cs[1])));
      if (child == kCrease) {
        acc.add(a, 0.5);
        acc.add(b, 0.5);
      } else {
        smooth(static_cast<double>(s));
      }
    }
    acc.emit(S);
  }

  // Vertex points.
  std::vector<float> pe, ce;
  C.vertex_sharpness.assign(size_t(F) + E + NV, 0.0f);
  for (uint32_t vi = 0; vi < NV; ++vi) {
    const uint32_t v = sel.vertex(vi);
    acc.clear();
    const uint32_t k0 = adj.vertex_edge_offsets[v], n = adj.vertex_edge_offsets[v + 1] - k0;
    const uint32_t s0 = t.vertex_offsets[v], nfaces = t.vertex_offsets[v + 1] - s0;
    pe.resize(n), ce.resize(n);
    int sharp_edges = 0;
    for (uint32_t k = 0; k < n; ++k) {
      pe[k] = P.edge_sharpness[adj.vertex_edges[k0 + k]];
      sharp_edges += sharp(pe[k]);
    }
    const float pv = P.vertex_sharpness[v], cv = decrement(pv);
    C.vertex_sharpness[F + E + vi] = cv;
    const Rule prule = vertex_rule(pv, sharp_edges);

    auto smooth_mask = [&](Accum& m) {
      const double dn = n;
      m.add(v, (dn - 2.0) / dn);
      const double w = 1.0 / (dn * dn);
      for (uint32_t k = 0; k < n; ++k) m.add(adj.other_end(adj.vertex_edges[k0 + k], v), w);
      for (uint32_t i = 0; i < nfaces; ++i)
        face_point(t.corner_face[t.vertex_corners[s0 + i]], w, m);
    };
    auto sharp_mask = [&](Rule r, const float* es, Accum& m) {
      if (r == kCrease) {
        m.add(v, 0.75);
        // The first and last sharp edges in the vertex's edge order (only two are sharp).
        int first = -1, last = -1;
        for (uint32_t k = 0; k < n; ++k)
          if (sharp(es[k])) last = int(k), first = first < 0 ? int(k) : first;
        m.add(adj.other_end(adj.vertex_edges[k0 + uint32_t(first)], v), 0.125);
        m.add(adj.other_end(adj.vertex_edges[k0 + uint32_t(last)], v), 0.125);
      } else {
        m.add(v, 1.0);
      }
    };
    auto check_smooth = [&] {
      if (nfaces != n)
        throw InputError(
            fmt::format("vertex {} needs the smooth rule but is on a boundary or "
                        "non-manifold (internal tagging error)",
                        v));
    };

    if (prule == kSmooth || prule == kDart) {
      check_smooth();
      smooth_mask(acc);
    } else {
      sharp_mask(prule, pe.data(), acc);
      child_edge_sharpness(o, pe.data(), int(n), ce.data());
      int child_sharp = 0;
      for (uint32_t k = 0; k < n; ++k) child_sharp += sharp(ce[k]);
      const Rule crule = vertex_rule(cv, child_sharp);
      if (crule != prule) {
        cmask.clear();
        if (crule == kSmooth || crule == kDart) {
          check_smooth();
          smooth_mask(cmask);
        } else {
          sharp_mask(crule, ce.data(), cmask);
        }
        const double pw = fractional_weight(o, pv, cv, pe.data(), ce.data(), int(n));
        acc.scale(pw);
        acc.append(cmask, 1.0 - pw);
      }
    }
    acc.emit(S);
  }

  // Child topology: each parent face of n corners becomes n quads (vertex point, edge point of
  // the outgoing edge, face point, edge point of the incoming edge), keeping orientation.
  C.face_offsets.assign(1, 0);
  C.face_vertices.clear();
  C.face_hole.clear();
  for (uint32_t fi = 0; fi < F; ++fi) {
    const uint32_t f = sel.face(fi);
    const uint32_t o0 = P.face_offsets[f], n = P.face_offsets[f + 1] - o0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = o0 + i;
      C.face_vertices.insert(
          C.face_vertices.end(),
          {F + E + sel.vslot(P.face_vertices[c]), F + sel.eslot(t.corner_edge[c]), fi,
           F + sel.eslot(t.corner_edge[t.corner_prev[c]])});
      C.face_offsets.push_back(static_cast<uint32_t>(C.face_vertices.size()));
      C.face_hole.push_back(P.face_hole[f]);
    }
  }
}

// Child edge sharpness, once the child's edges are known: only the halves of parent edges
// (edge point - vertex point) can be sharp.
void child_edges(const SubdivOptions& o, const RefinedLevel& P, const Adjacency& padj,
                 const Selection& sel, const Adjacency& cadj, RefinedLevel& C) {
  const uint32_t F = sel.nf, E = sel.ne;
  const size_t ne = cadj.topo.edge_count();
  C.edge_vertices = cadj.topo.edge_vertices;
  C.edge_sharpness.assign(ne, 0.0f);
  std::vector<float> pe, ce;
  for (size_t e = 0; e < ne; ++e) {
    const uint32_t a = C.edge_vertices[2 * e], b = C.edge_vertices[2 * e + 1];  // a < b
    if (a < F + E && a >= F && b >= F + E) {
      const uint32_t pedge = sel.edge(a - F), pvert = sel.vertex(b - F - E);
      const float s = P.edge_sharpness[pedge];
      if (!sharp(s)) continue;
      if (o.crease_method != CreaseMethod::chaikin) {
        C.edge_sharpness[e] = decrement(s);
        continue;
      }
      const uint32_t k0 = padj.vertex_edge_offsets[pvert],
                     n = padj.vertex_edge_offsets[pvert + 1] - k0;
      pe.resize(n), ce.resize(n);
      uint32_t self = 0;
      for (uint32_t k = 0; k < n; ++k) {
        pe[k] = P.edge_sharpness[padj.vertex_edges[k0 + k]];
        if (padj.vertex_edges[k0 + k] == pedge) self = k;
      }
      child_edge_sharpness(o, pe.data(), int(n), ce.data());
      C.edge_sharpness[e] = ce[self];
    }
  }
}

}  // namespace

SubdivOptions subdiv_options(const Mesh& mesh) {
  SubdivOptions o;
  if (mesh.tags.boundary != BoundaryInterpolation::unset) o.boundary = mesh.tags.boundary;
  if (mesh.tags.crease_method != CreaseMethod::unset) o.crease_method = mesh.tags.crease_method;
  o.smooth_triangles = mesh.tags.smooth_triangles;
  return o;
}

void apply_stencils(const StencilTable& table, const float* in, float* out, int channels) {
  if (channels < 1 || channels > kMaxChannels)
    throw std::invalid_argument(
        fmt::format("apply_stencils: {} channels (1-{})", channels, kMaxChannels));
  const size_t n = table.size();
  const uint32_t* off = table.offsets.data();
  const uint32_t* idx = table.indices.data();
  const float* w = table.weights.data();
  auto body = [&](size_t b, size_t e) {
    // Sums in double: a valence-360 vertex sums ~1000 terms, and float accumulation alone
    // would cost ~1e-6 of the model's size per level.
    double acc[kMaxChannels];
    for (size_t i = b; i < e; ++i) {
      for (int k = 0; k < channels; ++k) acc[k] = 0.0;
      for (uint32_t j = off[i]; j < off[i + 1]; ++j) {
        const float* src = in + size_t(idx[j]) * size_t(channels);
        const double wj = w[j];
        for (int k = 0; k < channels; ++k) acc[k] += wj * src[k];
      }
      float* o = out + i * size_t(channels);
      for (int k = 0; k < channels; ++k) o[k] = static_cast<float>(acc[k]);
    }
  };
  if (n < 4096) {
    body(0, n);
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2048),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
  }
}

StencilTable compose_stencils(const StencilTable& outer, const StencilTable& inner) {
  StencilTable out;
  out.offsets.reserve(outer.size() + 1);
  const size_t n = outer.size();
  // Dense scratch over the source points, cleared through the touched list: merging without
  // sorting keeps composition linear in the entries.
  size_t sources = 0;
  for (uint32_t i : inner.indices) sources = std::max(sources, size_t(i) + 1);
  std::vector<double> acc(sources, 0.0);
  std::vector<uint8_t> seen(sources, 0);
  std::vector<uint32_t> touched;
  for (size_t p = 0; p < n; ++p) {
    touched.clear();
    for (uint32_t j = outer.offsets[p]; j < outer.offsets[p + 1]; ++j) {
      const uint32_t q = outer.indices[j];
      const double w = outer.weights[j];
      for (uint32_t k = inner.offsets[q]; k < inner.offsets[q + 1]; ++k) {
        const uint32_t src = inner.indices[k];
        if (!seen[src]) seen[src] = 1, touched.push_back(src);
        acc[src] += w * double(inner.weights[k]);
      }
    }
    std::sort(touched.begin(), touched.end());
    for (uint32_t src : touched) {
      const double w = acc[src];
      acc[src] = 0.0, seen[src] = 0;
      if (w == 0.0) continue;  // exact cancellation: nothing to read
      out.indices.push_back(src);
      out.weights.push_back(static_cast<float>(w));
    }
    out.offsets.push_back(static_cast<uint32_t>(out.indices.size()));
  }
  return out;
}

StencilTable cage_stencils(const UniformRefinement& r, int level) {
  if (level < 1 || level > int(r.stencils.size()))
    throw InputError(fmt::format("cage_stencils: level {} not refined", level));
  StencilTable flat = r.stencils[0];
  for (int k = 1; k < level; ++k) flat = compose_stencils(r.stencils[size_t(k)], flat);
  return flat;
}

std::vector<float> UniformRefinement::positions(const Mesh& cage, int level) const {
  std::vector<float> cur = cage.positions, next;
  for (int k = 0; k < level; ++k) {
    next.resize(3 * stencils[size_t(k)].size());
    apply_stencils(stencils[size_t(k)], cur.data(), next.data(), 3);
    cur.swap(next);
  }
  return cur;
}

std::vector<float> SparseRefinement::positions(const Mesh& cage, int level) const {
  if (level < 0 || level >= int(levels.size()))
    throw InputError(fmt::format("sparse refinement: level {} not refined", level));
  std::vector<float> cur = cage.positions, next;
  for (int k = 0; k < level; ++k) {
    next.resize(3 * stencils[size_t(k)].size());
    apply_stencils(stencils[size_t(k)], cur.data(), next.data(), 3);
    cur.swap(next);
  }
  return cur;
}

SparseRefinement refine_sparse(const Mesh& cage, std::span<const uint8_t> vertex_depth,
                               std::span<const uint8_t> face_depth, const SubdivOptions& options) {
  constexpr int kMaxSparseDepth = 16;
  validate(cage, "cage");
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

  SparseRefinement r;
  r.options = options;
  r.levels.reserve(kMaxSparseDepth + 1);
  {
    SparseLevel& L0 = r.levels.emplace_back();
    L0.level.face_offsets = cage.face_offsets;
    L0.level.face_vertices = cage.face_vertices;
    L0.vertex_complete.assign(nv0, 1);
    L0.vertex_depth.assign(nv0, 0);
    L0.face_depth.assign(nf0, 0);
    std::copy(vertex_depth.begin(), vertex_depth.end(), L0.vertex_depth.begin());
    std::copy(face_depth.begin(), face_depth.end(), L0.face_depth.begin());
  }
  auto adj = std::make_unique<Adjacency>(nv0, r.levels[0].level);
  init_cage_level(cage, options, *adj, r.levels[0].level);

  for (size_t k = 0;; ++k) {
    SparseLevel& P = r.levels[k];
    const RefinedLevel& PL = P.level;
    const Topology& t = adj->topo;
    const uint32_t nf = static_cast<uint32_t>(PL.face_count()),
                   nv = static_cast<uint32_t>(PL.vertex_count()),
                   ne = static_cast<uint32_t>(PL.edge_count());
    // Requested faces, and the vertices they touch: every face around those is refined too, so
    // that each requested face's child points see whole rings.
    std::vector<uint8_t> near(nv, 0);
    bool any = false;
    for (uint32_t f = 0; f < nf; ++f) {
      const uint32_t b = PL.face_offsets[f], e = PL.face_offsets[f + 1];
      bool requested = P.face_depth[f] > 0;
      for (uint32_t c = b; c < e && !requested; ++c)
        requested = P.vertex_depth[PL.face_vertices[c]] > 0;
      if (!requested) continue;
      any = true;
      for (uint32_t c = b; c < e; ++c) near[PL.face_vertices[c]] = 1;
    }
    P.face_refined.assign(nf, 0);
    if (!any) break;
    if (k == kMaxSparseDepth)
      throw std::logic_error("sparse refinement: depth requests outlived the depth bound");
    for (uint32_t v = 0; v < nv; ++v)
      if (near[v])
        for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i)
          P.face_refined[t.corner_face[t.vertex_corners[i]]] = 1;

    Selection sel;
    sel.all = false;
    sel.edge_slot.assign(ne, kNone);
    sel.vertex_slot.assign(nv, kNone);
    for (uint32_t f = 0; f < nf; ++f) {
      if (!P.face_refined[f]) continue;
      sel.faces.push_back(f);
      for (uint32_t c = PL.face_offsets[f]; c < PL.face_offsets[f + 1]; ++c) {
        const uint32_t v = PL.face_vertices[c];
        // The selection rule guarantees this (see the header); a failure is a bug in limn.
        if (!P.vertex_complete[v])
          throw std::logic_error(fmt::format(
              "sparse refinement: level {} vertex {} is refined without its whole ring", k, v));
        sel.vertex_slot[v] = 0;
        sel.edge_slot[t.corner_edge[c]] = 0;
      }
    }
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
    StencilTable& S = r.stencils.emplace_back();
    refine_level(options, PL, *adj, sel, C.level, S);
    auto cadj = std::make_unique<Adjacency>(C.level.vertex_sharpness.size(), C.level);
    child_edges(options, PL, *adj, sel, *cadj, C.level);

    // Provenance, completeness and the depths left.
    const size_t nvc = size_t(sel.nf) + sel.ne + sel.nv;
    C.vertex_complete.assign(nvc, 1);  // face points: the face's children are all present
    C.vertex_depth.assign(nvc, 0);
    for (uint32_t i = 0; i < sel.ne; ++i) {
      const uint32_t e = sel.edges[i];
      const uint32_t a = PL.edge_vertices[2 * size_t(e)], b = PL.edge_vertices[2 * size_t(e) + 1];
      // A complete end vertex has every face of the edge; each must be refined.
      bool whole = P.vertex_complete[a] || P.vertex_complete[b];
      for (uint32_t j = adj->edge_face_offsets[e]; j < adj->edge_face_offsets[e + 1] && whole; ++j)
        whole = P.face_refined[adj->edge_faces[j]];
      C.vertex_complete[sel.nf + i] = whole;
    }
    for (uint32_t i = 0; i < sel.nv; ++i) {
      const uint32_t v = sel.vertices[i];
      bool whole = P.vertex_complete[v];
      for (uint32_t j = t.vertex_offsets[v]; j < t.vertex_offsets[v + 1] && whole; ++j)
        whole = P.face_refined[t.corner_face[t.vertex_corners[j]]];
      const size_t cv = size_t(sel.nf) + sel.ne + i;
      C.vertex_complete[cv] = whole;
      C.vertex_depth[cv] = P.vertex_depth[v] > 0 ? uint8_t(P.vertex_depth[v] - 1) : 0;
    }
    for (uint32_t f : sel.faces) {
      const uint32_t n = PL.face_offsets[f + 1] - PL.face_offsets[f];
      for (uint32_t i = 0; i < n; ++i) {
        C.face_parent.push_back(f);
        C.face_depth.push_back(P.face_depth[f] > 0 ? uint8_t(P.face_depth[f] - 1) : 0);
      }
    }
    C.parent_faces = std::move(sel.faces);
    C.parent_edges = std::move(sel.edges);
    C.parent_vertices = std::move(sel.vertices);
    r.levels.push_back(std::move(C));
    adj = std::move(cadj);
  }
  return r;
}

UniformRefinement refine_uniform(const Mesh& cage, int depth, const SubdivOptions& options) {
  if (depth < 0 || depth > 8)
    throw InputError(fmt::format("refinement depth {} out of range (0-8)", depth));
  validate(cage, "cage");
  UniformRefinement r;
  r.options = options;
  r.levels.resize(size_t(depth) + 1);
  r.stencils.resize(size_t(depth));
  RefinedLevel& L0 = r.levels[0];
  L0.face_offsets = cage.face_offsets;
  L0.face_vertices = cage.face_vertices;
  auto adj = std::make_unique<Adjacency>(cage.vertex_count(), L0);
  init_cage_level(cage, options, *adj, L0);
  for (int k = 0; k < depth; ++k) {
    RefinedLevel& P = r.levels[size_t(k)];
    RefinedLevel& C = r.levels[size_t(k) + 1];
    const Selection all = Selection::everything(P);
    refine_level(options, P, *adj, all, C, r.stencils[size_t(k)]);
    auto cadj = std::make_unique<Adjacency>(C.vertex_sharpness.size(), C);
    child_edges(options, P, *adj, all, *cadj, C);
    adj = std::move(cadj);
  }
  return r;
}

}  // namespace limn
