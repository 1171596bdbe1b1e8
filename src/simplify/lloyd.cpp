// Lloyd relaxation of a VSA partition: fit, pick seeds, flood.
#include "simplify/lloyd.hpp"

#include <algorithm>
#include <limits>

#include "simplify/seeding.hpp"

namespace limn {

LloydStats lloyd_optimize(const VsaSurface& s, Partition& p, const LloydOptions& o) {
  LloydStats st;
  const size_t nf = s.face_count(), K = p.cluster_count();
  std::vector<double> normals(3 * K);
  std::vector<uint32_t> seed(K), previous;
  std::vector<double> best(K);
  for (size_t it = 0; it < o.iterations; ++it) {
    for (uint32_t k = 0; k < K; ++k) {
      double n[3];
      p.proxy_normal(k, n);
      // A cluster of zero area keeps its previous normal (or any, the first time).
      if (n[0] != 0 || n[1] != 0 || n[2] != 0 || it == 0)
        for (int i = 0; i < 3; ++i) normals[3 * size_t(k) + i] = n[i];
      if (n[0] == 0 && n[1] == 0 && n[2] == 0 && it == 0) normals[3 * size_t(k) + 2] = 1;
    }
    std::fill(seed.begin(), seed.end(), kNone);
    std::fill(best.begin(), best.end(), std::numeric_limits<double>::infinity());
    for (uint32_t f = 0; f < nf; ++f) {
      const uint32_t k = p.label[f];
      const double* n = &normals[3 * size_t(k)];
      const double a = s.area[f];
      double e = 0;
      if (a > 0) {
        const double* v = &s.vec[3 * size_t(f)];
        const double d[3] = {v[0] / a - n[0], v[1] / a - n[1], v[2] / a - n[2]};
        e = a * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      } else {
        e = std::numeric_limits<double>::max();  // seeds should carry a normal
      }
      if (e < best[k] || seed[k] == kNone) best[k] = e, seed[k] = f;
    }
    previous = p.label;
    std::fill(p.label.begin(), p.label.end(), kUnassigned);
    std::fill(p.S.begin(), p.S.end(), 0.0);
    std::fill(p.N.begin(), p.N.end(), 0.0);
    std::fill(p.size.begin(), p.size.end(), 0u);
    std::fill(p.any_face.begin(), p.any_face.end(), kNone);
    for (uint32_t k = 0; k < K; ++k)
      if (seed[k] != kNone) p.assign(s, seed[k], k);
    flood_unassigned(s, p, normals);
    ++st.iterations;
    st.energy.push_back(p.energy());
    if (o.stop_when_stable && p.label == previous) break;
  }
  return st;
}

}  // namespace limn
