// Limit positions and tangents at the vertices of a refinement level.
//
// The masks are Catmull-Clark's limit masks as OpenSubdiv's Sdc::Scheme<CATMARK> states them
// (Halstead et al. 1993 for the smooth case; Biermann et al. 2000 for crease tangents). They
// need each vertex's faces and edges in rotational order: face i lies between edge i (towards the
// next vertex of face i) and edge i+1 (towards its previous vertex); boundary vertices start at
// their boundary edge; interior vertices start at their lowest-numbered face, as OpenSubdiv's
// Vtr does, so tangents agree with OpenSubdiv's, not only the normals.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "limit_masks.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {

LimitStencils limit_stencils(const UniformRefinement& r, int level) {
  if (level < 0 || level >= int(r.levels.size()))
    throw InputError(fmt::format("limit: level {} not refined", level));
  return limit_stencils(r.levels[size_t(level)]);
}

namespace {

// The smooth rule's limit masks at an interior vertex v of valence n (n != 2): position and the
// two tangents (the second the first turned by one sector), from its ring's edge-end and diagonal
// vertices in rotational order.
void smooth_masks(uint32_t v, int n, const std::vector<uint32_t>& ring_e,
                  const std::vector<uint32_t>& ring_f, Weighted& P, Weighted& T1, Weighted& T2) {
  const double pi = std::numbers::pi;
  const double dn = n;
  if (n == 4) {
    P.add(v, 4.0 / 9.0);
    for (int i = 0; i < 4; ++i) P.add(ring_e[i], 1.0 / 9.0), P.add(ring_f[i], 1.0 / 36.0);
  } else {
    const double fw = 1.0 / (dn * (dn + 5.0)), ew = 4.0 * fw;
    P.add(v, 1.0 - dn * (ew + fw));
    for (int i = 0; i < n; ++i) P.add(ring_e[i], ew), P.add(ring_f[i], fw);
  }
  std::vector<double> e1(n), f1(n);
  if (n == 4) {
    e1 = {4, 0, -4, 0};
    f1 = {1, -1, -1, 1};
  } else {
    const double th = 2.0 * pi / dn, ct = std::cos(th), ch = std::cos(0.5 * th);
    const double lambda = 5.0 / 16.0 + (ct + ch * std::sqrt(2.0 * (9.0 + ct))) / 16.0;
    const double fs = 1.0 / (4.0 * lambda - 1.0);
    for (int i = 0; i < n; ++i) {
      e1[i] = 4.0 * std::cos(i * th);
      f1[i] = fs * (std::cos(i * th) + std::cos((i + 1) * th));
    }
  }
  for (int i = 0; i < n; ++i) {
    T1.add(ring_e[i], e1[i]), T1.add(ring_f[i], f1[i]);
    // The second tangent is the first rotated by one sector.
    const int j = (i + n - 1) % n;
    T2.add(ring_e[i], e1[j]), T2.add(ring_f[i], f1[j]);
  }
}

// The crease rule's limit masks at v: position and the along-crease tangent from the crease's
// two edges (es: each ring edge's sharpness), the across-crease tangent from the ring between
// them (a convention where there is no rotational order).
void crease_masks(const Topology& t, const uint32_t* fv, uint32_t v, uint32_t s0, bool manifold,
                  const std::vector<uint32_t>& ring_e, const std::vector<uint32_t>& ring_f,
                  const std::vector<float>& es, Weighted& P, Weighted& T1, Weighted& T2) {
  const double pi = std::numbers::pi;
  const int n_e = int(ring_e.size());
  int c0 = -1, c1 = -1;
  for (int i = 0; i < n_e; ++i)
    if (es[i] > 0.0f) c1 = i, c0 = c0 < 0 ? i : c0;
  P.add(v, 2.0 / 3.0);
  P.add(ring_e[c0], 1.0 / 6.0), P.add(ring_e[c1], 1.0 / 6.0);
  T1.add(ring_e[c0], 0.5), T1.add(ring_e[c1], -0.5);
  const int interior = c1 - c0 - 1;
  if (!manifold) {
    // No rotational order (a non-manifold crease): the across-crease tangent is a
    // convention, along an edge off the crease, like a corner's.
    int off = -1;
    for (int i = 0; i < n_e && off < 0; ++i)
      if (i != c0 && i != c1) off = i;
    const uint32_t c = t.vertex_corners[s0];
    const uint32_t to = off >= 0 ? ring_e[size_t(off)] : fv[t.corner_prev[c]];
    T2.add(v, -1.0), T2.add(to, 1.0);
  } else if (interior == 1) {
    T2.add(v, -4.0 / 6.0);
    T2.add(ring_e[c0], -1.0 / 6.0), T2.add(ring_e[c0 + 1], 4.0 / 6.0);
    T2.add(ring_e[c1], -1.0 / 6.0);
    T2.add(ring_f[c0], 1.0 / 6.0), T2.add(ring_f[c0 + 1], 1.0 / 6.0);
  } else if (interior > 1) {
    const double k = interior + 1, th = pi / k, ct = std::cos(th), st = std::sin(th);
    const double denom = 1.0 / (k * (3.0 + ct)), R = (ct + 1.0) / st;
    T2.add(v, 4.0 * R * (ct - 1.0) * denom);
    T2.add(ring_e[c0], -R * (1.0 + 2.0 * ct) * denom);
    T2.add(ring_e[c1], -R * (1.0 + 2.0 * ct) * denom);
    T2.add(ring_f[c0], st * denom);
    for (int i = 1; i < k; ++i) {
      T2.add(ring_e[c0 + i], 4.0 * std::sin(i * th) * denom);
      T2.add(ring_f[c0 + i], (std::sin(i * th) + std::sin((i + 1) * th)) * denom);
    }
  } else {
    T2.add(v, -6.0), T2.add(ring_e[c0], 3.0), T2.add(ring_e[c1], 3.0);
  }
}

}  // namespace

