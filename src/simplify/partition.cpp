// Cluster sums of a VSA partition.
#include "limn/simplify/partition.hpp"

#include <algorithm>

namespace limn {

double Partition::energy() const {
  double e = 0;
  for (size_t k = 0; k < cluster_count(); ++k) e += cluster_energy(static_cast<uint32_t>(k));
  return e;
}

void Partition::proxy_normal(uint32_t k, double out[3]) const {
  const double n = norm(k);
  const double inv = n > 0 ? 1.0 / n : 0.0;
  for (int i = 0; i < 3; ++i) out[i] = N[3 * size_t(k) + i] * inv;
}

uint32_t Partition::add_cluster() {
  S.push_back(0);
  N.insert(N.end(), {0.0, 0.0, 0.0});
  size.push_back(0);
  any_face.push_back(kNone);
  return static_cast<uint32_t>(S.size() - 1);
}

void Partition::assign(const VsaSurface& s, uint32_t f, uint32_t k) {
  label[f] = k;
  S[k] += s.area[f];
  for (int i = 0; i < 3; ++i) N[3 * size_t(k) + i] += s.vec[3 * size_t(f) + i];
  ++size[k];
  if (any_face[k] == kNone) any_face[k] = f;
}

void Partition::move(const VsaSurface& s, uint32_t f, uint32_t k) {
  const uint32_t from = label[f];
  S[from] -= s.area[f];
  for (int i = 0; i < 3; ++i) N[3 * size_t(from) + i] -= s.vec[3 * size_t(f) + i];
  if (--size[from] == 0) {
    // An emptied cluster has exactly zero sums, not round-off.
    S[from] = 0;
    N[3 * size_t(from)] = N[3 * size_t(from) + 1] = N[3 * size_t(from) + 2] = 0;
    any_face[from] = kNone;
  } else if (any_face[from] == f) {
    const Mesh& m = *s.mesh;
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const uint32_t g = s.across(c);
      if (g != kNone && label[g] == from) {
        any_face[from] = g;
        break;
      }
    }
  }
  label[f] = kUnassigned;
  assign(s, f, k);
}

void Partition::recompute(const VsaSurface& s) {
  std::fill(S.begin(), S.end(), 0.0);
  std::fill(N.begin(), N.end(), 0.0);
  std::fill(size.begin(), size.end(), 0u);
  std::fill(any_face.begin(), any_face.end(), kNone);
  for (uint32_t f = 0; f < label.size(); ++f) {
    const uint32_t k = label[f];
    if (k == kUnassigned) continue;
    label[f] = kUnassigned;
    assign(s, f, k);
  }
}

Partition partition_from_labels(const VsaSurface& s, std::span<const uint32_t> labels,
                                size_t clusters) {
  Partition p;
  p.label.assign(labels.begin(), labels.end());
  for (size_t k = 0; k < clusters; ++k) p.add_cluster();
  p.recompute(s);
  return p;
}

}  // namespace limn
