// Face-varying channels (UVs) through uniform Catmull-Clark refinement, as OpenSubdiv 3.5
// refines them (Vtr::FVarLevel / FVarRefinement and Far::PrimvarRefiner::InterpolateFace-
// Varying; facts, not code).
//
// The model: a channel is a value index per corner; continuity is decided by index alone. At a
// vertex, the distinct values around it are its "siblings", each with a span of faces. On the
// cage every vertex whose channel topology differs from the vertex topology (a seam touches it,
// or the interpolation mode pins it) is tagged once: each of its values becomes a corner
// (pinned), a crease (the crease rule between the two values at the ends of its span) or
// semi-sharp (a corner until nearby semi-sharp edges decay, then a crease). Refinement then only
// propagates those tags, as OpenSubdiv does: children of a vertex keep its values and tags, the
// child of a seam edge gets one value per face on it (a crease unless boundaries are linear).
// Where the topology matches, values take the vertex masks (rules.hpp, read through the values
// at each corner); mismatched edge points are midpoints on each side.
#include "face_varying.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "core/parallel.hpp"
#include "limit_masks.hpp"
#include "limn/subdiv/refine.hpp"
#include "rules.hpp"
#include "shared_weights.hpp"

namespace limn {
namespace refine_detail {
namespace {

// What the interpolation mode means for tagging (Vtr::FVarLevel::completeTopologyFromFace-
// Values).
struct Mode {
  bool linear_all, linear_boundaries, dependent, corners_sharp, smooth_corners_sharp, sharpen_both,
      sharpen_darts;
  explicit Mode(const SubdivOptions& o) {
    const FVarInterpolation m = o.face_varying;
    linear_all = m == FVarInterpolation::all;
    linear_boundaries = linear_all || m == FVarInterpolation::boundaries;
    dependent = m == FVarInterpolation::corners_plus1 || m == FVarInterpolation::corners_plus2;
    corners_sharp = m != FVarInterpolation::none;
    smooth_corners_sharp = o.boundary != BoundaryInterpolation::edge_and_corner && corners_sharp;
    sharpen_both = m == FVarInterpolation::corners_plus2;
    sharpen_darts = sharpen_both || linear_boundaries;
  }
  bool smooth_boundaries() const { return !linear_boundaries; }
};

// Corner of half-edge h's face at end v of its edge.
uint32_t corner_at(const LevelRef& l, uint32_t h, uint32_t v) {
  return l.L.face_vertices[h] == v ? h : l.next(h);
}

// The values a stencil reads on level P: the value at each corner, edge end and (matching)
// vertex, as the caller indexes them (the cage's own indices on level 0).
struct FVarIds {
  LevelRef l;
  const uint32_t* value;   // per corner
  const uint32_t* source;  // per value, or null
  uint32_t id(uint32_t x) const { return source ? source[x] : x; }
  uint32_t corner(uint32_t c) const { return id(value[c]); }
  uint32_t end(uint32_t e, uint32_t w) const {
    return id(value[corner_at(l, l.a.ec[l.a.eco[e]], w)]);
  }
  uint32_t vertex(uint32_t v) const { return id(value[l.a.vc[l.a.vco[v]]]); }
};

// Per value at one vertex: its span (the faces around the vertex holding it) and the edges
// between two of them (OpenSubdiv's ValueSpan).
struct Span {
  uint32_t size = 0, interior = 0, discts = 0, inf = 0, semi = 0;
};

class Spans {
 public:
  Spans(const RefinedLevel& L, const Adj& a, const FVarState& s) : l_{L, a}, s_(s) {}

  // The value at v in the face of half-edge h (h on an edge at v).
  uint32_t value_at(uint32_t h, uint32_t v) const { return s_.corner_value[corner_at(l_, h, v)]; }

  // Both faces of two-face edge e (at v) hold value x at v and the channel is continuous across
  // it: e is inside x's span.
  bool interior(uint32_t e, uint32_t v, uint32_t x) const {
    const Adj& a = l_.a;
    if (a.edge_face_count(e) != 2 || (s_.edge[e] & kFvEdgeMismatch)) return false;
    return value_at(a.ec[a.eco[e]], v) == x && value_at(a.ec[a.eco[e] + 1], v) == x;
  }