LimitMasks::LimitMasks(const RefinedLevel& L)
    : L_(L), t_(build_topology(L.vertex_count(), L.face_offsets, L.face_vertices)) {
  for (size_t f = 0; f < L.face_count(); ++f)
    if (L.face_offsets[f + 1] - L.face_offsets[f] != 4)
      throw InputError("limit: the level has non-quad faces; refine at least once");
  const Topology& t = t_;
  const uint32_t* fv = L.face_vertices.data();
  // The level numbers its edges its own way (derived levels do not follow build_topology's
  // order), so carry each level edge's sharpness over to the corner table's edge ids.
  if (L.edge_vertices.size() != 2 * t.edge_count() || L.edge_sharpness.size() != t.edge_count())
    throw std::logic_error("limit: the level's edge list does not match its faces");
  sharp_of_edge_.assign(t.edge_count(), 0.0f);
  for (size_t e = 0; e < t.edge_count(); ++e) {
    const uint32_t a = L.edge_vertices[2 * e], b = L.edge_vertices[2 * e + 1];
    uint32_t id = kNone;
    for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}})
      for (uint32_t i = t.vertex_offsets[from]; i < t.vertex_offsets[from + 1] && id == kNone; ++i)
        if (fv[t.corner_next[t.vertex_corners[i]]] == to) id = t.corner_edge[t.vertex_corners[i]];
    if (id == kNone) throw std::logic_error("limit: a level edge joins no face's corners");
    sharp_of_edge_[id] = L.edge_sharpness[e];
  }
}

