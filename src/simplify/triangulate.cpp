// Minimum-weight polygon triangulation by dynamic programming.
#include "simplify/triangulate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace limn {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// O(n^3): 192^3 / 6 is about a million triangle weights.
constexpr uint32_t kMaxDp = 192;

bool dp(uint32_t n, const DiagonalOk& ok, const TriangleWeight& weight,
        std::vector<uint32_t>& out) {
  auto edge_ok = [&](uint32_t i, uint32_t j) {
    return j == i + 1 || (i == 0 && j == n - 1) || ok(i, j);
  };
  std::vector<double> W(size_t(n) * n, kInf);
  std::vector<uint32_t> best(size_t(n) * n, 0);
  std::vector<uint8_t> usable(size_t(n) * n, 0);
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = i + 1; j < n; ++j) usable[size_t(i) * n + j] = edge_ok(i, j);
  for (uint32_t i = 0; i + 1 < n; ++i) W[size_t(i) * n + i + 1] = 0;
  for (uint32_t len = 2; len < n; ++len) {
    for (uint32_t i = 0; i + len < n; ++i) {
      const uint32_t j = i + len;
      if (!usable[size_t(i) * n + j]) continue;
      double bw = kInf;
      uint32_t bk = 0;
      for (uint32_t k = i + 1; k < j; ++k) {
        if (!usable[size_t(i) * n + k] || !usable[size_t(k) * n + j]) continue;
        const double a = W[size_t(i) * n + k], b = W[size_t(k) * n + j];
        if (!(a + b < bw)) continue;
        const double w = a + b + weight(i, k, j);
        if (w < bw) bw = w, bk = k;
      }
      W[size_t(i) * n + j] = bw;
      best[size_t(i) * n + j] = bk;
    }
  }
  if (!(W[n - 1] < kInf)) return false;
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const uint32_t k = best[size_t(i) * n + j];
    out.insert(out.end(), {i, k, j});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

}  // namespace

bool triangulate_polygon(uint32_t n, const DiagonalOk& ok, const TriangleWeight& weight,
                         std::vector<uint32_t>& out) {
  if (n < 3) return false;
  if (n <= kMaxDp) return dp(n, ok, weight, out);
  // Cut into two halves along an allowed diagonal between nearly opposite positions; among a
  // few candidates, the one whose halves are most balanced and allowed.
  const size_t mark = out.size();
  for (uint32_t shift = 0; shift < n / 2; ++shift) {
    for (int side = 0; side < 2; ++side) {
      const uint32_t i = side == 0 ? shift : n - 1 - shift;
      const uint32_t j0 = (i + n / 2) % n;
      const uint32_t a = std::min(i, j0), b = std::max(i, j0);
      if (b - a < 2 || (a == 0 && b == n - 1) || !ok(a, b)) continue;
      // First half: a..b; second: b..n-1, 0..a.
      std::vector<uint32_t> first, second;
      for (uint32_t k = a; k <= b; ++k) first.push_back(k);
      for (uint32_t k = b; k < n; ++k) second.push_back(k);
      for (uint32_t k = 0; k <= a; ++k) second.push_back(k);
      bool good = true;
      for (const auto* part : {&first, &second}) {
        const std::vector<uint32_t>& map = *part;
        const uint32_t m = static_cast<uint32_t>(map.size());
        // The cut diagonal is a side of each half (first-last), so never vetoed there.
        auto sub_ok = [&](uint32_t x, uint32_t y) {
          return ok(std::min(map[x], map[y]), std::max(map[x], map[y]));
        };
        auto sub_w = [&](uint32_t x, uint32_t y, uint32_t z) {
          uint32_t t[3] = {map[x], map[y], map[z]};
          // Restore i < j < k order of the parent without changing the cyclic order.
          while (!(t[0] < t[1] && t[1] < t[2])) std::rotate(t, t + 1, t + 3);
          return weight(t[0], t[1], t[2]);
        };
        std::vector<uint32_t> tri;
        if (!triangulate_polygon(m, sub_ok, sub_w, tri)) {
          good = false;
          break;
        }
        for (size_t q = 0; q < tri.size(); q += 3) {
          uint32_t t[3] = {map[tri[q]], map[tri[q + 1]], map[tri[q + 2]]};
          while (!(t[0] < t[1] && t[1] < t[2])) std::rotate(t, t + 1, t + 3);
          out.insert(out.end(), t, t + 3);
        }
      }
      if (good) return true;
      out.resize(mark);
    }
  }
  return false;
}

}  // namespace limn