  // The values at the far ends of the two edges that bound value x's span at v (its crease
  // ends); false unless there are exactly two.
  bool ends(uint32_t v, uint32_t x, uint32_t out[2]) const {
    const Adj& a = l_.a;
    const uint32_t* cv = s_.corner_value.data();
    int n = 0;
    for (uint32_t i = a.vco[v]; i < a.vco[v + 1]; ++i) {
      const uint32_t c = a.vc[i];
      if (cv[c] != x) continue;
      const uint32_t far[2] = {l_.next(c), l_.prev(c)};
      const uint32_t edges[2] = {a.corner_edge[c], a.corner_edge[far[1]]};
      for (int j = 0; j < 2; ++j) {
        if (interior(edges[j], v, x)) continue;
        if (n == 2) return false;
        out[n++] = cv[far[j]];
      }
    }
    return n == 2;
  }

  // Parent and child sharpness of the edges inside value x's span at v (child: the half at v).
  void interior_sharpness(const SubdivOptions& o, uint32_t v, uint32_t x, std::vector<float>& pe,
                          std::vector<float>& ce) {
    pe.clear(), ce.clear();
    const Adj& a = l_.a;
    for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k) {
      const uint32_t e = a.ve[k];
      if (!interior(e, v, x)) continue;
      pe.push_back(l_.L.edge_sharpness[e]);
      ce.push_back(half_sharpness_at(o, l_.L, a, e, v, ps_, cs_));
    }
  }

 private:
  LevelRef l_;
  const FVarState& s_;
  std::vector<float> ps_, cs_;
};

// Tags the values of vertex v (its channel topology mismatches the vertex's), as
// completeTopologyFromFaceValues' second pass.
void tag_values(const Mode& m, const RefinedLevel& L, const Adj& a, const Spans& spans,
                bool non_manifold, uint32_t v, FVarState& s) {
  const uint32_t b = s.offsets[v], nvals = s.offsets[v + 1] - b;
  std::fill(s.tag.begin() + b, s.tag.begin() + b + nvals, uint8_t(kFvMismatch));
  if (non_manifold || nvals == 0) return;  // every value a corner
  bool boundary = false;
  for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k) boundary |= a.edge_face_count(a.ve[k]) == 1;
  std::vector<Span> sp(nvals);
  for (uint32_t i = a.vco[v]; i < a.vco[v + 1]; ++i) ++sp[s.corner_value[a.vc[i]] - b].size;
  uint32_t mismatched = 0;
  for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k) {
    const uint32_t e = a.ve[k];
    if (a.edge_face_count(e) != 2) continue;
    const uint32_t x0 = spans.value_at(a.ec[a.eco[e]], v);
    const uint32_t x1 = spans.value_at(a.ec[a.eco[e] + 1], v);
    if (x0 != x1) continue;
    Span& p = sp[x0 - b];
    ++p.interior;
    const float sharpness = L.edge_sharpness[e];
    if (s.edge[e] & kFvEdgeMismatch) {
      ++p.discts, ++mismatched;
    } else if (sharpness >= kInf) {
      ++p.inf;
    } else if (sharp(sharpness)) {
      ++p.semi;
    }
  }
  if (nvals == 1 && !boundary) {
    // One value all round: a dart when exactly one seam edge ends here, else disjoint.
    sp[0].discts = mismatched >= 2 ? 1 : 0;
  } else {
    // A span that is not one fan of faces counts as disjoint.
    for (Span& p : sp) p.discts += p.size - p.interior - 1;
  }
  const float vs = L.vertex_sharpness[v];
  bool all_sharp = m.linear_boundaries || vs >= kInf || (m.dependent && nvals > 2) ||
                   (m.sharpen_darts && nvals == 1 && !boundary);
  bool dependent = false;
  if (!all_sharp && m.dependent && nvals == 2) {
    all_sharp = sp[0].inf || sp[1].inf || sp[0].discts || sp[1].discts;
    if (m.sharpen_both) all_sharp |= sp[0].size == 1 || sp[1].size == 1;
    dependent = (sp[0].semi > 0) != (sp[1].semi > 0);
  }
  for (uint32_t i = 0; i < nvals; ++i) {
    const Span& p = sp[i];
    if (p.discts) continue;  // non-manifold in the channel: a corner
    const bool inf = all_sharp || p.inf || (p.size == 1 && m.corners_sharp);
    if (inf) continue;
    uint8_t& t = s.tag[b + i];
    if (p.semi || semi_sharp(vs)) {
      t |= kFvSemiSharp;
    } else if (dependent) {
      t |= kFvSemiSharp | kFvDepSharp;
    } else {
      t |= kFvCrease;
    }
  }
}

