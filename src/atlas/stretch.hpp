// Sander, Snyder, Gortler, Hoppe 2001 ("Texture mapping progressive meshes"): the stretch of one
// triangle's map from texture space to the surface. Internal header of the atlas layer.
#pragma once

#include <algorithm>
#include <cmath>

namespace limn::atlas {

struct TriangleStretch {
  double area3 = 0;    ///< surface area
  double area_uv = 0;  ///< signed UV area (positive: counter-clockwise, not mirrored)
  double l2_sq = 0;    ///< (Gamma^2 + gamma^2) / 2: the mean squared stretch over directions
  double gamma = 0;    ///< Gamma, the largest singular value
};

/// q: 3 surface points (xyz), uv: their texture coordinates. l2_sq and gamma stay 0 when the UV
/// triangle has no area.
inline TriangleStretch triangle_stretch(const double q[3][3], const double uv[3][2]) {
  TriangleStretch r;
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) e1[k] = q[1][k] - q[0][k], e2[k] = q[2][k] - q[0][k];
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
  r.area3 = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const double(*s)[2] = uv;
  r.area_uv =
      0.5 * ((s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) - (s[2][0] - s[0][0]) * (s[1][1] - s[0][1]));
  if (r.area_uv == 0 || !std::isfinite(r.area_uv)) return r;
  // Partial derivatives of the surface point along s and t.
  const double d = 2 * r.area_uv;
  double Ss[3], St[3];
  for (int k = 0; k < 3; ++k) {
    Ss[k] = (q[0][k] * (s[1][1] - s[2][1]) + q[1][k] * (s[2][1] - s[0][1]) +
             q[2][k] * (s[0][1] - s[1][1])) /
            d;
    St[k] = (q[0][k] * (s[2][0] - s[1][0]) + q[1][k] * (s[0][0] - s[2][0]) +
             q[2][k] * (s[1][0] - s[0][0])) /
            d;
  }
  const double a = Ss[0] * Ss[0] + Ss[1] * Ss[1] + Ss[2] * Ss[2];
  const double b = Ss[0] * St[0] + Ss[1] * St[1] + Ss[2] * St[2];
  const double c = St[0] * St[0] + St[1] * St[1] + St[2] * St[2];
  r.l2_sq = (a + c) / 2;
  r.gamma = std::sqrt(std::max(0.0, ((a + c) + std::sqrt((a - c) * (a - c) + 4 * b * b)) / 2));
  return r;
}

}  // namespace limn::atlas
