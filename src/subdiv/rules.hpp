// The Catmull-Clark rules as stencils (Sdc's masks with limn's expansion of face points into the
// parent level's vertices), shared by vertex refinement (refine.cpp) and face-varying channels
// (face_varying.cpp). Internal header of the subdiv layer.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <vector>

#include "refine_levels.hpp"

namespace limn::refine_detail {

inline constexpr float kInf = kInfiniteSharpness;

inline bool semi_sharp(float s) {
  return s > 0.0f && s < kInf;
}

inline float decrement(float s) {
  if (s <= 0.0f) return 0.0f;
  if (s >= kInf) return kInf;
  return s > 1.0f ? s - 1.0f : 0.0f;
}

enum Rule : uint8_t { kSmooth = 1, kDart = 2, kCrease = 4, kCorner = 8 };

inline Rule vertex_rule(float vertex_sharpness, int sharp_edges) {
  if (sharp(vertex_sharpness)) return kCorner;
  return sharp_edges > 2 ? kCorner : static_cast<Rule>(1 << sharp_edges);
}

// Sharpness of the child edges around a vertex (Sdc::Crease::SubdivideEdgeSharpnessesAround-
// Vertex): uniform decrements; Chaikin blends each semi-sharp edge with the mean of the others.
inline void child_edge_sharpness(const SubdivOptions& o, const float* parent, int n, float* child) {
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
inline float fractional_weight(const SubdivOptions& o, float pv, float cv, const float* pe,
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

// The stencil of every child point, from the rules. One instance per thread: it owns scratch.
// `Ids` names the points a stencil reads: VertexIds the parent level's vertices; a face-varying
// channel maps each corner, edge end and vertex to its value there instead (face_varying.cpp),
// so the same masks refine both.
template <class Ids>
class Rules {
 public:
  Rules(const SubdivOptions& o, const RefinedLevel& P, const Adj& a, const Selection& sel, Ids ids)
      : o_(o), P_(P), a_(a), l_{P, a}, sel_(sel), ids_(ids) {}

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
  // The stencils of the child points of face f, edge e and vertex v: kept until write() or
  // terms(); return the size.
  size_t face(uint32_t f) {
    acc_.clear();
    face_point(f, 1.0, acc_);
    return acc_.n;
  }
  size_t edge(uint32_t e) {
    acc_.clear();
    edge_point(e);
    return acc_.n;
  }
  size_t vertex(uint32_t v) {
    acc_.clear();
    vertex_point(v);
    return acc_.n;
  }
  const Terms& terms() const { return acc_; }
  void write(uint32_t* indices, float* weights) const {
    for (size_t k = 0; k < acc_.n; ++k)
      indices[k] = acc_.idx[k], weights[k] = static_cast<float>(acc_.w[k]);
  }

 private:
  void face_point(uint32_t f, double w, Terms& t) const {
    const uint32_t b = P_.face_offsets[f], n = P_.face_offsets[f + 1] - b;
    const double wi = w / double(n);
    for (uint32_t c = b; c < b + n; ++c) t.add(ids_.corner(c), wi);
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
        acc_.add(ids_.end(e, a), 0.375), acc_.add(ids_.end(e, b), 0.375);
        for (uint32_t c : {ca, cb}) {
          acc_.add(ids_.corner(l_.opposite_in_quad(c)), 0.0625);
          acc_.add(ids_.corner(l_.prev(c)), 0.0625);
        }
        return;
      }
    }
    acc_.add(ids_.end(e, a), blend * 0.5 + (1.0 - blend) * vw);
    acc_.add(ids_.end(e, b), blend * 0.5 + (1.0 - blend) * vw);
    for (uint32_t i = 0; i < nfe; ++i)
      face_point(a_.face_of(a_.ec[k0 + i]), fw * (1.0 - blend), acc_);
  }

  // The point at the other end of v's edge e.
  uint32_t neighbour(uint32_t e, uint32_t v) const { return ids_.end(e, l_.other_end(e, v)); }

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
      acc_.add(ids_.end(e, a), 0.5), acc_.add(ids_.end(e, b), 0.5);
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
      m.add(ids_.vertex(v), (dn - 2.0) / dn + 0.25 / dn);
      for (uint32_t k = 0; k < n; ++k) m.add(neighbour(a_.ve[k0 + k], v), 1.5 * w);
      for (uint32_t i = 0; i < nfaces; ++i)
        m.add(ids_.corner(l_.opposite_in_quad(a_.vc[s0 + i])), 0.25 * w);
      return;
    }
    m.add(ids_.vertex(v), (dn - 2.0) / dn);
    for (uint32_t k = 0; k < n; ++k) m.add(neighbour(a_.ve[k0 + k], v), w);
    for (uint32_t i = 0; i < nfaces; ++i) face_point(a_.face_of(a_.vc[s0 + i]), w, m);
  }

  void sharp_vertex(uint32_t v, Rule r, const float* es, Terms& m) const {
    if (r != kCrease) {
      m.add(ids_.vertex(v), 1.0);
      return;
    }
    const uint32_t k0 = a_.veo[v], n = a_.veo[v + 1] - k0;
    m.add(ids_.vertex(v), 0.75);
    for (uint32_t k = 0; k < n; ++k)
      if (sharp(es[k])) m.add(neighbour(a_.ve[k0 + k], v), 0.125);
  }

  void vertex_point(uint32_t v) {
    const uint32_t k0 = a_.veo[v], n = a_.veo[v + 1] - k0;
    if (n == 0) {  // on no face: stays where it is (its ring is empty)
      acc_.add(ids_.vertex(v), 1.0);
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
  Ids ids_;
  Terms acc_, cmask_;
  std::vector<float> pe_, ce_;
};

// The points a vertex stencil reads: the parent level's vertices.
struct VertexIds {
  const uint32_t* face_vertices;
  uint32_t corner(uint32_t c) const { return face_vertices[c]; }
  uint32_t end(uint32_t, uint32_t w) const { return w; }
  uint32_t vertex(uint32_t v) const { return v; }
};

struct VertexRules : Rules<VertexIds> {
  VertexRules(const SubdivOptions& o, const RefinedLevel& P, const Adj& a, const Selection& sel)
      : Rules<VertexIds>(o, P, a, sel, VertexIds{P.face_vertices.data()}) {}
};

}  // namespace limn::refine_detail
