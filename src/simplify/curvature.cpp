// Meyer et al.'s angle-defect Gaussian curvature over mixed Voronoi areas.
#include "simplify/curvature.hpp"

#include <cmath>
#include <numbers>

#include "core/vec3.hpp"

namespace limn {

std::vector<double> gaussian_curvature(const VsaSurface& s) {
  const Mesh& m = *s.mesh;
  const size_t nv = m.vertex_count();
  std::vector<double> angle(nv, 0.0), area(nv, 0.0);
  auto pos = [&](uint32_t v) {
    const float* p = &m.positions[3 * size_t(v)];
    return Vec3d{p[0], p[1], p[2]};
  };
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t i = 1; i + 1 < fv.size(); ++i) {
      const uint32_t id[3] = {fv[0], fv[i], fv[i + 1]};
      const Vec3d p[3] = {pos(id[0]), pos(id[1]), pos(id[2])};
      const double a2 = length(cross(p[1] - p[0], p[2] - p[0]));  // twice the area
      // Zero-area triangles have no meaningful angles (they would read 0, 0 and pi).
      if (!(a2 > 0)) continue;
      double ang[3], cot[3];
      for (int k = 0; k < 3; ++k) {
        const Vec3d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
        ang[k] = std::atan2(length(cross(u, w)), dot(u, w));
        cot[k] = dot(u, w) / a2;  // |u x w| is twice the area for every corner
      }
      const bool obtuse = ang[0] > std::numbers::pi / 2 || ang[1] > std::numbers::pi / 2 ||
                          ang[2] > std::numbers::pi / 2;
      for (int k = 0; k < 3; ++k) {
        angle[id[k]] += ang[k];
        double a;
        if (!obtuse) {
          // Voronoi region: the two edges at this corner, each weighted by the opposite cot.
          const Vec3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
          a = (dot(e1, e1) * cot[(k + 2) % 3] + dot(e2, e2) * cot[(k + 1) % 3]) / 8.0;
        } else {
          a = ang[k] > std::numbers::pi / 2 ? a2 / 4.0 : a2 / 8.0;
        }
        area[id[k]] += a;
      }
    }
  }
  std::vector<double> K(nv, 0.0);
  for (size_t v = 0; v < nv; ++v)
    if (s.vertex_kind[v] == 1 && area[v] > 0) K[v] = (2.0 * std::numbers::pi - angle[v]) / area[v];
  return K;
}

std::vector<double> face_abs_curvature(const VsaSurface& s, std::span<const double> vertex_k) {
  const Mesh& m = *s.mesh;
  std::vector<double> out(m.face_count());
  for (size_t f = 0; f < m.face_count(); ++f) {
    double sum = 0;
    for (uint32_t v : m.face(f)) sum += std::abs(vertex_k[v]);
    out[f] = sum / m.face_size(f);
  }
  return out;
}

}  // namespace limn
