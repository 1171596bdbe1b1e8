// Union-find over indices 0..n-1 with path halving; a set's root is its smallest index, so roots
// come out in the order of their first member. Internal header of the mesh layer.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace limn::detail {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace limn::detail
