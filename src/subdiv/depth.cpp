// View-dependent depth per vertex (see the header).
#include "limn/subdiv/depth.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "limn/mesh/topology.hpp"

namespace limn {

namespace {

double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// c_n of K_v = c_n D_v for smooth interior extraordinary vertices (index n - 3, n >= 12 use
// the last), and c for every other irregular vertex (creases, corners, boundaries,
// non-manifold, next to non-quads). Measured by build/bench/limn_calibrate_depth --seeds 8
// (2026-12-01): the largest ratio of the end-cap error (at equal parameters, against a
// reference at depth 12) to D_v r^d over random tori at depths 1-6 was flat in d: 0.052
// (n = 3), 0.051 (5), 0.093 (6), 0.105 (7), 0.207 (8), 0.120 (9), 0.145 (10, 11), 0.200 (12);
// 0.52 on the crease cage. The constants are those maxima (at least 0.2 from n = 8 up, where
// the spread says the samples are few); the deep-reference test bounds the result (the errors
// it measures stay at 0.16-0.66 of the tolerance, since D_v is a maximum over the ring).
constexpr double kSmooth[10] = {0.052, 0.052, 0.052, 0.093, 0.105, 0.207, 0.2, 0.2, 0.2, 0.2};
constexpr double kOther = 0.52;

}  // namespace

void catmark_eigenvalues(int n, double& lambda, double& mu) {
  std::vector<double> ev;
  for (int k = 1; k < n; ++k) {
    const double c = std::cos(2.0 * std::numbers::pi * k / n);
    const double r = std::sqrt((1.0 + c) * (9.0 + c));
    ev.push_back((5.0 + c + r) / 16.0);
    ev.push_back((5.0 + c - r) / 16.0);
  }
  // k = 0: besides 1, the roots of t^2 - (3/4 - 7/(4n)) t + (1 - 3/n)/16.
  const double b = 0.75 - 7.0 / (4.0 * n), c0 = (1.0 - 3.0 / n) / 16.0;
  const double disc = std::sqrt(std::max(0.0, b * b - 4.0 * c0));
  ev.push_back((b + disc) / 2.0);
  ev.push_back((b - disc) / 2.0);
  std::sort(ev.begin(), ev.end(), std::greater<>());
  lambda = ev[0];
  mu = lambda;
  for (double x : ev)
    if (x < lambda - 1e-9) {
      mu = x;
      break;
    }
}

namespace {

// The view axis (unit), the eye-target distance and the focal length in pixels.
struct ViewAxis {
  double f[3] = {}, distance = 0, f_px = 0;
};

ViewAxis view_axis(const Camera& c) {
  ViewAxis a;
  for (int k = 0; k < 3; ++k) a.f[k] = double(c.target[k]) - c.eye[k];
  a.distance = std::sqrt(dot3(a.f, a.f));
  if (a.distance > 0)
    for (double& x : a.f) x /= a.distance;
  a.f_px = c.height / (2.0 * std::tan(0.5 * double(c.fovy_deg) * std::numbers::pi / 180.0));
  return a;
}

}  // namespace

double Camera::scale_at(const float p[3], double radius) const {
  const ViewAxis a = view_axis(*this);
  if (!(a.distance > 0)) return 0.0;
  const double d[3] = {double(p[0]) - eye[0], double(p[1]) - eye[1], double(p[2]) - eye[2]};
  const double z = std::max(dot3(d, a.f) - radius, 1e-6 * a.distance);
  return a.f_px / z;
}

bool Camera::project(const float p[3], double& x, double& y) const {
  const ViewAxis a = view_axis(*this);
  const double* f = a.f;
  // right = f x up, true up = right x f
  double r[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                 f[0] * up[1] - f[1] * up[0]};
  const double l = std::sqrt(dot3(r, r));
  if (!(l > 0)) return false;
  for (double& c : r) c /= l;
  const double u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2],
                       r[0] * f[1] - r[1] * f[0]};
  const double d[3] = {double(p[0]) - eye[0], double(p[1]) - eye[1], double(p[2]) - eye[2]};
  const double z = dot3(d, f);
  if (z <= 0) return false;
  x = 0.5 * width + a.f_px * dot3(d, r) / z;
  y = 0.5 * height - a.f_px * dot3(d, u) / z;
  return true;
}