void LimitMasks::compute(uint32_t v, Weighted& P, Weighted& T1, Weighted& T2) {
  const Topology& t = t_;
  const RefinedLevel& L = L_;
  const uint32_t* fv = L.face_vertices.data();
  std::vector<uint32_t>& ring_e = ring_e_;  // other-end vertex per edge
  std::vector<uint32_t>& ring_f = ring_f_;  // diagonal vertex per face
  std::vector<float>& es = es_;
  const std::vector<float>& sharp_of_edge = sharp_of_edge_;
  const uint32_t s0 = t.vertex_offsets[v], nfaces = t.vertex_offsets[v + 1] - s0;
  if (nfaces == 0) {  // isolated vertex: stays where it is
    P.add(v, 1.0);
    return;
  }
  // Rotational order. Start: the corner whose outgoing half-edge is a boundary, else the first
  // (lowest face) corner.
  uint32_t start = t.vertex_corners[s0];
  bool manifold = true, boundary = false;
  for (uint32_t i = 0; i < nfaces; ++i) {
    const uint32_t c = t.vertex_corners[s0 + i];
    // Shared by more than two faces, or by two that disagree on its direction: no fan.
    auto torn = [&](uint32_t h) {
      const uint32_t tw = t.corner_twin[h];
      return tw == kNonManifold || (tw != kNone && fv[tw] == fv[h]);
    };
    if (torn(c) || torn(t.corner_prev[c])) manifold = false;
    if (t.corner_twin[c] == kNone && !boundary) start = c, boundary = true;
  }
  ring_e.clear(), ring_f.clear(), es.clear();
  if (manifold) {
    uint32_t c = start;
    for (uint32_t i = 0; i < nfaces; ++i) {
      ring_e.push_back(fv[t.corner_next[c]]);
      es.push_back(sharp_of_edge[t.corner_edge[c]]);
      ring_f.push_back(fv[t.corner_next[t.corner_next[c]]]);
      const uint32_t in = t.corner_prev[c];
      const uint32_t tw = t.corner_twin[in];
      if (tw == kNone) {  // reached the other boundary edge
        ring_e.push_back(fv[in]);
        es.push_back(sharp_of_edge[t.corner_edge[in]]);
        break;
      }
      if (tw == start || tw >= kNonManifold) break;
      c = tw;
    }
    // A vertex whose faces do not form one fan (a bowtie) is non-manifold.
    if (ring_f.size() != nfaces) manifold = false;
  }
  if (!manifold) {
    // No rotational order exists: take the incident edges in star order for the rule and the
    // crease ends (a non-manifold crease is two non-manifold edges, as OpenSubdiv tags it).
    ring_e.clear(), ring_f.clear(), es.clear();
    for (uint32_t i = 0; i < nfaces; ++i) {
      const uint32_t c = t.vertex_corners[s0 + i];
      for (const uint32_t h : {c, t.corner_prev[c]}) {
        const uint32_t other = h == c ? fv[t.corner_next[c]] : fv[h];
        if (std::find(ring_e.begin(), ring_e.end(), other) != ring_e.end()) continue;
        ring_e.push_back(other);
        es.push_back(sharp_of_edge[t.corner_edge[h]]);
      }
    }
  }
  const bool is_corner_rule = false;
  int sharp_edges = 0;
  for (float x : es) sharp_edges += x > 0.0f;
  const float vs = L.vertex_sharpness[v];
  const int n_e = int(ring_e.size()), n_f = int(ring_f.size());
  int rule;  // 0 smooth/dart, 1 crease, 2 corner
  if (is_corner_rule || vs > 0.0f || sharp_edges > 2)
    rule = 2;
  else
    rule = sharp_edges == 2 ? 1 : 0;

  if (rule == 0 && !manifold) rule = 2;  // smooth needs a fan; OpenSubdiv sharpens these
  if (rule == 0) {
    const int n = n_f;
    if (n == 2) {  // OpenSubdiv treats a smooth valence-2 vertex as a corner
      rule = 2;
    } else {
      smooth_masks(v, n, ring_e, ring_f, P, T1, T2);
    }
  }
  if (rule == 1) crease_masks(t, fv, v, s0, manifold, ring_e, ring_f, es, P, T1, T2);
  if (rule == 2) {
    P.add(v, 1.0);
    // Corner tangents: along the first two edges of the ring (any two for non-manifold).
    if (n_e >= 2) {
      T1.add(v, -1.0), T1.add(ring_e[0], 1.0);
      T2.add(v, -1.0), T2.add(ring_e[1], 1.0);
    } else {
      // Non-manifold: tangents along the first two edges of the first face.
      const uint32_t c = t.vertex_corners[s0];
      T1.add(v, -1.0), T1.add(fv[t.corner_next[c]], 1.0);
      T2.add(v, -1.0), T2.add(fv[t.corner_prev[c]], 1.0);
    }
  }
}

LimitStencils limit_stencils(const RefinedLevel& L) {
  LimitMasks masks(L);
  const size_t nv = L.vertex_count();
  LimitStencils out;
  for (auto* s : {&out.position, &out.tangent1, &out.tangent2}) s->offsets.reserve(nv + 1);
  Weighted P, T1, T2;
  for (uint32_t v = 0; v < nv; ++v) {
    masks.compute(v, P, T1, T2);
    P.emit(out.position), T1.emit(out.tangent1), T2.emit(out.tangent2);
  }
  return out;
}

std::vector<float> normals_from_tangents(const std::vector<float>& a, const std::vector<float>& b) {
  std::vector<float> n(a.size());
  for (size_t i = 0; i + 2 < a.size(); i += 3) {
    const double x = double(a[i + 1]) * b[i + 2] - double(a[i + 2]) * b[i + 1];
    const double y = double(a[i + 2]) * b[i] - double(a[i]) * b[i + 2];
    const double z = double(a[i]) * b[i + 1] - double(a[i + 1]) * b[i];
    const double l = std::sqrt(x * x + y * y + z * z);
    const double s = l > 0.0 ? 1.0 / l : 0.0;
    n[i] = float(x * s), n[i + 1] = float(y * s), n[i + 2] = float(z * s);
  }
  return n;
}

}  // namespace limn
