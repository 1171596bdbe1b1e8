// Watertight tessellation of patch tables (see the header for the idea).
//
// Coordinates: every ptex face is an R x R integer grid, R = factor * 2^max_depth, so every
// sample of every patch has integer coordinates. A sample is keyed where it lies on the cage:
// inside a ptex face by (ptex, i, j); on a cage edge by the edge (its two vertex ids) and its
// position along it (0..2R from the lower id: a quad's ptex spans the edge with R units, a
// non-quad's corner ptex spans half of it); on a spoke of a non-quad (edge point -> face point)
// by the ptex on its left and the position from the edge point; at cage vertices and face
// centres by their ids. Lines (rows and columns inside a ptex, cage edges, spokes) collect the
// samples every patch edge on them contributes; each patch edge then takes all of them.
#include "limn/subdiv/tessellate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace limn {

namespace {

struct Key {
  uint64_t hi = 0, lo = 0;
  bool operator==(const Key& o) const { return hi == o.hi && lo == o.lo; }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    uint64_t h = k.hi * 0x9e3779b97f4a7c15ull ^ (k.lo + 0x632be59bd9b4e019ull + (k.hi << 6));
    h ^= h >> 29;
    return size_t(h * 0xbf58476d1ce4e5b9ull);
  }
};

enum : uint64_t { kRow = 0, kCol = 1, kEdge = 2, kSpoke = 3, kVertex = 4, kFace = 5, kInside = 6 };
Key make(uint64_t type, uint64_t id, uint64_t q) {
  return {type << 58 | id, q};
}

class Tessellator {
 public:
  Tessellator(const Mesh& cage, const PatchTable& t, std::span<const float> pts,
              const TessellateOptions& o)
      : cage_(cage), t_(t), pts_(pts), o_(o) {}
  Mesh run();
  // Patch i of the table: its regular patches first, then its end caps.
  const PatchParam& param(size_t i) const {
    const size_t nr = t_.regular_params.size();
    return i < nr ? t_.regular_params[i] : t_.gregory_params[i - nr];
  }
  void evaluate(std::vector<uint32_t> tris, Mesh& out) const;
  std::vector<std::array<int, 4>> edge_rates(int n) const;
  void edge_samples(const std::vector<std::array<int, 4>>& rate, std::vector<uint32_t>& edge_line,
                    std::vector<std::pair<uint32_t, int64_t>>& samples) const;

 private:
  struct Line {
    Key key;     // line key (lo = 0)
    int64_t q0;  // line parameter at the patch edge's start
    int64_t dq;  // per ptex grid unit along the patch edge (+1 / -1, or +-2 on quad cage edges)
  };
  struct Face {  // ptex face -> cage face and corner
    uint32_t face, corner, size;
  };
  Line ptex_boundary(uint32_t p, int e, int64_t t) const;
  Key boundary_point(const Key& line, int64_t q) const;
  Key point(uint32_t p, int64_t i, int64_t j) const;
  Line patch_edge(const PatchParam& pp, int e, int64_t& length) const;
  uint32_t vertex(const Key& k, uint32_t patch, float s, float t);
  // A vertex as one patch sees it: where along a patch edge (sorting), and its (s, t) there.
  struct Sample {
    double a;
    uint32_t v;
    float s, t;
  };
  // Appends triangle (x, y, z) of patch i, and its corners' (s, t) in that patch (for UVs).
  void triangle(std::vector<uint32_t>& tris, uint32_t i, const Sample& x, const Sample& y,
                const Sample& z) {
    tris.insert(tris.end(), {x.v, y.v, z.v});
    tri_patch_.push_back(i);
    corner_st_.insert(corner_st_.end(), {x.s, x.t, y.s, y.t, z.s, z.t});
  }
  void face_varying(Mesh& out) const;
  std::vector<uint32_t> tri_patch_;
  std::vector<float> corner_st_;

  const Mesh& cage_;
  const PatchTable& t_;
  std::span<const float> pts_;
  TessellateOptions o_;
  int64_t R_ = 0;
  std::vector<Face> ptex_;
  std::unordered_map<Key, uint32_t, KeyHash> vertices_;
  std::vector<PatchCoord> coords_;  // one per output vertex
};