Camera frame_camera(const Mesh& mesh, int width, int height) {
  const Box b = bounding_box(mesh);
  Camera c;
  c.width = width, c.height = height;
  float centre[3], radius = 0.5f * std::max(b.diagonal(), 1e-6f);
  for (int k = 0; k < 3; ++k) centre[k] = b.empty() ? 0.0f : 0.5f * (b.min[k] + b.max[k]);
  const double fov = double(c.fovy_deg) * std::numbers::pi / 180.0;
  const double aspect = double(width) / std::max(height, 1);
  const double half = std::min(fov, 2.0 * std::atan(std::tan(0.5 * fov) * aspect)) * 0.5;
  const float dist = float(radius / std::sin(half));
  for (int k = 0; k < 3; ++k) c.target[k] = centre[k];
  c.eye[0] = centre[0];
  c.eye[1] = centre[1] + 0.3f * dist;
  c.eye[2] = centre[2] + 0.954f * dist;
  return c;
}

VertexErrorModel vertex_error_model(const Mesh& cage, const SubdivOptions& options) {
  (void)options;
  const size_t nv = cage.vertex_count();
  const Topology t = build_topology(cage);
  const uint32_t* fv = cage.face_vertices.data();
  const float* p = cage.positions.data();
  std::vector<float> sharp_vertex(nv, 0.0f);
  for (size_t i = 0; i < cage.corner_vertices.size(); ++i)
    sharp_vertex[cage.corner_vertices[i]] = cage.corner_sharpness[i];
  std::vector<uint8_t> crease(nv, 0);
  for (size_t i = 0; i < cage.crease_sharpness.size(); ++i)
    if (cage.crease_sharpness[i] > 0)
      crease[cage.crease_edges[2 * i]] = crease[cage.crease_edges[2 * i + 1]] = 1;

  VertexErrorModel m;
  m.k.assign(nv, 0.0f);
  m.d.assign(nv, 0.0f);
  m.mu.assign(nv, 0.5f);
  m.smooth.assign(nv, 0);
  m.radius.assign(nv, 0.0f);
  std::vector<uint32_t> ring_e, ring_f;
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t s0 = t.vertex_offsets[v], n = t.vertex_offsets[v + 1] - s0;
    if (n == 0) continue;
    bool boundary = false, quads = true, manifold = true;
    uint32_t start = t.vertex_corners[s0];
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = t.vertex_corners[s0 + i];
      if (t.corner_twin[c] == kNone && !boundary) start = c, boundary = true;
      if (t.corner_twin[c] == kNonManifold) manifold = false;
      const uint32_t f = t.corner_face[c];
      quads = quads && cage.face_size(f) == 4;
    }
    ring_e.clear(), ring_f.clear();
    uint32_t c = start;
    for (uint32_t i = 0; i < n && manifold; ++i) {
      ring_e.push_back(fv[t.corner_next[c]]);
      ring_f.push_back(fv[t.corner_next[t.corner_next[c]]]);
      const uint32_t in = t.corner_prev[c], tw = t.corner_twin[in];
      if (tw == kNone) {
        ring_e.push_back(fv[in]);
        break;
      }
      if (tw >= kNonManifold || tw == start) break;
      c = tw;
    }
    if (ring_f.size() != n) manifold = false;
    const bool features = crease[v] || sharp_vertex[v] > 0;
    const bool regular =
        manifold && quads && !features && ((!boundary && n == 4) || (boundary && n == 2));
    if (regular) continue;
    // D_v: the largest second difference across the vertex (ring point, v, opposite point).
    double D = 0;
    auto second = [&](uint32_t a, uint32_t b, double w) {
      double s = 0;
      for (int k = 0; k < 3; ++k) {
        const double x = double(p[3 * a + k]) + p[3 * b + k] - 2.0 * p[3 * v + k];
        s += x * x;
      }
      D = std::max(D, w * std::sqrt(s));
    };
    const size_t ne = ring_e.size();
    if (manifold && ne >= 2) {
      if (boundary) {
        second(ring_e.front(), ring_e.back(), 1.0);
        for (size_t i = 1; i + 1 < ne; ++i) second(ring_e[i], v, 1.0);
      } else {
        for (size_t i = 0; i < ne; ++i) second(ring_e[i], ring_e[(i + ne / 2) % ne], 1.0);
        for (size_t i = 0; i < ring_f.size(); ++i)
          second(ring_f[i], ring_f[(i + ne / 2) % ne], 0.5);
      }
    } else {
      // No ring: the longest edge at the vertex bounds what the patches there can be off by.
      for (uint32_t i = 0; i < n; ++i) second(fv[t.corner_next[t.vertex_corners[s0 + i]]], v, 1.0);
    }
    m.d[v] = float(D);
    double r2 = 0;
    for (uint32_t i = 0; i < n; ++i)
      for (const uint32_t w : {fv[t.corner_next[t.vertex_corners[s0 + i]]],
                               fv[t.corner_next[t.corner_next[t.vertex_corners[s0 + i]]]]}) {
        double x = 0;
        for (int k = 0; k < 3; ++k) x += std::pow(double(p[3 * w + k]) - p[3 * v + k], 2);
        r2 = std::max(r2, x);
      }
    m.radius[v] = float(std::sqrt(r2));
    if (manifold && quads && !features && !boundary) {
      // Measured (limn_calibrate_depth): the end caps' error at equal parameters shrinks like
      // the subdominant eigenvalue (the ring's size), never faster than 1/2 per level; mu_n
      // would only bound the error normal to the surface.
      double lambda, mu;
      catmark_eigenvalues(int(n), lambda, mu);
      m.mu[v] = float(std::max(lambda, 0.5));
      m.smooth[v] = 1;
      m.k[v] = float(kSmooth[std::min<uint32_t>(n - 3, 9)] * D);
    } else {
      m.k[v] = float(kOther * D);
    }
  }
  return m;
}