// After a step, semi-sharp values whose sharpness has decayed become creases
// (FVarRefinement::reclassifySemisharpValues). `ce` holds the child sharpness of v's edges.
void reclassify(const SubdivOptions& o, const Mode& m, const RefinedLevel& P, const Adj& a,
                const Spans& spans, uint32_t v, uint32_t pb, uint8_t* tag, uint32_t nvals,
                std::vector<float>& ce, std::vector<float>& pe_scratch,
                std::vector<float>& ce_scratch) {
  bool p_semi_edges = false;
  for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k)
    p_semi_edges |= semi_sharp(P.edge_sharpness[a.ve[k]]);
  const float pv = P.vertex_sharpness[v], cv = decrement(pv);
  if (!semi_sharp(pv) && !p_semi_edges) return;
  if (semi_sharp(cv) || cv >= kInf) return;
  // The child sharpness of v's edges (their halves at v).
  ce.clear();
  bool c_semi_edges = false;
  for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k) {
    ce.push_back(half_sharpness_at(o, P, a, a.ve[k], v, pe_scratch, ce_scratch));
    c_semi_edges |= semi_sharp(ce.back());
  }
  for (uint32_t i = 0; i < nvals; ++i) {
    if (!(tag[i] & kFvSemiSharp)) continue;
    bool still = false;
    if (c_semi_edges && !(tag[i] & kFvDepSharp)) {
      for (uint32_t k = a.veo[v]; k < a.veo[v + 1] && !still; ++k)
        still = spans.interior(a.ve[k], v, pb + i) && semi_sharp(ce[k - a.veo[v]]);
    } else if (c_semi_edges) {
      continue;  // dependent: follows its sibling (below)
    }
    if (!still) tag[i] = uint8_t((tag[i] & ~(kFvSemiSharp | kFvDepSharp)) | kFvCrease);
  }
  if (c_semi_edges && nvals == 2 && m.dependent) {
    if ((tag[0] & kFvDepSharp) && !(tag[1] & kFvSemiSharp)) {
      tag[0] &= uint8_t(~kFvDepSharp);
    } else if ((tag[1] & kFvDepSharp) && !(tag[0] & kFvSemiSharp)) {
      tag[1] &= uint8_t(~kFvDepSharp);
    }
  }
}

// Appends one stencil row (weights per entry).
void emit(StencilTable& t, std::initializer_list<std::pair<uint32_t, double>> terms) {
  for (const auto& [i, w] : terms) t.indices.push_back(i), t.weights.push_back(float(w));
  t.offsets.push_back(uint32_t(t.indices.size()));
}

void emit(StencilTable& t, const Terms& terms) {
  const size_t b = t.indices.size(), n = terms.n;
  t.indices.resize(b + n), t.weights.resize(b + n);
  uint32_t* ix = t.indices.data() + b;
  float* w = t.weights.data() + b;
  for (size_t k = 0; k < n; ++k) ix[k] = terms.idx[k], w[k] = float(terms.w[k]);
  t.offsets.push_back(uint32_t(b + n));
}

// Position of half-edge h among edge e's.
uint32_t slot_on_edge(const Adj& a, uint32_t e, uint32_t h) {
  for (uint32_t k = a.eco[e]; k < a.eco[e + 1]; ++k)
    if (a.ec[k] == h) return k - a.eco[e];
  return 0;
}

