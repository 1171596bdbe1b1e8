// Least-squares conformal maps (Levy, Petitjean, Ray, Maillot 2002) in the form of Mullen et al.
// 2008: E_C(u, v) = E_D(u) + E_D(v) - A(u, v), the Dirichlet energy (cotangent weights) minus
// the signed area of the image, which is zero exactly for conformal maps. A is a sum over the
// chart's boundary edges, so the coupling between u and v is there alone. Two pinned vertices
// remove the similarity the energy is blind to; what is left is symmetric positive definite.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <array>
#include <cmath>

#include "atlas/chart.hpp"

namespace limn::atlas {

namespace {

std::array<double, 3> point(const VsaSurface& s, const Chart& ch, uint32_t v) {
  const float* p = &s.mesh->positions[3 * size_t(ch.vertex_source[v])];
  return {p[0], p[1], p[2]};
}

double distance2(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
         (a[2] - b[2]) * (a[2] - b[2]);
}

// The chart vertex farthest from `from` (3D distance).
uint32_t farthest(const VsaSurface& s, const Chart& ch, uint32_t from) {
  const auto p = point(s, ch, from);
  uint32_t best = from;
  double d = -1;
  for (uint32_t v = 0; v < ch.vertex_source.size(); ++v) {
    const double dv = distance2(p, point(s, ch, v));
    if (dv > d) d = dv, best = v;
  }
  return best;
}

// Scales the UVs so their total area equals the surface area; false when the map has no area.
bool scale_to_area(const VsaSurface& s, Chart& ch) {
  double area_uv = 0, area3 = 0;
  for (size_t t = 0; t < ch.triangles.size(); t += 3) {
    const uint32_t a = ch.triangles[t], b = ch.triangles[t + 1], c = ch.triangles[t + 2];
    const double* u = ch.uv.data();
    area_uv += 0.5 * ((u[2 * b] - u[2 * a]) * (u[2 * c + 1] - u[2 * a + 1]) -
                      (u[2 * c] - u[2 * a]) * (u[2 * b + 1] - u[2 * a + 1]));
    const auto p = point(s, ch, a), q = point(s, ch, b), r = point(s, ch, c);
    const double e1[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double e2[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    area3 += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  if (!(area_uv > 0) || !(area3 > 0) || !std::isfinite(area_uv)) return false;
  const double k = std::sqrt(area3 / area_uv);
  for (double& x : ch.uv) x *= k;
  return true;
}

}  // namespace

bool conformal_map(const VsaSurface& s, Chart& ch) {
  const uint32_t n = uint32_t(ch.vertex_source.size());
  if (n < 3) return false;
  const uint32_t pin0 = farthest(s, ch, farthest(s, ch, 0));
  const uint32_t pin1 = farthest(s, ch, pin0);
  const double length = std::sqrt(distance2(point(s, ch, pin0), point(s, ch, pin1)));
  if (pin0 == pin1 || !(length > 0)) return false;

  // Unknowns: u of every vertex, then v of every vertex; the pinned four are moved to the right.
  std::vector<double> pinned(2 * size_t(n), NAN);
  pinned[pin0] = 0, pinned[n + pin0] = 0, pinned[pin1] = length, pinned[n + pin1] = 0;
  std::vector<int> free_index(2 * size_t(n), -1);
  int unknowns = 0;
  for (size_t i = 0; i < 2 * size_t(n); ++i)
    if (std::isnan(pinned[i])) free_index[i] = unknowns++;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(ch.triangles.size() * 8 + ch.boundary.size() * 2);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(unknowns);
  auto add = [&](size_t r, size_t c, double value) {
    if (free_index[r] < 0) return;
    if (free_index[c] >= 0)
      entries.emplace_back(free_index[r], free_index[c], value);
    else
      rhs[free_index[r]] -= value * pinned[c];
  };

  const double diag = s.bbox.diagonal();
  const double tiny = 1e-14 * diag * diag;
  for (size_t t = 0; t < ch.triangles.size(); t += 3) {
    const uint32_t v[3] = {ch.triangles[t], ch.triangles[t + 1], ch.triangles[t + 2]};
    const std::array<double, 3> p[3] = {point(s, ch, v[0]), point(s, ch, v[1]), point(s, ch, v[2])};
    for (int i = 0; i < 3; ++i) {
      // The angle at corner i weighs the opposite edge (a, b): E_D = 1/4 sum cot (x_a - x_b)^2.
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      double e1[3], e2[3];
      for (int k = 0; k < 3; ++k) e1[k] = p[a][k] - p[i][k], e2[k] = p[b][k] - p[i][k];
      const double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
      const double sine = std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
      if (!(sine > tiny)) break;  // a triangle without area carries no energy
      const double w = 0.5 * (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / sine;
      for (size_t off : {size_t(0), size_t(n)}) {
        add(off + v[a], off + v[a], w), add(off + v[b], off + v[b], w);
        add(off + v[a], off + v[b], -w), add(off + v[b], off + v[a], -w);
      }
    }
  }
  // -A = -1/2 sum over boundary edges (a -> b) of (u_a v_b - u_b v_a).
  for (size_t e = 0; e < ch.boundary.size(); e += 2) {
    const uint32_t a = ch.boundary[e], b = ch.boundary[e + 1];
    add(a, n + b, -0.5), add(n + b, a, -0.5);
    add(b, n + a, 0.5), add(n + a, b, 0.5);
  }

  Eigen::SparseMatrix<double> m(unknowns, unknowns);
  m.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(m);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::VectorXd x = solver.solve(rhs);
  if (solver.info() != Eigen::Success) return false;

  ch.uv.assign(2 * size_t(n), 0);
  for (uint32_t i = 0; i < n; ++i)
    for (int k = 0; k < 2; ++k) {
      const size_t var = size_t(k) * n + i;
      const double value = free_index[var] >= 0 ? x[free_index[var]] : pinned[var];
      if (!std::isfinite(value)) return false;
      ch.uv[2 * size_t(i) + k] = value;
    }
  return scale_to_area(s, ch);
}

void planar_map(const VsaSurface& s, Chart& ch) {
  double n[3] = {0, 0, 0};
  for (uint32_t f : ch.faces)
    for (int k = 0; k < 3; ++k) n[k] += s.vec[3 * size_t(f) + k];
  double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0)) n[0] = 0, n[1] = 0, n[2] = 1, len = 1;
  for (double& x : n) x /= len;
  // Any unit vector across the normal, then the third of a right-handed frame.
  double a[3] = {0, 0, 0};
  a[std::fabs(n[0]) < 0.9 ? 0 : 1] = 1;
  const double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
  for (int k = 0; k < 3; ++k) a[k] -= d * n[k];
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (double& x : a) x /= la;
  const double b[3] = {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2],
                       n[0] * a[1] - n[1] * a[0]};
  ch.uv.assign(2 * ch.vertex_source.size(), 0);
  for (uint32_t v = 0; v < ch.vertex_source.size(); ++v) {
    const auto p = point(s, ch, v);
    ch.uv[2 * size_t(v)] = p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
    ch.uv[2 * size_t(v) + 1] = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
  }
  scale_to_area(s, ch);
}

}  // namespace limn::atlas
