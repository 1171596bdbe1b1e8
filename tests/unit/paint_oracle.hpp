// Independent references for the paint tests: test meshes, a box-triangle test by clipping (not
// the separating-axis test the library uses), closest points by projection and edge search (not
// Voronoi regions), the tag table restated from the file format, and a map of the texture's cells.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/paint/texture.hpp"

namespace limn::test {

using P3 = std::array<double, 3>;

inline P3 sub(P3 a, P3 b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline double dot3(P3 a, P3 b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline P3 cross3(P3 a, P3 b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm3(P3 a) {
  return std::sqrt(dot3(a, a));
}

/// A UV sphere: `rings` x `segments`, outward-facing triangles.
inline Mesh uv_sphere(double radius, int rings, int segments, P3 centre = {0, 0, 0}) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  m.add_vertex(float(centre[0]), float(centre[1]), float(centre[2] + radius));
  for (int i = 1; i < rings; ++i) {
    const double th = pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * pi * j / segments;
      m.add_vertex(float(centre[0] + radius * std::sin(th) * std::cos(ph)),
                   float(centre[1] + radius * std::sin(th) * std::sin(ph)),
                   float(centre[2] + radius * std::cos(th)));
    }
  }
  const uint32_t south =
      m.add_vertex(float(centre[0]), float(centre[1]), float(centre[2] - radius));
  auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) m.add_face({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.add_face({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.add_face({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j)
    m.add_face({ring(rings - 1, j), south, ring(rings - 1, j + 1)});
  return m;
}

/// A square sheet at height z over [x0,x1] x [y0,y1], n x n quads split into triangles, facing
/// +z (up) or -z, with uvs (x, y) mapped to [0,1].
inline Mesh sheet(double x0, double x1, double y0, double y1, double z, int n, bool up) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.add_vertex(float(x0 + (x1 - x0) * i / n), float(y0 + (y1 - y0) * j / n), float(z));
      m.uvs.push_back(float(i) / float(n));
      m.uvs.push_back(float(j) / float(n));
    }
  auto v = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (up) {
        m.add_face({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
        m.add_face({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
      } else {
        m.add_face({v(i, j), v(i + 1, j + 1), v(i + 1, j)});
        m.add_face({v(i, j), v(i, j + 1), v(i + 1, j + 1)});
      }
    }
  m.uv_indices = m.face_vertices;
  return m;
}

/// Concatenates meshes (uvs dropped unless every part has them).
inline Mesh merge(const std::vector<Mesh>& parts) {
  Mesh m;
  bool uvs = true;
  for (const Mesh& p : parts) uvs = uvs && !p.uvs.empty();
  for (const Mesh& p : parts) {
    const uint32_t base = uint32_t(m.vertex_count()), ubase = uint32_t(m.uvs.size() / 2);
    m.positions.insert(m.positions.end(), p.positions.begin(), p.positions.end());
    for (size_t f = 0; f < p.face_count(); ++f) {
      std::vector<uint32_t> v;
      for (uint32_t x : p.face(f)) v.push_back(x + base);
      m.add_face(v);
    }
    if (uvs) {
      m.uvs.insert(m.uvs.end(), p.uvs.begin(), p.uvs.end());
      for (uint32_t x : p.uv_indices) m.uv_indices.push_back(x + ubase);
    }
  }
  return m;
}

/// Fanned triangles of a mesh, in the order PaintSurface numbers them.
struct Tri {
  P3 a, b, c;
  P3 n;  // unit normal, or 0
};
inline std::vector<Tri> triangles(const Mesh& m) {
  std::vector<Tri> out;
  auto p = [&](uint32_t v) {
    return P3{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
  };
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (size_t i = 1; i + 1 < v.size(); ++i) {
      Tri t{p(v[0]), p(v[i]), p(v[i + 1]), {0, 0, 0}};
      const P3 n = cross3(sub(t.b, t.a), sub(t.c, t.a));
      const double l = norm3(n);
      if (l > 0) t.n = {n[0] / l, n[1] / l, n[2] / l};
      out.push_back(t);
    }
  }
  return out;
}

/// Does the triangle meet the closed box [lo - slack, hi + slack]? Sutherland-Hodgman clipping of
/// the triangle against the six planes: it meets the box iff something survives.
inline bool tri_meets_box(const Tri& t, P3 lo, P3 hi, double slack) {
  std::vector<P3> poly = {t.a, t.b, t.c};
  for (int axis = 0; axis < 3 && !poly.empty(); ++axis)
    for (int s = 0; s < 2 && !poly.empty(); ++s) {
      const double bound = s ? hi[size_t(axis)] + slack : lo[size_t(axis)] - slack;
      auto inside = [&](const P3& p) {
        return s ? p[size_t(axis)] <= bound : p[size_t(axis)] >= bound;
      };
      std::vector<P3> out;
      for (size_t i = 0; i < poly.size(); ++i) {
        const P3 a = poly[i], b = poly[(i + 1) % poly.size()];
        const bool ia = inside(a), ib = inside(b);
        if (ia) out.push_back(a);
        if (ia != ib) {
          const double u = (bound - a[size_t(axis)]) / (b[size_t(axis)] - a[size_t(axis)]);
          out.push_back(
              {a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])});
        }
      }
      poly = out;
    }
  return !poly.empty();
}

inline P3 closest_on_segment(P3 p, P3 a, P3 b) {
  const P3 ab = sub(b, a);
  const double l2 = dot3(ab, ab);
  const double u = l2 > 0 ? std::clamp(dot3(sub(p, a), ab) / l2, 0.0, 1.0) : 0.0;
  return {a[0] + u * ab[0], a[1] + u * ab[1], a[2] + u * ab[2]};
}

/// Closest point on a triangle: the plane projection when it falls inside (barycentric signs),
/// else the best of the three edges.
inline P3 closest_on_tri(P3 p, const Tri& t) {
  const P3 n = cross3(sub(t.b, t.a), sub(t.c, t.a));
  const double nn = dot3(n, n);
  if (nn > 0) {
    const double d = dot3(sub(p, t.a), n) / nn;
    const P3 q = {p[0] - d * n[0], p[1] - d * n[1], p[2] - d * n[2]};
    const double w0 = dot3(cross3(sub(t.b, q), sub(t.c, q)), n);
    const double w1 = dot3(cross3(sub(t.c, q), sub(t.a, q)), n);
    const double w2 = dot3(cross3(sub(t.a, q), sub(t.b, q)), n);
    if (w0 >= 0 && w1 >= 0 && w2 >= 0) return q;
  }
  P3 best = closest_on_segment(p, t.a, t.b);
  for (const P3& c : {closest_on_segment(p, t.b, t.c), closest_on_segment(p, t.c, t.a)})
    if (norm3(sub(c, p)) < norm3(sub(best, p))) best = c;
  return best;
}

/// The tag directions as the file format documents them (1-6 axes, 7-14 diagonals, x slowest).
inline P3 tag_dir(int tag) {
  if (tag >= 1 && tag <= 6) {
    P3 d{0, 0, 0};
    d[size_t((tag - 1) / 2)] = (tag % 2) ? 1.0 : -1.0;
    return d;
  }
  if (tag >= 7 && tag <= 14) {
    const int i = tag - 7;
    const double s = 1 / std::sqrt(3.0);
    return {(i & 4) ? -s : s, (i & 2) ? -s : s, (i & 1) ? -s : s};
  }
  return {0, 0, 0};
}
/// The sample of a cell with `tag` that a lookup with normal n reads (0 front, 1 back).
inline int side_of(int tag, const float* n) {
  if (!n || tag == 0) return 0;
  const P3 d = tag_dir(tag);
  return d[0] * n[0] + d[1] * n[1] + d[2] * n[2] >= 0 ? 0 : 1;
}

/// The texture's leaf cells as a plain map (built from for_each_sample).
struct CellMap {
  struct Cell {
    int tag = 0;
    bool dbl = false;
    Rgba8 s[2] = {0, 0};
  };
  std::map<std::tuple<int, uint32_t, uint32_t, uint32_t>, Cell> cells;
  /// Every cell holding a finer leaf (a leaf's ancestors, the root's cell at level 0 included).
  std::set<std::tuple<int, uint32_t, uint32_t, uint32_t>> above;
  const OctreeTexture* t = nullptr;

  explicit CellMap(const OctreeTexture& tex) : t(&tex) {
    tex.for_each_sample([&](const OctreeSample& s) {
      Cell& c = cells[{s.level, s.x, s.y, s.z}];
      c.tag = s.tag;
      c.s[s.side] = s.color;
      if (s.side == 1) c.dbl = true;
      for (int l = 0; l < s.level; ++l)
        above.insert({l, s.x >> (s.level - l), s.y >> (s.level - l), s.z >> (s.level - l)});
    });
  }
  /// The level of the cell holding (x, y, z) (level 16) that is a leaf or holds no leaf at all.
  int cell_level(uint32_t x, uint32_t y, uint32_t z) const {
    int l = 0;
    while (l < 16 && above.count({l, x >> (16 - l), y >> (16 - l), z >> (16 - l)})) ++l;
    return l;
  }
  /// The leaf holding integer point (x, y, z) at level 16, by trying every level: nullptr when
  /// none. `level` receives the leaf's level.
  const Cell* leaf(uint32_t x, uint32_t y, uint32_t z, int* level = nullptr) const {
    const Cell* found = nullptr;
    for (int l = 1; l <= 16; ++l) {
      auto it = cells.find({l, x >> (16 - l), y >> (16 - l), z >> (16 - l)});
      if (it == cells.end()) continue;
      if (found) return nullptr;  // two leaves on one path: the tree is broken
      found = &it->second;
      if (level) *level = l;
    }
    return found;
  }
  /// Reference nearest lookup at a world point.
  bool nearest(const float p[3], const float* n, Rgba8& out) const {
    out = t->background();
    uint32_t xyz[3];
    // The documented mapping: level-16 cell floor((p - origin) * (65536 / size)).
    for (int k = 0; k < 3; ++k) {
      const double v = (double(p[k]) - double(t->origin()[k])) * (65536.0 / double(t->size()));
      if (!(v >= 0 && v < 65536.0)) return false;
      xyz[k] = uint32_t(v);
    }
    const Cell* c = leaf(xyz[0], xyz[1], xyz[2]);
    if (!c) return false;
    const int side = side_of(c->tag, n);
    if (side && !c->dbl) return false;
    out = c->s[side];
    return true;
  }
  /// Reference trilinear lookup: the 8 cells around p at a level, each read as a nearest lookup
  /// at its centre, premultiplied, weights renormalised over the cells with a sample facing n.
  /// The level starts at the cell holding p that is a leaf or holds none and goes down to the
  /// deepest leaf whose sample a tap read, until no tap reads a deeper one; when no leaf holds p,
  /// also one level finer while a tap's cell holds finer leaves. False when no tap has a sample.
  bool filtered(const float p[3], const float* n, float out[4]) const {
    uint32_t xyz[3];
    double u[3];
    for (int k = 0; k < 3; ++k) {
      const double v = (double(p[k]) - double(t->origin()[k])) * (65536.0 / double(t->size()));
      if (!(v >= 0 && v < 65536.0)) return false;
      xyz[k] = uint32_t(v);
      u[k] = v / 65536.0;
    }
    int level = 0;
    const bool at_leaf = leaf(xyz[0], xyz[1], xyz[2], &level) != nullptr;
    if (!at_leaf) level = cell_level(xyz[0], xyz[1], xyz[2]);
    double acc[5] = {0, 0, 0, 0, 0};
    for (;;) {
      std::fill(acc, acc + 5, 0.0);
      int deepest = level;
      bool finer = false;
      taps(u, level, n, acc, deepest, &finer);
      if (deepest > level) {
        level = deepest;
      } else if (!at_leaf && finer && level < 16) {
        ++level;
      } else {
        break;
      }
    }
    if (!(acc[4] > 0)) return false;
    for (int k = 0; k < 3; ++k) out[k] = acc[3] > 0 ? float(acc[k] / acc[3]) : 0.0f;
    out[3] = float(acc[3] / acc[4]);
    return true;
  }
  /// The 8 taps of `filtered` at `level`; `deepest` rises to the level of any deeper leaf whose
  /// sample a tap read; `finer` (may be null) is set when a tap's cell holds finer leaves.
  void taps(const double u[3], int level, const float* n, double acc[5], int& deepest,
            bool* finer = nullptr) const {
    const double n_cells = double(1u << level);
    for (int corner = 0; corner < 8; ++corner) {
      double w = 1;
      int64_t ic[3];
      for (int k = 0; k < 3; ++k) {
        const double g = u[k] * n_cells - 0.5, f = std::floor(g);
        const int d = corner >> k & 1;
        ic[k] = int64_t(f) + d;
        w *= d ? g - f : 1 - (g - f);
      }
      bool inside = true;
      for (int k = 0; k < 3; ++k) inside = inside && ic[k] >= 0 && ic[k] < int64_t(n_cells);
      if (!inside || w <= 0) continue;
      const int sh = 16 - level;
      const uint32_t half = sh ? 1u << (sh - 1) : 0;
      int at = 0;
      const uint32_t x = (uint32_t(ic[0]) << sh) + half, y = (uint32_t(ic[1]) << sh) + half,
                     z = (uint32_t(ic[2]) << sh) + half;
      if (finer && above.count({level, x >> sh, y >> sh, z >> sh})) *finer = true;
      const Cell* c = leaf(x, y, z, &at);
      if (!c) continue;
      const int side = side_of(c->tag, n);
      if (side && !c->dbl) continue;
      deepest = std::max(deepest, at);
      const Rgba8 col = c->s[side];
      const double a = channel(col, 3) / 255.0;
      for (int k = 0; k < 3; ++k) acc[k] += w * a * channel(col, k) / 255.0;
      acc[3] += w * a, acc[4] += w;
    }
  }
};

/// A point uniformly inside triangle t (u, v uniform in [0,1]).
inline P3 point_in(const Tri& t, double u, double v) {
  if (u + v > 1) u = 1 - u, v = 1 - v;
  return {t.a[0] + u * (t.b[0] - t.a[0]) + v * (t.c[0] - t.a[0]),
          t.a[1] + u * (t.b[1] - t.a[1]) + v * (t.c[1] - t.a[1]),
          t.a[2] + u * (t.b[2] - t.a[2]) + v * (t.c[2] - t.a[2])};
}

}  // namespace limn::test