// The corners around v in OpenSubdiv's vertex-face order: on a manifold vertex, from the
// corner of its lowest face (interior) or the one whose outgoing edge is on the boundary, each
// next across the incoming edge; else by face.
void ring_corners(const LevelRef& l, bool non_manifold, uint32_t v, std::vector<uint32_t>& out) {
  const Adj& a = l.a;
  out.clear();
  const uint32_t b = a.vco[v], n = a.vco[v + 1] - b;
  if (non_manifold) {
    out.assign(a.vc.begin() + b, a.vc.begin() + b + n);
    return;
  }
  if (n == 0) return;
  uint32_t c = a.vc[b];
  for (uint32_t i = b; i < b + n; ++i)
    if (a.edge_face_count(a.corner_edge[a.vc[i]]) == 1) {
      c = a.vc[i];
      break;
    }
  for (uint32_t i = 0; i < n; ++i) {
    out.push_back(c);
    const uint32_t e = a.corner_edge[l.prev(c)];
    if (a.edge_face_count(e) != 2) break;
    const uint32_t h0 = a.ec[a.eco[e]], h1 = a.ec[a.eco[e] + 1];
    c = h0 == l.prev(c) ? h1 : h0;
  }
}

constexpr size_t kChunk = 1 << 13;

// Where child rows go: appended to a table, or applied to values at once (the lean path).
struct TableSink {
  StencilTable& t;
  void row(const Terms& terms) { emit(t, terms); }
  void row(std::initializer_list<std::pair<uint32_t, double>> terms) { emit(t, terms); }
};

// Computes row after row of `width` floats: out[next] from in, weights rounded to float and
// summed in double as apply_stencils does, so both paths give the same values.
struct ApplySink {
  const float* in;
  float* out;
  int width;
  size_t next = 0;
  void row(const Terms& terms) {
    double acc[4] = {0, 0, 0, 0};
    for (size_t k = 0; k < terms.n; ++k) add(acc, terms.idx[k], terms.w[k]);
    store(acc);
  }
  void row(std::initializer_list<std::pair<uint32_t, double>> terms) {
    double acc[4] = {0, 0, 0, 0};
    for (const auto& [i, w] : terms) add(acc, i, w);
    store(acc);
  }
  void add(double* acc, uint32_t i, double w) const {
    const double wf = double(float(w));
    for (int k = 0; k < width; ++k)
      acc[k] += wf * double(in[size_t(i) * size_t(width) + size_t(k)]);
  }
  void store(const double* acc) {
    for (int k = 0; k < width; ++k) out[next * size_t(width) + size_t(k)] = float(acc[k]);
    ++next;
  }
};

// Sends the stencils of child vertex i's values (face point, edge point or vertex point of level
// P, derive_child's numbering) to `sink`.
template <class Sink>
void child_rows(const SubdivOptions& o, const Mode& m, const RefinedLevel& P, const FVarState& ps,
                const FVarState& cs, const FVarIds& ids, Rules<FVarIds>& rules, Spans& spans,
                uint32_t i, std::vector<float>& pe, std::vector<float>& ce, Sink& t) {
  const Adj& a = ids.l.a;
  const uint32_t F = uint32_t(P.face_count()), E = uint32_t(P.edge_count());
  const uint32_t cb = cs.offsets[i], n = cs.offsets[i + 1] - cb;
  if (i < F) {
    rules.face(i);
    return t.row(rules.terms());
  }
  if (i < F + E) {
    const uint32_t e = i - F;
    if (!(cs.tag[cb] & kFvMismatch)) {
      if (!m.linear_all) {
        rules.edge(e);
        return t.row(rules.terms());
      }
      const uint32_t x = P.edge_vertices[2 * size_t(e)], y = P.edge_vertices[2 * size_t(e) + 1];
      return t.row({{ids.end(e, x), 0.5}, {ids.end(e, y), 0.5}});
    }
    for (uint32_t j = 0; j < n; ++j) {  // each side of a seam: its own midpoint
      const uint32_t h = a.ec[a.eco[e] + j];
      t.row({{ids.corner(h), 0.5}, {ids.corner(ids.l.next(h)), 0.5}});
    }
    return;
  }
  if (n == 0) return;
  const uint32_t v = i - F - E, pb = ps.offsets[v];
  if (!(cs.tag[cb] & kFvMismatch)) {
    if (m.linear_all) return t.row({{ids.id(pb), 1.0}});
    rules.vertex(v);
    return t.row(rules.terms());
  }
  uint32_t end_values[2];
  for (uint32_t k = 0; k < n; ++k) {
    if (m.linear_all || !(cs.tag[cb + k] & kFvCrease) || !spans.ends(v, pb + k, end_values)) {
      t.row({{ids.id(pb + k), 1.0}});
      continue;
    }
    double vw = 0.75, ew = 0.125;
    const uint8_t ptag = ps.tag[pb + k];
    if (ptag & kFvSemiSharp) {
      // The fractional weight of the span whose sharpness this value follows.
      const uint32_t from = (ptag & kFvDepSharp) ? pb + (1 - k) : pb + k;
      spans.interior_sharpness(o, v, from, pe, ce);
      const float pvs = P.vertex_sharpness[v];
      const double wc =
          fractional_weight(o, pvs, decrement(pvs), pe.data(), ce.data(), int(pe.size()));
      vw = (1.0 - wc) * 0.75 + wc, ew = (1.0 - wc) * 0.125;
    }
    t.row({{ids.id(end_values[0]), ew}, {ids.id(end_values[1]), ew}, {ids.id(pb + k), vw}});
  }
}

}  // namespace

