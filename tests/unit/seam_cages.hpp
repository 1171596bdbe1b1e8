// Cages with UV seams built on purpose, for the face-varying tests (subdivision against
// OpenSubdiv, attributes through simplification).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/mesh/shapes.hpp"

namespace limn::test {

// A cube whose six sides are separate UV islands (24 values, a 3 x 2 atlas).
inline Mesh cube_islands() {
  Mesh m = make_cube();
  for (size_t f = 0; f < m.face_count(); ++f) {
    const float u0 = float(f % 3) / 3.0f, v0 = float(f / 3) / 2.0f;
    const float corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (uint32_t i = 0; i < m.face_size(f); ++i) {
      m.uv_indices.push_back(uint32_t(m.uvs.size() / 2));
      m.uvs.push_back(u0 + (0.05f + 0.9f * corner[i][0]) / 3.0f);
      m.uvs.push_back(v0 + (0.05f + 0.9f * corner[i][1]) / 2.0f);
    }
  }
  return m;
}

// The procedural torus (with extraordinary vertices) mapped by its two angles: cut by a seam
// around each circle, the two seams crossing at one vertex with four values.
inline Mesh torus_seams() {
  const int valences[] = {3, 5, 6};
  Mesh m = make_torus(24, 12, valences);
  constexpr double kTwoPi = 6.283185307179586;
  auto angles = [&](uint32_t v, double out[2]) {
    const double x = m.positions[3 * v], y = m.positions[3 * v + 1], z = m.positions[3 * v + 2];
    out[0] = std::atan2(y, x) / kTwoPi + 0.5;
    out[1] = std::atan2(z, std::hypot(x, y) - 1.0) / kTwoPi + 0.5;
  };
  std::map<std::array<uint32_t, 3>, uint32_t> ids;  // (vertex, wrapped u, wrapped v) -> value
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    std::vector<std::array<double, 2>> a(fv.size());
    double lo[2] = {1, 1}, hi[2] = {0, 0};
    for (size_t i = 0; i < fv.size(); ++i) {
      angles(fv[i], a[i].data());
      for (int k = 0; k < 2; ++k)
        lo[k] = std::min(lo[k], a[i][k]), hi[k] = std::max(hi[k], a[i][k]);
    }
    for (size_t i = 0; i < fv.size(); ++i) {
      std::array<uint32_t, 3> key{fv[i], 0, 0};
      for (int k = 0; k < 2; ++k)
        if (hi[k] - lo[k] > 0.5 && a[i][k] < 0.5) a[i][k] += 1.0, key[size_t(k) + 1] = 1;
      const auto [it, added] = ids.emplace(key, uint32_t(m.uvs.size() / 2));
      if (added) m.uvs.insert(m.uvs.end(), {float(a[i][0]), float(a[i][1])});
      m.uv_indices.push_back(it->second);
    }
  }
  return m;
}

// A 4 x 4 grid of quads with a seam from the boundary into the middle, where it ends (a dart):
// faces above the slit see its vertices at other UVs than the faces below.
inline Mesh dart_grid() {
  Mesh m;
  for (int y = 0; y <= 4; ++y)
    for (int x = 0; x <= 4; ++x) m.add_vertex(float(x), float(y), 0.1f * float(x * y % 3));
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const uint32_t v = uint32_t(5 * y + x);
      m.add_face({v, v + 1, v + 6, v + 5});
    }
  for (uint32_t v = 0; v < 25; ++v)
    m.uvs.insert(m.uvs.end(), {float(v % 5) / 4.0f, float(v / 5) / 4.0f});
  // Slit vertices (0,2) and (1,2) get second values for the faces above; (2,2) is the tip.
  const uint32_t slit[2] = {10, 11};
  for (uint32_t v : slit) m.uvs.insert(m.uvs.end(), {float(v % 5) / 4.0f, 0.5f + 0.08f});
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t v : m.face(f)) {
      const bool above = f >= 8;  // faces of rows 2 and 3
      m.uv_indices.push_back(above && v == slit[0] ? 25 : above && v == slit[1] ? 26 : v);
    }
  m.tags.boundary = BoundaryInterpolation::edge_only;
  return m;
}

}  // namespace limn::test
