// Random open cages for the subdivision tests: mixed arities (triangles to octagons), a crease
// polyline and scattered creases of assorted sharpness, corners and holes, deterministic per seed.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

// SplitMix64, so the cages do not depend on the standard library's distributions.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(next() % n); }
  float uniform(float lo, float hi) {
    return lo + (hi - lo) * static_cast<float>(static_cast<double>(next() >> 11) * 0x1.0p-53);
  }

 private:
  uint64_t state_;
};

inline constexpr float kSharpnessChoices[] = {0.5f, 1.0f, 1.7f, 2.5f, 3.3f, 10.0f};

inline float random_sharpness(Rng& rng) {
  return kSharpnessChoices[rng.below(6)];
}

// An open grid whose cells are kept as quads, split into two triangles, or merged with their
// right neighbours into hexagons / octagons (sometimes trimmed into a pentagon plus a triangle).
// Merges never remove two vertical edges meeting at one interior vertex, so no interior vertex
// drops to valence 2 and the cage stays manifold with a single boundary loop.
inline Mesh random_cage(uint64_t seed) {
  Rng rng(seed);
  const int nx = 5 + static_cast<int>(rng.below(5)), ny = 4 + static_cast<int>(rng.below(4));
  Mesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.add_vertex(static_cast<float>(i) + rng.uniform(-0.2f, 0.2f),
                   static_cast<float>(j) + rng.uniform(-0.2f, 0.2f), rng.uniform(-0.5f, 0.5f));
  const auto id = [nx](int i, int j) { return static_cast<uint32_t>(j * (nx + 1) + i); };
  std::vector<char> removed_below(static_cast<size_t>(nx) + 1, 0);
  for (int j = 0; j < ny; ++j) {
    std::vector<char> removed(static_cast<size_t>(nx) + 1, 0);
    for (int i = 0; i < nx;) {
      int len = 1;
      while (i + len < nx && len < 3 && !removed_below[static_cast<size_t>(i + len)] &&
             rng.below(3) == 0)
        ++len;
      if (len == 1) {
        const uint32_t r = rng.below(6);
        if (r == 0) {
          m.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
          m.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        } else if (r == 1) {
          m.add_face({id(i, j), id(i + 1, j), id(i, j + 1)});
          m.add_face({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
        } else {
          m.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
        }
      } else {
        for (int x = i + 1; x < i + len; ++x) removed[static_cast<size_t>(x)] = 1;
        const bool trim = len == 2 && rng.below(2) == 0;
        std::vector<uint32_t> poly;
        if (trim) {
          m.add_face({id(i, j), id(i + 1, j), id(i, j + 1)});
        } else {
          poly.push_back(id(i, j));
        }
        for (int x = i + 1; x <= i + len; ++x) poly.push_back(id(x, j));
        for (int x = i + len; x >= i; --x) poly.push_back(id(x, j + 1));
        m.add_face(poly);
      }
      i += len;
    }
    removed_below = removed;
  }

  // Creases: one full polyline across the grid with varying sharpness (what Chaikin smooths),
  // plus scattered edges. One sharpness per edge, as duplicates are resolved differently.
  std::map<std::pair<uint32_t, uint32_t>, float> creases;
  const auto edge_key = [](uint32_t a, uint32_t b) {
    return std::pair(std::min(a, b), std::max(a, b));
  };
  const int row = 1 + static_cast<int>(rng.below(static_cast<uint32_t>(ny - 1)));
  for (int i = 0; i < nx; ++i)
    creases[edge_key(id(i, row), id(i + 1, row))] = random_sharpness(rng);
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t c = 0; c < fv.size(); ++c)
      edges.push_back(edge_key(fv[c], fv[(c + 1) % fv.size()]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (size_t n = edges.size() / 6; n > 0; --n)
    creases[edges[rng.below(static_cast<uint32_t>(edges.size()))]] = random_sharpness(rng);
  for (const auto& [e, s] : creases) {
    m.crease_edges.insert(m.crease_edges.end(), {e.first, e.second});
    m.crease_sharpness.push_back(s);
  }

  std::map<uint32_t, float> corners;
  for (size_t n = m.vertex_count() / 10; n > 0; --n)
    corners[rng.below(static_cast<uint32_t>(m.vertex_count()))] = random_sharpness(rng);
  for (const auto& [v, s] : corners)
    m.corner_vertices.push_back(v), m.corner_sharpness.push_back(s);

  std::vector<uint32_t> holes;
  for (uint32_t n = 1 + rng.below(3); n > 0; --n)
    holes.push_back(rng.below(static_cast<uint32_t>(m.face_count())));
  std::sort(holes.begin(), holes.end());
  holes.erase(std::unique(holes.begin(), holes.end()), holes.end());
  m.hole_faces = holes;
  validate(m, "random cage");
  return m;
}

}  // namespace limn::test