void check_face_varying(const FaceVaryingInput& channel, size_t corners) {
  if (channel.corner_values.size() != corners)
    throw InputError(fmt::format("face-varying channel has {} corner indices for {} corners",
                                 channel.corner_values.size(), corners));
  for (size_t c = 0; c < corners; ++c)
    if (channel.corner_values[c] >= channel.value_count)
      throw InputError(fmt::format("face-varying index {} at corner {} is past the {} values",
                                   channel.corner_values[c], c, channel.value_count));
}

FVarState fvar_cage_state(const SubdivOptions& o, const RefinedLevel& L0, const Adj& a,
                          std::span<const uint32_t> corner_values, size_t value_count) {
  const size_t nc = L0.face_vertices.size(), nv = L0.vertex_count();
  check_face_varying({corner_values, value_count}, nc);
  const Mode m(o);
  const LevelRef l{L0, a};
  const uint32_t* u = corner_values.data();
  FVarState s;
  s.edge.assign(L0.edge_count(), 0);
  // Seams: edges whose faces disagree on the value at an end, found vertex by vertex in
  // OpenSubdiv's order (the linear tags of boundary edges depend on it).
  auto disagrees_at = [&](uint32_t e, uint32_t v) {
    if (a.edge_face_count(e) < 2) return false;
    const uint32_t x = u[corner_at(l, a.ec[a.eco[e]], v)];
    for (uint32_t k = a.eco[e] + 1; k < a.eco[e + 1]; ++k)
      if (u[corner_at(l, a.ec[k], v)] != x) return true;
    return false;
  };
  std::vector<uint8_t> mismatch(nv, 0), non_manifold(nv, 0);
  std::vector<uint32_t> distinct, ring;
  s.corner_value.resize(nc);
  s.offsets.assign(nv + 1, 0);
  std::vector<uint32_t> source;
  for (uint32_t v = 0; v < nv; ++v) {
    non_manifold[v] = cage_vertex_non_manifold(a, v);
    bool boundary = false;
    for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k) {
      const uint32_t e = a.ve[k];
      boundary |= a.edge_face_count(e) == 1;
      if (!disagrees_at(e, v)) continue;
      s.edge[e] = uint8_t(kFvEdgeMismatch | (m.linear_boundaries ? kFvEdgeLinear : 0));
      mismatch[L0.edge_vertices[2 * e]] = mismatch[L0.edge_vertices[2 * e + 1]] = 1;
    }
    const uint32_t nfaces = a.vertex_face_count(v);
    if (boundary && !mismatch[v]) {
      if (m.linear_boundaries && nfaces > 0) {
        mismatch[v] = 1;
        for (uint32_t k = a.veo[v]; k < a.veo[v + 1]; ++k)
          if (a.edge_face_count(a.ve[k]) == 1) s.edge[a.ve[k]] |= kFvEdgeLinear;
      } else if (nfaces == 1 && m.smooth_corners_sharp) {
        mismatch[v] = 1;
      }
    }
    // The distinct values around v, each corner's sibling, in OpenSubdiv's order and with its
    // quirk: a value that returns after a third one may be counted twice (it then has two
    // spans, as separate values).
    ring_corners(l, non_manifold[v], v, ring);
    distinct.clear();
    for (size_t i = 0; i < ring.size(); ++i) {
      const uint32_t x = u[ring[i]];
      uint32_t sib = uint32_t(distinct.size());
      if (i > 0 && x == u[ring[i - 1]]) {
        sib = s.corner_value[ring[i - 1]] - s.offsets[v];
      } else if (distinct.size() == 2 && distinct[0] != x) {
        distinct.push_back(x);
      } else {
        const auto it = std::find(distinct.begin(), distinct.end(), x);
        if (it == distinct.end()) {
          distinct.push_back(x);
        } else {
          sib = uint32_t(it - distinct.begin());
        }
      }
      s.corner_value[ring[i]] = s.offsets[v] + sib;
    }
    if (non_manifold[v] && distinct.size() > 1) mismatch[v] = 1;
    source.insert(source.end(), distinct.begin(), distinct.end());
    s.offsets[v + 1] = uint32_t(source.size());
  }
  s.source = std::move(source);
  s.tag.assign(s.source.size(), 0);
  const Spans spans(L0, a, s);
  for (uint32_t v = 0; v < nv; ++v)
    if (mismatch[v]) tag_values(m, L0, a, spans, non_manifold[v], v, s);
  return s;
}

