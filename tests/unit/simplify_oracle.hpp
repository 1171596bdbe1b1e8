// Independent references for the simplify tests: the L2,1 energy recomputed from face labels and
// positions in long double (both from the cluster sums, eq. 7, and from its definition, eq. 5),
// face adjacency from a std::map over vertex pairs (not limn's corner table), cluster
// connectivity by breadth-first search, and a few small synthetic meshes.
#pragma once

#include <cmath>
#include <cstdint>
#include <map>
#include <queue>
#include <set>
#include <utility>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

struct LVec {
  long double x = 0, y = 0, z = 0;
};

/// Vector area (area times unit normal) of face f, fanned from its first corner.
inline LVec face_vector_area(const Mesh& m, size_t f) {
  const auto v = m.face(f);
  auto P = [&](uint32_t i) {
    const float* p = &m.positions[3 * size_t(i)];
    return LVec{p[0], p[1], p[2]};
  };
  LVec n;
  const LVec o = P(v[0]);
  for (size_t i = 1; i + 1 < v.size(); ++i) {
    const LVec a = P(v[i]), b = P(v[i + 1]);
    const LVec u{a.x - o.x, a.y - o.y, a.z - o.z}, w{b.x - o.x, b.y - o.y, b.z - o.z};
    n.x += (u.y * w.z - u.z * w.y) / 2;
    n.y += (u.z * w.x - u.x * w.z) / 2;
    n.z += (u.x * w.y - u.y * w.x) / 2;
  }
  return n;
}

/// E = sum over clusters of 2 (S - |N|), from labels alone (eq. 7).
inline double energy_from_sums(const Mesh& m, const std::vector<uint32_t>& labels) {
  std::map<uint32_t, std::pair<long double, LVec>> c;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const LVec n = face_vector_area(m, f);
    auto& [S, N] = c[labels[f]];
    S += std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    N.x += n.x, N.y += n.y, N.z += n.z;
  }
  long double e = 0;
  for (const auto& [k, sn] : c) {
    const LVec& N = sn.second;
    e += 2 * (sn.first - std::sqrt(N.x * N.x + N.y * N.y + N.z * N.z));
  }
  return double(e);
}

/// E = sum over faces of a_j |n_j - n_C|^2 with n_C the normalised area-weighted normal of the
/// face's cluster (eq. 5, the definition).
inline double energy_from_definition(const Mesh& m, const std::vector<uint32_t>& labels) {
  std::map<uint32_t, LVec> N;
  std::vector<LVec> fv(m.face_count());
  for (size_t f = 0; f < m.face_count(); ++f) {
    fv[f] = face_vector_area(m, f);
    LVec& n = N[labels[f]];
    n.x += fv[f].x, n.y += fv[f].y, n.z += fv[f].z;
  }
  long double e = 0;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const LVec& c = N[labels[f]];
    const long double cl = std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    const long double a = std::sqrt(fv[f].x * fv[f].x + fv[f].y * fv[f].y + fv[f].z * fv[f].z);
    if (!(a > 0) || !(cl > 0)) continue;
    const long double dx = fv[f].x / a - c.x / cl, dy = fv[f].y / a - c.y / cl,
                      dz = fv[f].z / a - c.z / cl;
    e += a * (dx * dx + dy * dy + dz * dz);
  }
  return double(e);
}

/// Faces sharing an edge with each face (from a map over vertex pairs).
inline std::vector<std::vector<uint32_t>> face_neighbours(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edges;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (size_t i = 0; i < v.size(); ++i) {
      const uint32_t a = v[i], b = v[(i + 1) % v.size()];
      edges[{std::min(a, b), std::max(a, b)}].push_back(uint32_t(f));
    }
  }
  std::vector<std::vector<uint32_t>> nb(m.face_count());
  for (const auto& [e, fs] : edges)
    for (uint32_t a : fs)
      for (uint32_t b : fs)
        if (a != b) nb[a].push_back(b);
  return nb;
}

/// Number of clusters that are not edge-connected (0 when all are), by BFS over `nb`.
inline size_t disconnected_clusters(const std::vector<std::vector<uint32_t>>& nb,
                                    const std::vector<uint32_t>& labels) {
  std::map<uint32_t, std::vector<uint32_t>> members;
  for (uint32_t f = 0; f < labels.size(); ++f) members[labels[f]].push_back(f);
  std::vector<uint8_t> seen(labels.size(), 0);
  size_t bad = 0;
  for (const auto& [k, faces] : members) {
    std::queue<uint32_t> q;
    q.push(faces[0]);
    seen[faces[0]] = 1;
    size_t reached = 1;
    while (!q.empty()) {
      const uint32_t f = q.front();
      q.pop();
      for (uint32_t g : nb[f])
        if (!seen[g] && labels[g] == k) seen[g] = 1, ++reached, q.push(g);
    }
    bad += reached != faces.size();
  }
  return bad;
}

/// Whether removing face f from its cluster would leave the rest of the cluster disconnected
/// (or empty), by BFS.
inline bool removal_disconnects(const std::vector<std::vector<uint32_t>>& nb,
                                const std::vector<uint32_t>& labels, uint32_t f) {
  const uint32_t k = labels[f];
  std::vector<uint32_t> rest;
  for (uint32_t g = 0; g < labels.size(); ++g)
    if (labels[g] == k && g != f) rest.push_back(g);
  if (rest.empty()) return true;
  std::set<uint32_t> seen{rest[0]};
  std::queue<uint32_t> q;
  q.push(rest[0]);
  while (!q.empty()) {
    const uint32_t g = q.front();
    q.pop();
    for (uint32_t h : nb[g])
      if (h != f && labels[h] == k && seen.insert(h).second) q.push(h);
  }
  return seen.size() != rest.size();
}

/// An n x n grid of unit squares in the z = 0 plane, each split into two triangles; cells
/// listed in `skip` (row * n + col) are left out (holes).
inline Mesh grid_mesh(int n, const std::set<int>& skip = {}) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.add_vertex(float(i), float(j), 0.0f);
  auto id = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (skip.count(j * n + i)) continue;
      m.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  // Drop vertices no face uses (inside large holes) so outputs are compared cleanly.
  return m;
}

/// A latitude-longitude sphere of radius r (triangles, poles as fans), closed and oriented
/// outwards.
inline Mesh uv_sphere(int rings, int segments, float r) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  m.add_vertex(0, 0, r);
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double t = pi * i / rings, p = 2 * pi * j / segments;
      m.add_vertex(float(r * std::sin(t) * std::cos(p)), float(r * std::sin(t) * std::sin(p)),
                   float(r * std::cos(t)));
    }
  const uint32_t south = m.add_vertex(0, 0, -r);
  auto id = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) m.add_face({0, id(1, j), id(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) m.add_face({south, id(rings - 1, j + 1), id(rings - 1, j)});
  return m;
}

/// Boundary loops of a mesh (vertices joined by edges used by one face), counted by union-find.
inline size_t boundary_loops(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (size_t i = 0; i < v.size(); ++i) {
      const uint32_t a = v[i], b = v[(i + 1) % v.size()];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::vector<uint32_t> parent(m.vertex_count());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::set<uint32_t> on;
  for (const auto& [e, n] : uses)
    if (n == 1) parent[find(e.first)] = find(e.second), on.insert(e.first), on.insert(e.second);
  std::set<uint32_t> roots;
  for (uint32_t v : on) roots.insert(find(v));
  return roots.size();
}

}  // namespace limn::test
