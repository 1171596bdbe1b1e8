// Adaptive (curvature) and random seeding, flooding of unassigned faces.
#include "simplify/seeding.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <random>

#include "simplify/curvature.hpp"

namespace limn {

namespace {

struct Item {
  double key;
  uint32_t face, cluster;
  bool operator>(const Item& o) const {
    // Ties broken by face id so the result never depends on the heap's internals.
    return key > o.key || (key == o.key && face > o.face);
  }
};
using MinHeap = std::priority_queue<Item, std::vector<Item>, std::greater<Item>>;

// |n_f - n|^2 for unit proxy normal n (a zero-area face reads as deviation 1).
inline double deviation2(const VsaSurface& s, uint32_t f, const double* n) {
  const double a = s.area[f];
  if (!(a > 0)) return 1.0;
  const double* v = &s.vec[3 * size_t(f)];
  const double inv = 1.0 / a;
  const double d[3] = {v[0] * inv - n[0], v[1] * inv - n[1], v[2] * inv - n[2]};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

std::vector<uint32_t> shuffled_faces(size_t nf, uint64_t seed) {
  std::vector<uint32_t> order(nf);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937_64 rng(seed);
  // Fisher-Yates with our own index draw: std::shuffle's draws differ between library versions.
  for (size_t i = nf; i > 1; --i) {
    const size_t j = size_t(rng() % i);
    std::swap(order[i - 1], order[j]);
  }
  return order;
}

Partition empty_partition(const VsaSurface& s) {
  Partition p;
  p.label.assign(s.face_count(), kUnassigned);
  return p;
}

void grow_curvature(const VsaSurface& s, const SeedingOptions& o, Partition& p, SeedingStats& st) {
  const Mesh& m = *s.mesh;
  const std::vector<double> kv = gaussian_curvature(s);
  const std::vector<double> kf = face_abs_curvature(s, kv);
  double total = 0;
  for (size_t f = 0; f < s.face_count(); ++f) total += s.area[f] * kf[f];
  const double D = total / double(o.clusters);
  st.budget = D;
  const double planar2 = o.planar_deviation * o.planar_deviation;
  const std::vector<uint32_t> order = shuffled_faces(s.face_count(), o.seed);
  size_t cursor = 0;
  MinHeap heap;
  double n[3];
  while (p.cluster_count() < o.clusters) {
    while (cursor < order.size() && p.label[order[cursor]] != kUnassigned) ++cursor;
    if (cursor == order.size()) break;
    const uint32_t k = p.add_cluster();
    const uint32_t seed = order[cursor];
    p.assign(s, seed, k);
    double curvature = s.area[seed] * kf[seed];
    p.proxy_normal(k, n);
    auto push_neighbours = [&](uint32_t f) {
      for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
        const uint32_t g = s.across(c);
        if (g != kNone && p.label[g] == kUnassigned) heap.push({deviation2(s, g, n), g, k});
      }
    };
    push_neighbours(seed);
    while (!heap.empty()) {
      const Item it = heap.top();
      heap.pop();
      if (p.label[it.face] != kUnassigned) continue;
      // Keys go stale as the proxy normal turns; re-key lazily when the face reaches the top.
      const double key = deviation2(s, it.face, n);
      if (key > it.key && !heap.empty() && key > heap.top().key) {
        heap.push({key, it.face, k});
        continue;
      }
      if (curvature > D && key >= planar2) break;
      p.assign(s, it.face, k);
      curvature += s.area[it.face] * kf[it.face];
      p.proxy_normal(k, n);
      push_neighbours(it.face);
    }
    heap = MinHeap();
  }
}

void seed_random(const VsaSurface& s, const SeedingOptions& o, Partition& p) {
  const std::vector<uint32_t> order = shuffled_faces(s.face_count(), o.seed);
  for (size_t i = 0; i < std::min(o.clusters, order.size()); ++i)
    p.assign(s, order[i], p.add_cluster());
  std::vector<double> normals(3 * p.cluster_count());
  for (uint32_t k = 0; k < p.cluster_count(); ++k) p.proxy_normal(k, &normals[3 * size_t(k)]);
  flood_unassigned(s, p, normals);
}

}  // namespace

Partition seed_partition(const VsaSurface& s, const SeedingOptions& options, SeedingStats* stats) {
  SeedingOptions o = options;
  o.clusters = std::max<size_t>(1, std::min(o.clusters, s.face_count()));
  Partition p = empty_partition(s);
  SeedingStats st;
  if (o.method == SeedingMethod::curvature)
    grow_curvature(s, o, p, st);
  else
    seed_random(s, o, p);
  st.clusters = p.cluster_count();
  st.left_over = size_t(std::count(p.label.begin(), p.label.end(), kUnassigned));
  if (stats) *stats = st;
  return p;
}

void flood_from(const VsaSurface& s, Partition& p, std::span<const uint32_t> sources,
                std::span<const double> normals) {
  const Mesh& m = *s.mesh;
  MinHeap heap;
  auto push_neighbours = [&](uint32_t f, uint32_t k) {
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const uint32_t g = s.across(c);
      if (g != kNone && p.label[g] == kUnassigned)
        heap.push({s.area[g] * deviation2(s, g, &normals[3 * size_t(k)]), g, k});
    }
  };
  for (uint32_t f : sources) push_neighbours(f, p.label[f]);
  while (!heap.empty()) {
    const Item it = heap.top();
    heap.pop();
    if (p.label[it.face] != kUnassigned) continue;
    p.assign(s, it.face, it.cluster);
    push_neighbours(it.face, it.cluster);
  }
}

void flood_unassigned(const VsaSurface& s, Partition& p, std::span<const double> normals) {
  const Mesh& m = *s.mesh;
  std::vector<uint32_t> sources;
  for (uint32_t f = 0; f < s.face_count(); ++f) {
    if (p.label[f] == kUnassigned) continue;
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const uint32_t g = s.across(c);
      if (g != kNone && p.label[g] == kUnassigned) {
        sources.push_back(f);
        break;
      }
    }
  }
  flood_from(s, p, sources, normals);
}

size_t absorb_unassigned(const VsaSurface& s, Partition& p) {
  std::vector<double> normals(3 * p.cluster_count());
  for (uint32_t k = 0; k < p.cluster_count(); ++k) p.proxy_normal(k, &normals[3 * size_t(k)]);
  flood_unassigned(s, p, normals);
  // Components without a cluster: one cluster each, flooded from its first face.
  size_t added = 0;
  for (uint32_t f = 0; f < s.face_count(); ++f) {
    if (p.label[f] != kUnassigned) continue;
    const uint32_t k = p.add_cluster();
    ++added;
    p.assign(s, f, k);
    double n[3];
    p.proxy_normal(k, n);
    normals.insert(normals.end(), n, n + 3);
    if (!(s.area[f] > 0)) normals[3 * size_t(k) + 2] = 1;  // any direction will do
    flood_unassigned(s, p, normals);
  }
  return added;
}

}  // namespace limn