namespace {

// The channel on the child level of P (values, tags, corners, edges): the part of a step both
// the stencils and the lean path's direct application need.
void fvar_child_state(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                      const FVarState& ps, FVarState& cs) {
  const Mode m(o);
  const LevelRef l{P, a};
  const uint32_t F = uint32_t(P.face_count()), E = uint32_t(P.edge_count()),
                 V = uint32_t(P.vertex_count()), NC = uint32_t(P.face_vertices.size());
  const uint32_t* pv = ps.corner_value.data();
  auto count = [&](uint32_t v) { return ps.offsets[v + 1] - ps.offsets[v]; };
  // Child values: one per face point, one per edge point (one per face on a seam), and per
  // vertex point one (matching) or one per parent value.
  cs = FVarState();
  cs.offsets.assign(size_t(F) + E + V + 1, 0);
  for (uint32_t f = 0; f < F; ++f) cs.offsets[f + 1] = cs.offsets[f] + 1;
  for (uint32_t e = 0; e < E; ++e)
    cs.offsets[F + e + 1] =
        cs.offsets[F + e] + ((ps.edge[e] & kFvEdgeMismatch) ? a.edge_face_count(e) : 1);
  for (uint32_t v = 0; v < V; ++v) {
    const uint32_t n = count(v), i = F + E + v;
    cs.offsets[i + 1] = cs.offsets[i] + (n == 0                                  ? 0
                                         : (ps.tag[ps.offsets[v]] & kFvMismatch) ? n
                                                                                 : 1);
  }
  cs.tag.assign(cs.offsets.back(), 0);
  const uint8_t split = m.smooth_boundaries() ? kFvMismatch | kFvCrease : kFvMismatch;
  for (uint32_t e = 0; e < E; ++e)
    if (ps.edge[e] & (kFvEdgeMismatch | kFvEdgeLinear))
      std::fill(cs.tag.begin() + cs.offsets[F + e], cs.tag.begin() + cs.offsets[F + e + 1], split);
  const Spans spans(P, a, ps);
  parallel_range(V, kChunk, [&](size_t vb, size_t ve) {
    std::vector<float> ce, pe_scratch, ce_scratch;
    for (size_t v = vb; v < ve; ++v) {
      const uint32_t cb = cs.offsets[F + E + v], n = cs.offsets[F + E + v + 1] - cb;
      if (n == 0) continue;
      std::copy_n(ps.tag.begin() + ps.offsets[v], n, cs.tag.begin() + cb);
      if (m.smooth_boundaries() && (cs.tag[cb] & kFvMismatch))
        reclassify(o, m, P, a, spans, uint32_t(v), ps.offsets[v], cs.tag.data() + cb, n, ce,
                   pe_scratch, ce_scratch);
    }
  });
  // Child corners (derive_child's quads: vertex point, outgoing edge point, face point,
  // incoming edge point) and child edges (a seam's halves stay seams).
  cs.corner_value.resize(4 * size_t(NC));
  auto on_edge = [&](uint32_t e, uint32_t h) {
    const uint32_t b = cs.offsets[F + e];
    return cs.offsets[F + e + 1] - b > 1 ? b + slot_on_edge(a, e, h) : b;
  };
  parallel_range(F, kChunk, [&](size_t fb, size_t fe) {
    for (size_t f = fb; f < fe; ++f)
      for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
        const uint32_t p = l.prev(c), v = P.face_vertices[c];
        const uint32_t vb = cs.offsets[F + E + v];
        uint32_t* q = &cs.corner_value[4 * size_t(c)];
        q[0] = cs.offsets[F + E + v + 1] - vb > 1 ? vb + (pv[c] - ps.offsets[v]) : vb;
        q[1] = on_edge(a.corner_edge[c], c);
        q[2] = cs.offsets[f];
        q[3] = on_edge(a.corner_edge[p], p);
      }
  });
  cs.edge.assign(size_t(NC) + 2 * size_t(E), 0);
  for (uint32_t e = 0; e < E; ++e) cs.edge[NC + 2 * e] = cs.edge[NC + 2 * e + 1] = ps.edge[e];
}

