// Brute-force reference computations for tests: std::map edge counting and BFS, written
// independently of limn's corner table so the two can disagree.
#pragma once

#include <map>
#include <queue>
#include <set>
#include <utility>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

struct BruteStats {
  size_t edges = 0, boundary_edges = 0, non_manifold_edges = 0, inconsistent_edges = 0;
  size_t components = 0, boundary_loops = 0, referenced = 0;
  std::map<uint32_t, size_t> face_count_at_vertex;
};

inline BruteStats brute_stats(const Mesh& m) {
  BruteStats s;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::pair<uint32_t, uint32_t>>> edges;
  std::vector<std::vector<uint32_t>> nbr(m.vertex_count());
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t i = 0; i < fv.size(); ++i) {
      const uint32_t a = fv[i], b = fv[(i + 1) % fv.size()];
      edges[{std::min(a, b), std::max(a, b)}].push_back({a, b});
      nbr[a].push_back(b), nbr[b].push_back(a);
      ++s.face_count_at_vertex[a];
    }
  }
  s.edges = edges.size();
  std::vector<std::vector<uint32_t>> bnbr(m.vertex_count());
  for (const auto& [k, list] : edges) {
    if (list.size() == 1) {
      ++s.boundary_edges;
      bnbr[k.first].push_back(k.second), bnbr[k.second].push_back(k.first);
    }
    if (list.size() > 2) ++s.non_manifold_edges;
    if (list.size() == 2 && list[0] == list[1]) ++s.inconsistent_edges;
  }
  auto count_components = [&](const std::vector<std::vector<uint32_t>>& g) {
    std::vector<char> seen(g.size(), 0);
    size_t n = 0;
    for (uint32_t v = 0; v < g.size(); ++v) {
      if (seen[v] || g[v].empty()) continue;
      ++n;
      std::queue<uint32_t> q;
      q.push(v), seen[v] = 1;
      while (!q.empty()) {
        const uint32_t x = q.front();
        q.pop();
        for (uint32_t y : g[x])
          if (!seen[y]) seen[y] = 1, q.push(y);
      }
    }
    return n;
  };
  s.components = count_components(nbr);
  s.boundary_loops = count_components(bnbr);
  for (const auto& l : nbr) s.referenced += !l.empty();
  return s;
}

}  // namespace limn::test