// The line of ptex face p's edge e and the line parameter at t (0..R from ptex corner e).
Tessellator::Line Tessellator::ptex_boundary(uint32_t p, int e, int64_t t) const {
  const Face& f = ptex_[p];
  const uint32_t* v = cage_.face_vertices.data() + cage_.face_offsets[f.face];
  auto edge = [&](uint32_t a, uint32_t b, int64_t q_from_a, int64_t per_t) {
    const uint32_t lo = std::min(a, b), hi = std::max(a, b);
    Line l;
    l.key = make(kEdge, uint64_t(lo) << 28 | hi, 0);
    l.q0 = a < b ? q_from_a : 2 * R_ - q_from_a;
    l.dq = a < b ? per_t : -per_t;
    return l;
  };
  if (f.size == 4) return edge(v[e], v[(e + 1) % 4], 2 * t, 2);
  const uint32_t n = f.size, k = f.corner;
  const uint32_t ck = v[k], next = v[(k + 1) % n], prev = v[(k + n - 1) % n];
  switch (e) {
    case 0:
      return edge(ck, next, t, 1);
    case 3:
      return edge(prev, ck, R_ + t, 1);
    case 1:
      return {make(kSpoke, p, 0), t, 1};
    default: {
      const uint32_t pk = k == 0 ? p + n - 1 : p - 1;  // the spoke is the previous corner's
      return {make(kSpoke, pk, 0), R_ - t, -1};
    }
  }
}

// The canonical key of the point at parameter q of a cage-edge or spoke line.
Key Tessellator::boundary_point(const Key& line, int64_t q) const {
  const uint64_t type = line.hi >> 58, id = line.hi & ((1ull << 58) - 1);
  if (type == kEdge) {
    if (q <= 0) return make(kVertex, id >> 28, 0);
    if (q >= 2 * R_) return make(kVertex, id & ((1u << 28) - 1), 0);
    return {line.hi, uint64_t(q)};
  }
  // A spoke of ptex p runs from the midpoint of its corner's leading edge to the face centre.
  const Face& f = ptex_[id];
  if (q >= R_) return make(kFace, f.face, 0);
  if (q <= 0)
    return boundary_point(ptex_boundary(uint32_t(id), 0, 0).key,
                          ptex_boundary(uint32_t(id), 0, R_).q0);
  return {line.hi, uint64_t(q)};
}

Key Tessellator::point(uint32_t p, int64_t i, int64_t j) const {
  if (i > 0 && i < R_ && j > 0 && j < R_) return make(kInside, p, uint64_t(i) << 32 | uint64_t(j));
  int e;
  int64_t t;
  if (j == 0)
    e = 0, t = i;
  else if (i == R_)
    e = 1, t = j;
  else if (j == R_)
    e = 2, t = R_ - i;
  else
    e = 3, t = R_ - j;
  const Line l = ptex_boundary(p, e, t);
  return boundary_point(l.key, l.q0);
}

// Ptex grid coordinates (resolution R) of the corner where a patch's edge e starts.
void edge_start(const PatchParam& pp, int e, int64_t R, int64_t& i, int64_t& j) {
  const int64_t size = R >> pp.depth;
  i = pp.u * size + (e == 1 || e == 2 ? size : 0);
  j = pp.v * size + (e >= 2 ? size : 0);
}

// The line under edge e of a patch, with the parameter at the edge's start and its step per
// ptex grid unit; `length` gets the edge's length in grid units.
Tessellator::Line Tessellator::patch_edge(const PatchParam& pp, int e, int64_t& length) const {
  length = R_ >> pp.depth;
  int64_t i, j;
  edge_start(pp, e, R_, i, j);
  switch (e) {
    case 0:
      if (j > 0) return {make(kRow, uint64_t(pp.ptex) << 24 | uint64_t(j), 0), i, 1};
      return ptex_boundary(pp.ptex, 0, i);
    case 1:
      if (i < R_) return {make(kCol, uint64_t(pp.ptex) << 24 | uint64_t(i), 0), j, 1};
      return ptex_boundary(pp.ptex, 1, j);
    case 2:
      if (j < R_) return {make(kRow, uint64_t(pp.ptex) << 24 | uint64_t(j), 0), i, -1};
      return ptex_boundary(pp.ptex, 2, R_ - i);
    default:
      if (i > 0) return {make(kCol, uint64_t(pp.ptex) << 24 | uint64_t(i), 0), j, -1};
      return ptex_boundary(pp.ptex, 3, R_ - j);
  }
}

uint32_t Tessellator::vertex(const Key& k, uint32_t patch, float s, float t) {
  const auto [it, fresh] = vertices_.try_emplace(k, uint32_t(coords_.size()));
  if (fresh) coords_.push_back({patch, s, t});
  return it->second;
}