// Runs child_rows over chunks of child vertices in parallel, each chunk with its own rules and
// scratch, into the sink make_sink(chunk, first child vertex, end) returns.
template <class MakeSink>
void for_child_chunks(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                      const FVarState& ps, const FVarState& cs, MakeSink&& make_sink) {
  const Mode m(o);
  const FVarIds ids{{P, a}, ps.corner_value.data(), ps.source.empty() ? nullptr : ps.source.data()};
  const Selection all = Selection::everything(P);
  const size_t n = P.face_count() + P.edge_count() + P.vertex_count();
  const size_t chunks = (n + kChunk - 1) / kChunk;
  parallel_range(chunks, 1, [&](size_t cb, size_t ce_) {
    Rules<FVarIds> rules(o, P, a, all, ids);
    Spans local(P, a, ps);
    std::vector<float> pe, ce;
    for (size_t c = cb; c < ce_; ++c) {
      const size_t first = c * kChunk, last = std::min(n, first + kChunk);
      auto sink = make_sink(c, first, last);
      for (size_t i = first; i < last; ++i)
        child_rows(o, m, P, ps, cs, ids, rules, local, uint32_t(i), pe, ce, sink);
    }
  });
}

}  // namespace

StencilTable fvar_refine(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                         const FVarState& ps, FVarState& cs) {
  fvar_child_state(o, P, a, ps, cs);
  // Stencils, in child value order (child vertex by child vertex), built in parallel chunks.
  const size_t n = P.face_count() + P.edge_count() + P.vertex_count();
  const size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<StencilTable> parts(chunks);
  for_child_chunks(o, P, a, ps, cs, [&](size_t c, size_t first, size_t last) {
    StencilTable& t = parts[c];
    const size_t rows = cs.offsets[last] - cs.offsets[first];
    // Room for the usual rows (a vertex point's smooth mask is 2 * valence + 1 entries).
    t.offsets.reserve(rows + 1);
    t.indices.reserve(rows * 10), t.weights.reserve(rows * 10);
    return TableSink{t};
  });
  // Concatenated in parallel: each part lands at its row and entry bases, its rows sharing
  // their weights (a level has a few distinct rows, as the vertex tables do).
  std::vector<size_t> row_base(chunks + 1, 0), entry_base(chunks + 1, 0);
  for (size_t c = 0; c < chunks; ++c) {
    row_base[c + 1] = row_base[c] + parts[c].size();
    entry_base[c + 1] = entry_base[c] + parts[c].indices.size();
  }
  if (entry_base[chunks] > UINT32_MAX)
    throw InputError("face-varying level needs more than 2^32 stencil entries");
  StencilTable t;
  t.offsets.resize(row_base[chunks] + 1);
  t.weight_offsets.resize(row_base[chunks]);
  t.indices.resize(entry_base[chunks]);
  std::vector<std::vector<float>> pools(chunks);
  parallel_range(chunks, 1, [&](size_t cb, size_t ce_) {
    for (size_t c = cb; c < ce_; ++c) {
      StencilTable& part = parts[c];
      detail::SharedWeights shared;
      for (size_t r = 0; r + 1 < part.offsets.size(); ++r) {
        const uint32_t b = part.offsets[r], e = part.offsets[r + 1];
        t.offsets[row_base[c] + r + 1] = uint32_t(entry_base[c] + e);
        t.weight_offsets[row_base[c] + r] = shared.add(pools[c], part.weights.data() + b, e - b);
      }
      std::copy(part.indices.begin(), part.indices.end(), t.indices.begin() + entry_base[c]);
      part = StencilTable();
    }
  });
  size_t pool_base = 0;
  for (size_t c = 0; c < chunks; ++c) {
    for (size_t r = row_base[c]; r < row_base[c + 1]; ++r)
      t.weight_offsets[r] += uint32_t(pool_base);
    t.weights.insert(t.weights.end(), pools[c].begin(), pools[c].end());
    pool_base += pools[c].size();
  }
  return t;
}

