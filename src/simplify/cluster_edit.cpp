// Cluster splits and merges.
#include "simplify/cluster_edit.hpp"

#include <cmath>
#include <stdexcept>

#include "simplify/seeding.hpp"

namespace limn {

uint32_t worst_cluster(const Partition& p) {
  uint32_t best = kNone;
  double worst = -1;
  for (uint32_t k = 0; k < p.cluster_count(); ++k) {
    if (p.size[k] < 2) continue;
    const double e = p.cluster_energy(k);
    if (e > worst) worst = e, best = k;
  }
  return best;
}

uint32_t split_cluster(const VsaSurface& s, Partition& p, uint32_t k, std::vector<uint32_t>* out) {
  if (k >= p.cluster_count() || p.size[k] < 2) return kNone;
  std::vector<uint32_t> faces = cluster_faces(s, p, k);
  double nk[3];
  p.proxy_normal(k, nk);
  auto farthest = [&](const double* n, uint32_t skip) {
    uint32_t best = kNone;
    double worst = -1;
    for (uint32_t f : faces) {
      if (f == skip) continue;
      double d = -0.5;  // faces with area first
      if (s.area[f] > 0) {
        double u[3];
        s.normal(f, u);
        d = (u[0] - n[0]) * (u[0] - n[0]) + (u[1] - n[1]) * (u[1] - n[1]) +
            (u[2] - n[2]) * (u[2] - n[2]);
      }
      if (d > worst) worst = d, best = f;
    }
    return best;
  };
  const uint32_t a = farthest(nk, kNone);
  double na[3];
  s.normal(a, na);
  if (!(s.area[a] > 0)) na[0] = nk[0], na[1] = nk[1], na[2] = nk[2];
  const uint32_t b = farthest(na, a);
  // Empty k and re-grow it and the new cluster from the two seeds, inside k's old faces only.
  for (uint32_t f : faces) p.label[f] = kUnassigned;
  p.S[k] = 0, p.size[k] = 0, p.any_face[k] = kNone;
  p.N[3 * size_t(k)] = p.N[3 * size_t(k) + 1] = p.N[3 * size_t(k) + 2] = 0;
  const uint32_t k2 = p.add_cluster();
  p.assign(s, a, k);
  p.assign(s, b, k2);
  double nb[3];
  s.normal(b, nb);
  std::vector<double> normals(3 * p.cluster_count(), 0.0);
  for (int i = 0; i < 3; ++i)
    normals[3 * size_t(k) + i] = na[i], normals[3 * size_t(k2) + i] = nb[i];
  const uint32_t sources[2] = {a, b};
  flood_from(s, p, sources, normals);
  if (out) *out = std::move(faces);
  return k2;
}

std::vector<uint32_t> cluster_faces(const VsaSurface& s, Partition& p, uint32_t k) {
  std::vector<uint32_t> faces;
  if (p.size[k] == 0) return faces;
  faces.reserve(p.size[k]);
  // Faces found are relabelled to a marker while searching (no per-face scratch array, so the
  // cost stays O(|C_k|)), then given back their label.
  const uint32_t mark = kUnassigned - 1;
  const Mesh& m = *s.mesh;
  faces.push_back(p.any_face[k]);
  p.label[faces[0]] = mark;
  for (size_t i = 0; i < faces.size(); ++i) {
    const uint32_t f = faces[i];
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const uint32_t g = s.across(c);
      if (g != kNone && p.label[g] == k) p.label[g] = mark, faces.push_back(g);
    }
  }
  for (uint32_t f : faces) p.label[f] = k;
  return faces;
}

void merge_clusters(const VsaSurface& s, Partition& p, uint32_t into, uint32_t from,
                    std::vector<uint32_t>* out) {
  std::vector<uint32_t> faces = cluster_faces(s, p, from);
  for (uint32_t f : faces) p.label[f] = into;
  p.S[into] += p.S[from];
  for (int i = 0; i < 3; ++i) p.N[3 * size_t(into) + i] += p.N[3 * size_t(from) + i];
  p.size[into] += p.size[from];
  if (p.any_face[into] == kNone) p.any_face[into] = p.any_face[from];
  p.S[from] = 0;
  p.N[3 * size_t(from)] = p.N[3 * size_t(from) + 1] = p.N[3 * size_t(from) + 2] = 0;
  p.size[from] = 0;
  p.any_face[from] = kNone;
  if (out) *out = std::move(faces);
}

double merge_cost(const Partition& p, uint32_t k, uint32_t l) {
  const double* a = &p.N[3 * size_t(k)];
  const double* b = &p.N[3 * size_t(l)];
  const double x = a[0] + b[0], y = a[1] + b[1], z = a[2] + b[2];
  return 2 * (p.norm(k) + p.norm(l) - std::sqrt(x * x + y * y + z * z));
}

void pop_empty_cluster(Partition& p) {
  if (p.cluster_count() == 0 || p.size.back() != 0)
    throw std::logic_error("pop_empty_cluster: the last cluster has faces");
  p.S.pop_back();
  p.N.resize(p.N.size() - 3);
  p.size.pop_back();
  p.any_face.pop_back();
}

}  // namespace limn