// Segments per patch edge: `n` (the factor), or from the edge's length on screen (its corners
// projected; the next power of two of length / pixels_per_segment, 1-64).
std::vector<std::array<int, 4>> Tessellator::edge_rates(int n) const {
  const size_t np = t_.patch_count();
  std::vector<std::array<int, 4>> rate(np, {n, n, n, n});
  if (!o_.camera) return rate;
  std::vector<PatchCoord> corners;
  for (uint32_t i = 0; i < np; ++i)
    for (int c = 0; c < 4; ++c) corners.push_back({i, float(c == 1 || c == 2), float(c >= 2)});
  std::vector<float> cp(3 * corners.size());
  evaluate_patches(t_, pts_, corners, cp.data());
  for (size_t i = 0; i < np; ++i)
    for (int e = 0; e < 4; ++e) {
      double x0, y0, x1, y1;
      const float* a = &cp[3 * (4 * i + size_t(e))];
      const float* b = &cp[3 * (4 * i + size_t(e + 1) % 4)];
      int r = 64;
      if (o_.camera->project(a, x0, y0) && o_.camera->project(b, x1, y1)) {
        const double segs = std::hypot(x1 - x0, y1 - y0) / o_.pixels_per_segment;
        r = 1;
        while (r < 64 && r < segs) r *= 2;
      }
      rate[i][size_t(e)] = r;
    }
  return rate;
}

// Every patch edge's samples on its line (edge_line: per patch edge, its line's id), as (line,
// parameter) pairs, sorted and deduplicated.
void Tessellator::edge_samples(const std::vector<std::array<int, 4>>& rate,
                               std::vector<uint32_t>& edge_line,
                               std::vector<std::pair<uint32_t, int64_t>>& samples) const {
  const size_t np = t_.patch_count();
  std::unordered_map<Key, uint32_t, KeyHash> line_of;
  line_of.reserve(3 * np);
  for (size_t i = 0; i < np; ++i)
    for (int e = 0; e < 4; ++e) {
      int64_t len;
      const Line l = patch_edge(param(i), e, len);
      const uint32_t id = line_of.try_emplace(l.key, uint32_t(line_of.size())).first->second;
      edge_line[4 * i + size_t(e)] = id;
      const int m = rate[i][size_t(e)];
      for (int k = 0; k <= m; ++k) samples.emplace_back(id, l.q0 + l.dq * (len * k / m));
    }
  std::sort(samples.begin(), samples.end());
  samples.erase(std::unique(samples.begin(), samples.end()), samples.end());
}

// The mesh's vertices evaluated once each, with normals and depth colours as asked; `tris` its
// triangles.
void Tessellator::evaluate(std::vector<uint32_t> tris, Mesh& out) const {
  const size_t nv = coords_.size();
  out.positions.resize(3 * nv);
  std::vector<float> du(3 * nv), dv(3 * nv);
  evaluate_patches(t_, pts_, coords_, out.positions.data(), du.data(), dv.data());
  out.face_vertices = std::move(tris);
  out.face_offsets.resize(out.face_vertices.size() / 3 + 1);
  for (size_t f = 0; f < out.face_offsets.size(); ++f) out.face_offsets[f] = uint32_t(3 * f);
  if (o_.normals) {
    out.normals = normals_from_tangents(du, dv);
    out.normal_indices = out.face_vertices;
  }
  face_varying(out);
  if (o_.depth_colors) {
    out.colors.resize(4 * nv);
    for (size_t v = 0; v < nv; ++v) {
      depth_color(param(coords_[v].patch).level, &out.colors[4 * v]);
      out.colors[4 * v + 3] = 1.0f;
    }
  }
}