std::vector<uint8_t> select_depths(const Mesh& cage, const VertexErrorModel& model,
                                   const Camera& camera, const DepthOptions& o,
                                   std::span<const uint8_t> previous,
                                   std::span<const uint8_t> overrides,
                                   std::vector<float>* estimate_px) {
  const size_t nv = cage.vertex_count();
  if (model.k.size() != nv) throw InputError("select depths: the error model is another cage's");
  if (!previous.empty() && previous.size() != nv)
    throw InputError(
        fmt::format("select depths: {} previous depths for {} vertices", previous.size(), nv));
  if (!overrides.empty() && overrides.size() != nv)
    throw InputError(
        fmt::format("select depths: {} overrides for {} vertices", overrides.size(), nv));
  if (!(o.tolerance_px > 0))
    throw InputError(
        fmt::format("select depths: tolerance {} px must be positive", o.tolerance_px));
  if (o.min_depth < 0 || o.max_depth > 12 || o.min_depth > o.max_depth)
    throw InputError(
        fmt::format("select depths: depth range {}-{} (0-12)", o.min_depth, o.max_depth));
  std::vector<uint8_t> d(nv, uint8_t(o.min_depth));
  if (estimate_px) estimate_px->assign(nv, 0.0f);
  for (size_t v = 0; v < nv; ++v) {
    if (!overrides.empty() && overrides[v] != 255) {
      d[v] = std::min<uint8_t>(overrides[v], 12);
    } else if (model.k[v] > 0) {
      // The error left at depth d lies in the end caps, within radius * r^d of v (the ring
      // shrinks by at most r per level): take the scale there, and the shallowest d that is
      // enough for its own region.
      const double r = double(model.mu[v]), k = double(model.k[v]);
      auto need_at = [&](int depth) {
        const double reach = model.radius[v] * std::pow(r, std::max(depth, 0));
        const double s = camera.scale_at(&cage.positions[3 * v], reach);
        return std::log(k * s / o.tolerance_px) / std::log(1.0 / r);
      };
      int depth = 0;
      double need = need_at(0);
      while (depth < 12 && need > depth + 1e-9) need = need_at(++depth);
      // Hysteresis: hold a deeper previous depth until the need falls clearly below it.
      if (!previous.empty() && previous[v] > depth && need > previous[v] - 1 - o.hysteresis)
        depth = previous[v];
      d[v] = uint8_t(std::clamp(depth, o.min_depth, o.max_depth));
    }
    if (estimate_px && model.k[v] > 0) {
      const double reach = model.radius[v] * std::pow(double(model.mu[v]), d[v]);
      (*estimate_px)[v] = float(model.k[v] * camera.scale_at(&cage.positions[3 * v], reach) *
                                std::pow(double(model.mu[v]), d[v]));
    }
  }
  return d;
}

}  // namespace limn