std::vector<float> fvar_refine_apply(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                                     const FVarState& ps, FVarState& cs, const float* values,
                                     int width) {
  fvar_child_state(o, P, a, ps, cs);
  std::vector<float> out(cs.value_count() * size_t(width));
  for_child_chunks(o, P, a, ps, cs, [&](size_t, size_t first, size_t) {
    return ApplySink{values, out.data(), width, cs.offsets[first]};
  });
  return out;
}

StencilTable fvar_limit(const SubdivOptions& o, const RefinedLevel& L, const Adj& a,
                        const FVarState& s) {
  const Mode m(o);
  const LevelRef l{L, a};
  LimitMasks masks(L);
  Weighted P, T1, T2;
  const Spans spans(L, a, s);
  const uint32_t* cv = s.corner_value.data();
  auto id = [&](uint32_t x) { return s.source.empty() ? x : s.source[x]; };
  std::vector<std::pair<uint32_t, uint32_t>> near;  // vertex -> its value, around v
  StencilTable t;
  uint32_t end_values[2];
  for (uint32_t v = 0; v < L.vertex_count(); ++v) {
    const uint32_t b = s.offsets[v], n = s.offsets[v + 1] - b;
    if (n == 0) continue;
    const bool linear = m.linear_all || a.vertex_edge_count(v) == 0;
    if (!linear && !(s.tag[b] & kFvMismatch)) {
      // The vertex's own limit mask, read through the values of its ring.
      near.clear();
      for (uint32_t i = a.vco[v]; i < a.vco[v + 1]; ++i) {
        const uint32_t c = a.vc[i];
        for (uint32_t k : {c, l.next(c), l.opposite_in_quad(c), l.prev(c)})
          near.emplace_back(L.face_vertices[k], cv[k]);
      }
      masks.compute(v, P, T1, T2);
      T1.terms.clear(), T2.terms.clear();
      for (auto& term : P.terms) {
        const uint32_t w = term.first;
        const auto it =
            std::find_if(near.begin(), near.end(), [w](const auto& p) { return p.first == w; });
        term.first = id(it->second);
      }
      P.emit(t);
      continue;
    }
    for (uint32_t i = 0; i < n; ++i) {
      if (linear || !(s.tag[b + i] & kFvCrease) || !spans.ends(v, b + i, end_values)) {
        emit(t, {{id(b + i), 1.0}});
      } else {
        emit(t, {{id(end_values[0]), 1.0 / 6.0},
                 {id(end_values[1]), 1.0 / 6.0},
                 {id(b + i), 2.0 / 3.0}});
      }
    }
  }
  return t;
}

}  // namespace refine_detail

std::vector<float> FaceVaryingLevels::values(const float* cage_values, int channels,
                                             int level) const {
  if (level < 0 || size_t(level) > stencils.size())
    throw std::out_of_range(fmt::format("face-varying level {} of {}", level, stencils.size()));
  std::vector<float> cur(cage_values, cage_values + value_counts[0] * size_t(channels)), next;
  for (int k = 0; k < level; ++k) {
    next.assign(stencils[size_t(k)].size() * size_t(channels), 0.0f);
    apply_stencils(stencils[size_t(k)], cur.data(), next.data(), channels);
    cur.swap(next);
  }
  return cur;
}

}  // namespace limn
