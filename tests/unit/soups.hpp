// Broken versions of a clean mesh, as repair meets them in scans and exports: shuffled and
// partly reversed faces, every corner its own vertex, and non-manifold, duplicate and degenerate
// faces added. Shared by the repair tests and limn_bench_repair, so both meet the same soups.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

using Pos = std::array<float, 3>;

inline Pos pos(const Mesh& m, uint32_t v) {
  return {m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1],
          m.positions[3 * size_t(v) + 2]};
}

// A copy of `m` with faces shuffled, rotated and reversed at `flip_rate` (`flipped` says which),
// and vertices renumbered at random.
inline Mesh shuffled(const Mesh& m, std::mt19937& rng, std::vector<uint8_t>& flipped,
                     double flip_rate) {
  std::vector<uint32_t> vperm(m.vertex_count()), forder(m.face_count());
  std::iota(vperm.begin(), vperm.end(), 0u);
  std::iota(forder.begin(), forder.end(), 0u);
  std::shuffle(vperm.begin(), vperm.end(), rng);
  std::shuffle(forder.begin(), forder.end(), rng);
  Mesh out;
  out.positions.resize(m.positions.size());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) out.positions[3 * size_t(vperm[v]) + k] = m.positions[3 * v + k];
  std::bernoulli_distribution coin(flip_rate);
  flipped.assign(m.face_count(), 0);
  std::vector<uint32_t> face;
  for (const uint32_t f : forder) {
    const auto fv = m.face(f);
    face.clear();
    for (const uint32_t v : fv) face.push_back(vperm[v]);
    std::rotate(face.begin(), face.begin() + rng() % face.size(), face.end());
    if (coin(rng)) std::reverse(face.begin(), face.end()), flipped[f] = 1;
    out.add_face(face);
  }
  return out;
}

// Every corner its own vertex (a triangle soup as STL stores it), faces shuffled.
inline Mesh welded_apart(const Mesh& m, std::mt19937& rng) {
  std::vector<uint32_t> order(m.face_count());
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  Mesh out;
  std::vector<uint32_t> face;
  for (const uint32_t f : order) {
    face.clear();
    for (const uint32_t v : m.face(f)) {
      const Pos p = pos(m, v);
      face.push_back(out.add_vertex(p[0], p[1], p[2]));
    }
    out.add_face(face);
  }
  return out;
}

// `clean` and a copy of it touching it at one vertex, `fins` triangles on edges (three faces on
// an edge), `duplicates` repeated faces (every other one reversed; their area summed in
// `duplicate_area`) and `degenerate` triangles over an exact copy of one of their corners.
inline Mesh broken(const Mesh& clean, std::mt19937& rng, size_t fins, size_t duplicates,
                   size_t degenerate, double& duplicate_area) {
  Mesh m = clean;
  const size_t nv = clean.vertex_count(), nf = clean.face_count();
  // The copy's largest-x vertex onto the original's smallest-x vertex.
  uint32_t lo = 0, hi = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    if (clean.positions[3 * v] < clean.positions[3 * lo]) lo = v;
    if (clean.positions[3 * v] > clean.positions[3 * hi]) hi = v;
  }
  float t[3];
  for (int k = 0; k < 3; ++k) t[k] = clean.positions[3 * lo + k] - clean.positions[3 * hi + k];
  for (uint32_t v = 0; v < nv; ++v) {
    const Pos p =
        v == hi ? pos(clean, lo)
                : Pos{pos(clean, v)[0] + t[0], pos(clean, v)[1] + t[1], pos(clean, v)[2] + t[2]};
    m.add_vertex(p[0], p[1], p[2]);
  }
  std::vector<uint32_t> face;
  for (size_t f = 0; f < nf; ++f) {
    face.clear();
    for (const uint32_t v : clean.face(f)) face.push_back(v + uint32_t(nv));
    m.add_face(face);
  }
  std::uniform_int_distribution<size_t> pick(0, nf - 1);
  std::set<std::pair<uint32_t, uint32_t>> used;
  for (size_t i = 0; i < fins;) {
    const auto fv = clean.face(pick(rng));
    const uint32_t a = fv[0], b = fv[1];
    if (!used.insert({std::min(a, b), std::max(a, b)}).second) continue;
    const Pos pa = pos(clean, a), pb = pos(clean, b);
    const uint32_t c = m.add_vertex(0.5f * (pa[0] + pb[0]), 0.5f * (pa[1] + pb[1]) + 0.3f,
                                    0.5f * (pa[2] + pb[2]) + 0.2f);
    m.add_face({a, b, c});
    ++i;
  }
  duplicate_area = 0;
  for (size_t i = 0; i < duplicates; ++i) {
    const size_t f = pick(rng);
    duplicate_area += face_area(clean, f);
    const auto fv = clean.face(f);
    face.assign(fv.begin(), fv.end());
    if (i % 2) std::reverse(face.begin(), face.end());
    m.add_face(face);
  }
  for (size_t i = 0; i < degenerate; ++i) {  // a triangle over an exact copy of one of its corners
    const auto fv = clean.face(pick(rng));
    const Pos p = pos(clean, fv[0]);
    m.add_face({fv[0], fv[1], m.add_vertex(p[0], p[1], p[2])});
  }
  return m;
}

}  // namespace limn::test