// The cage's UVs on every triangle corner, from the corner's place in its own patch (so a
// vertex on a UV seam takes each side's value); equal values at a vertex are stored once. Smooth
// channels go through their face-varying patches (built with the default patch options).
void Tessellator::face_varying(Mesh& out) const {
  if (cage_.uv_indices.empty()) return;
  const size_t nc = out.face_vertices.size();
  std::vector<PtexCoord> at(nc);
  for (size_t c = 0; c < nc; ++c)
    at[c] = ptex_coord(t_, {tri_patch_[c / 3], corner_st_[2 * c], corner_st_[2 * c + 1]});
  std::vector<float> uv(2 * nc);
  const FaceVaryingInput in{cage_.uv_indices, cage_.uvs.size() / 2};
  PatchOptions po;
  po.subdiv = t_.options;
  const FaceVaryingPatches patches = build_face_varying_patches(cage_, t_, in, po);
  evaluate_face_varying(cage_, in, patches, cage_.uvs.data(), 2, at, uv.data());
  // One value per distinct UV at each vertex (a handful at most: seams).
  std::vector<std::vector<uint32_t>> at_vertex(out.vertex_count());
  out.uv_indices.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    std::vector<uint32_t>& ids = at_vertex[out.face_vertices[c]];
    uint32_t id = UINT32_MAX;
    // Patches on both sides of an edge compute its points' UVs apart: equal to round-off.
    for (uint32_t x : ids)
      if (std::fabs(out.uvs[2 * x] - uv[2 * c]) <= 1e-6f &&
          std::fabs(out.uvs[2 * x + 1] - uv[2 * c + 1]) <= 1e-6f)
        id = x;
    if (id == UINT32_MAX) {
      id = uint32_t(out.uvs.size() / 2);
      out.uvs.insert(out.uvs.end(), {uv[2 * c], uv[2 * c + 1]});
      ids.push_back(id);
    }
    out.uv_indices[c] = id;
  }
}

Mesh Tessellator::run() {
  const bool screen = o_.camera != nullptr;
  const int n = screen ? 64 : o_.factor;  // screen-space rates are powers of two up to 64
  if (!screen && (n < 1 || n > 64))
    throw InputError(fmt::format("tessellate: factor {} out of range (1-64)", n));
  if (screen && !(o_.pixels_per_segment > 0))
    throw InputError(
        fmt::format("tessellate: {} pixels per segment must be positive", o_.pixels_per_segment));
  if (cage_.vertex_count() >= (1u << 28))
    throw InputError("tessellate: the cage has too many vertices (2^28 at most)");
  int max_depth = 0;
  const size_t np = t_.patch_count();
  for (size_t i = 0; i < np; ++i) max_depth = std::max<int>(max_depth, param(i).depth);
  R_ = int64_t(n) << max_depth;
  for (uint32_t f = 0; f < cage_.face_count(); ++f) {
    const uint32_t size = cage_.face_size(f);
    for (uint32_t c = 0; c < (size == 4 ? 1 : size); ++c) ptex_.push_back({f, c, size});
  }
  if (ptex_.size() != t_.ptex_count) throw InputError("tessellate: the table is not this cage's");

  // Segments per patch edge: the factor, or from the edge's length on screen.
  const std::vector<std::array<int, 4>> rate = edge_rates(n);

  // Pass 1: every patch edge's own samples on its line, as (line, parameter) pairs in one flat
  // array; sorted and deduplicated, each line's samples are one range of it.
  std::vector<uint32_t> edge_line(4 * np);
  std::vector<std::pair<uint32_t, int64_t>> samples;
  edge_samples(rate, edge_line, samples);
  auto line_begin = [&](uint32_t id, int64_t q) {
    return std::lower_bound(samples.begin(), samples.end(), std::make_pair(id, q));
  };
  vertices_.reserve(samples.size());

  // Pass 2: vertices and triangles per patch.
  Mesh out;
  std::vector<uint32_t> tris;
  std::vector<uint32_t> inner;
  std::vector<Sample> side[4];  // by position along the edge (0..1)
  static constexpr float kCs[4] = {0, 1, 1, 0}, kCt[4] = {0, 0, 1, 1};
  for (uint32_t i = 0; i < np; ++i) {
    const PatchParam& pp = param(i);
    for (int e = 0; e < 4; ++e) {
      int64_t len;
      const Line l = patch_edge(pp, e, len);
      const uint32_t id = edge_line[4 * size_t(i) + size_t(e)];
      const int64_t qa = l.q0, qb = l.q0 + l.dq * len;
      const auto lo = line_begin(id, std::min(qa, qb)), hi = line_begin(id, std::max(qa, qb) + 1);
      side[e].clear();
      const uint64_t type = l.key.hi >> 58;
      for (auto s_it = lo; s_it != hi; ++s_it) {
        const int64_t* it = &s_it->second;
        const double a = double(*it - qa) / double(qb - qa);  // 0 at the start corner
        const float s = float(kCs[e] + a * (kCs[(e + 1) % 4] - kCs[e]));
        const float t = float(kCt[e] + a * (kCt[(e + 1) % 4] - kCt[e]));
        Key k;
        if (type == kRow || type == kCol) {
          const int64_t along = (*it - l.q0) * l.dq;  // grid units from the start corner
          int64_t i0, j0;
          edge_start(pp, e, R_, i0, j0);
          static constexpr int64_t kDi[4] = {1, 0, -1, 0}, kDj[4] = {0, 1, 0, -1};
          k = point(pp.ptex, i0 + kDi[e] * along, j0 + kDj[e] * along);
        } else {
          k = boundary_point(l.key, *it);
        }
        side[e].push_back({a, vertex(k, i, s, t), s, t});
      }
      std::sort(side[e].begin(), side[e].end(),
                [](const Sample& x, const Sample& y) { return x.a < y.a; });
    }
    // Interior grid of the patch (as fine as its finer opposite edges), then the four
    // stitching strips.
    const int nu = std::max(rate[i][0], rate[i][2]), nv = std::max(rate[i][1], rate[i][3]);
    const size_t w = size_t(nu) + 1;
    inner.assign(w * (size_t(nv) + 1), 0);
    for (int y = 1; y < nv; ++y)
      for (int x = 1; x < nu; ++x) {
        inner[size_t(y) * w + size_t(x)] = uint32_t(coords_.size());
        coords_.push_back({i, float(x) / float(nu), float(y) / float(nv)});
      }
    auto grid = [&](int x, int y) {
      return Sample{0, inner[size_t(y) * w + size_t(x)], float(x) / float(nu),
                    float(y) / float(nv)};
    };
    for (int y = 1; y + 1 < nv; ++y)
      for (int x = 1; x + 1 < nu; ++x) {
        const Sample a = grid(x, y), b = grid(x + 1, y), c = grid(x + 1, y + 1), d = grid(x, y + 1);
        triangle(tris, i, a, b, c);
        triangle(tris, i, a, c, d);
      }
    if (nu < 2 || nv < 2) {  // no interior grid: fan the boundary around the centre
      const Sample centre{0, uint32_t(coords_.size()), 0.5f, 0.5f};
      coords_.push_back({i, 0.5f, 0.5f});
      for (int e = 0; e < 4; ++e)
        for (size_t k = 0; k + 1 < side[e].size(); ++k)
          triangle(tris, i, side[e][k], side[e][k + 1], centre);
      continue;
    }
    for (int e = 0; e < 4; ++e) {
      // The inner row along edge e, from its start corner's side to its end's.
      std::vector<Sample> row;
      const int m = e % 2 == 0 ? nu : nv;
      for (int k = 1; k < m; ++k) {
        int x = 0, y = 0;
        switch (e) {
          case 0:
            x = k, y = 1;
            break;
          case 1:
            x = nu - 1, y = k;
            break;
          case 2:
            x = nu - k, y = nv - 1;
            break;
          default:
            x = 1, y = nv - k;
            break;
        }
        Sample r = grid(x, y);
        r.a = double(k) / m;
        row.push_back(r);
      }
      const auto& b = side[e];
      size_t p = 0, q = 0;
      while (p + 1 < b.size() || q + 1 < row.size()) {
        const bool advance_b =
            q + 1 >= row.size() || (p + 1 < b.size() && b[p + 1].a <= row[q + 1].a);
        if (advance_b) {
          triangle(tris, i, b[p], b[p + 1], row[q]);
          ++p;
        } else {
          triangle(tris, i, b[p], row[q + 1], row[q]);
          ++q;
        }
      }
    }
  }

  // Evaluate every vertex once.
  evaluate(std::move(tris), out);
  return out;
}

}  // namespace

void depth_color(int level, float rgb[3]) {
  // A short perceptual ramp: dark blue, blue, cyan, green, yellow, orange, red, magenta.
  static constexpr float kRamp[8][3] = {
      {0.10f, 0.15f, 0.45f}, {0.15f, 0.35f, 0.85f}, {0.10f, 0.70f, 0.85f}, {0.25f, 0.75f, 0.30f},
      {0.90f, 0.85f, 0.20f}, {0.95f, 0.55f, 0.15f}, {0.85f, 0.20f, 0.15f}, {0.75f, 0.20f, 0.65f}};
  const int i = std::clamp(level, 0, 7);
  for (int c = 0; c < 3; ++c) rgb[c] = kRamp[i][c];
}

Mesh tessellate_patches(const Mesh& cage, const PatchTable& table, std::span<const float> points,
                        const TessellateOptions& options) {
  return Tessellator(cage, table, points, options).run();
}

}  // namespace limn
