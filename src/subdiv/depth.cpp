// View-dependent depth per vertex (see the header).
#include "limn/subdiv/depth.hpp"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

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

// The camera's frame: right = f x up and the true up = right x f (unit); false when the up
// vector is parallel to the view axis.
bool view_frame(const Camera& c, const ViewAxis& a, double r[3], double u[3]) {
  const double* f = a.f;
  r[0] = f[1] * c.up[2] - f[2] * c.up[1];
  r[1] = f[2] * c.up[0] - f[0] * c.up[2];
  r[2] = f[0] * c.up[1] - f[1] * c.up[0];
  const double l = std::sqrt(dot3(r, r));
  if (!(l > 0)) return false;
  for (int k = 0; k < 3; ++k) r[k] /= l;
  u[0] = r[1] * f[2] - r[2] * f[1];
  u[1] = r[2] * f[0] - r[0] * f[2];
  u[2] = r[0] * f[1] - r[1] * f[0];
  return true;
}

}  // namespace

CameraView::CameraView(const Camera& c) {
  const ViewAxis a = view_axis(c);
  for (int k = 0; k < 3; ++k) eye_[k] = c.eye[k], f_[k] = a.f[k];
  distance_ = a.distance, f_px_ = a.f_px;
  half_w_ = 0.5 * c.width, half_h_ = 0.5 * c.height;
  framed_ = view_frame(c, a, r_, u_);
  // Side planes through the eye: x = +-z w / (2 f_px), y = +-z h / (2 f_px), and the factors
  // that turn a point's offset from them into a distance.
  hx_ = 0.5 * c.width / a.f_px, hy_ = 0.5 * c.height / a.f_px;
  nx_ = 1.0 / std::sqrt(1.0 + hx_ * hx_), ny_ = 1.0 / std::sqrt(1.0 + hy_ * hy_);
}

double Camera::scale_at(const float p[3], double radius) const {
  return CameraView(*this).scale_at(p, radius);
}

bool Camera::project(const float p[3], double& x, double& y) const {
  return CameraView(*this).project(p, x, y);
}

bool Camera::ball_outside(const float p[3], double radius) const {
  return CameraView(*this).ball_outside(p, radius);
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

Camera fit_camera(const Camera& view, std::span<const float> points, double margin) {
  const size_t n = points.size() / 3;
  if (n == 0 || !(margin >= 0 && margin <= 0.45)) return view;
  // The view's frame: forward f, right r, up u (orthonormal).
  double f[3], u[3], r[3];
  for (int k = 0; k < 3; ++k) f[k] = double(view.target[k]) - view.eye[k], u[k] = view.up[k];
  auto dot3 = [](const double* a, const double* b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  auto unit = [&](double* a) {
    const double l = std::sqrt(dot3(a, a));
    if (!(l > 0)) return false;
    for (int k = 0; k < 3; ++k) a[k] /= l;
    return true;
  };
  if (!unit(f)) return view;
  r[0] = f[1] * u[2] - f[2] * u[1], r[1] = f[2] * u[0] - f[0] * u[2],
  r[2] = f[0] * u[1] - f[1] * u[0];
  if (!unit(r)) return view;
  u[0] = r[1] * f[2] - r[2] * f[1], u[1] = r[2] * f[0] - r[0] * f[2],
  u[2] = r[0] * f[1] - r[1] * f[0];
  // The image's half extents as tangents, less the margin.
  const double ty = std::tan(0.5 * double(view.fovy_deg) * std::numbers::pi / 180.0);
  const double tx = ty * double(view.width) / std::max(view.height, 1);
  const double hx = tx * (1 - 2 * margin), hy = ty * (1 - 2 * margin);
  // A point at (a, b, d) in the frame (about the old eye), seen from an eye moved to
  // s_r r + s_u u - t f, fits when |a - s_r| <= hx (d + t) and |b - s_u| <= hy (d + t). Over all
  // points: max(a - hx d) - hx t <= s_r <= min(a + hx d) + hx t, which has room once
  // t >= (max(a - hx d) - min(a + hx d)) / (2 hx); the same in b. The nearest such eye frames
  // the points.
  double amax = -HUGE_VAL, amin = HUGE_VAL, bmax = -HUGE_VAL, bmin = HUGE_VAL;
  double dmin = HUGE_VAL, dmax = -HUGE_VAL;
  for (size_t i = 0; i < n; ++i) {
    const double p[3] = {double(points[3 * i]) - view.eye[0],
                         double(points[3 * i + 1]) - view.eye[1],
                         double(points[3 * i + 2]) - view.eye[2]};
    const double a = dot3(p, r), b = dot3(p, u), d = dot3(p, f);
    amax = std::max(amax, a - hx * d), amin = std::min(amin, a + hx * d);
    bmax = std::max(bmax, b - hy * d), bmin = std::min(bmin, b + hy * d);
    dmin = std::min(dmin, d), dmax = std::max(dmax, d);
  }
  if (!std::isfinite(amax + amin + bmax + bmin + dmin + dmax)) return view;
  double t = std::max((amax - amin) / (2 * hx), (bmax - bmin) / (2 * hy));
  // Every point in front of the eye, by a little of the depth range at least.
  t = std::max(t, -dmin + 1e-3 * std::max(dmax - dmin, 1e-9));
  // The shifts centre the points' extent: the middle of each feasible interval.
  // Each shift centres the points' image on its axis: the largest and the smallest of
  // (a - s) / (d + t) opposite (found by bisection: their sum falls as s grows). On the axis
  // that fixed t the interval is a single shift.
  auto centre = [&](const double* axis, double lo, double hi) {
    for (int it = 0; it < 60 && hi - lo > 1e-12 * (std::abs(lo) + std::abs(hi) + 1); ++it) {
      const double s = 0.5 * (lo + hi);
      double most = -HUGE_VAL, least = HUGE_VAL;
      for (size_t i = 0; i < n; ++i) {
        const double p[3] = {double(points[3 * i]) - view.eye[0],
                             double(points[3 * i + 1]) - view.eye[1],
                             double(points[3 * i + 2]) - view.eye[2]};
        const double x = (dot3(p, axis) - s) / (dot3(p, f) + t);
        most = std::max(most, x), least = std::min(least, x);
      }
      (most + least > 0 ? lo : hi) = s;
    }
    return 0.5 * (lo + hi);
  };
  const double sr = centre(r, amax - hx * t, amin + hx * t);
  const double su = centre(u, bmax - hy * t, bmin + hy * t);
  const double centre_depth = 0.5 * (dmin + dmax) + t;
  Camera c = view;
  for (int k = 0; k < 3; ++k) {
    const double eye = view.eye[k] + sr * r[k] + su * u[k] - t * f[k];
    c.eye[k] = float(eye);
    c.target[k] = float(eye + centre_depth * f[k]);
  }
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

namespace {

// Samples per end-cap edge in measure_vertex_errors, and the margin on the largest sampled
// error for what lies between samples (the error is smooth over a patch: at most a few per cent
// above the 5 x 5 maximum in the deep-reference tests).
constexpr int kSamples = 5;
constexpr double kSampleMargin = 1.15;

}  // namespace

void measure_vertex_errors(const Mesh& cage, const PatchHierarchy& h, VertexErrorModel& m) {
  const size_t nv = cage.vertex_count();
  const PatchTable& t = h.table;
  if (m.k.size() != nv)
    throw InputError("measure vertex errors: the error model is another cage's");
  if (t.level_offsets.size() < 2 || t.level_offsets[1] != nv || h.roots.empty() != (nv == 0))
    throw InputError("measure vertex errors: the hierarchy is another cage's");
  int depth = 0;
  for (const uint8_t l : h.node_level) depth = std::max(depth, int(l));
  m.levels = depth;
  m.level_error.assign(nv * size_t(depth), 0.0f);
  m.level_reach.assign(nv * size_t(depth), 0.0f);
  if (depth == 0) return;
  const size_t nr = t.regular_params.size();
  auto patch_of = [&](uint32_t node) {
    const uint32_t p = h.node_patch[node];
    return p & kPatchGregory ? uint32_t(nr) + (p & ~kPatchGregory) : p;
  };
  auto param = [&](uint32_t patch) -> const PatchParam& {
    return patch < nr ? t.regular_params[patch] : t.gregory_params[patch - nr];
  };
  // End caps that have a deeper surface below them and whose level some vertex's depth decides.
  std::vector<uint32_t> caps;
  for (uint32_t n = 0; n < h.node_count(); ++n)
    if (h.node_patch[n] != kNone && (h.node_patch[n] & kPatchGregory) &&
        h.node_first_child[n] != kNone && h.node_src_offsets[n + 1] > h.node_src_offsets[n])
      caps.push_back(n);
  constexpr size_t kPer = size_t(kSamples) * kSamples;
  std::vector<PatchCoord> at(caps.size() * kPer), deep(caps.size() * kPer);
  tbb::parallel_for(size_t(0), caps.size(), [&](size_t i) {
    const uint32_t n = caps[i], patch = patch_of(n);
    const PatchParam& pp = param(patch);
    const double size = 1.0 / double(1u << pp.depth);
    for (int y = 0; y < kSamples; ++y)
      for (int x = 0; x < kSamples; ++x) {
        const float s = float(x) / (kSamples - 1), tt = float(y) / (kSamples - 1);
        const size_t j = i * kPer + size_t(y) * kSamples + size_t(x);
        at[j] = {patch, s, tt};
        // The deepest node over the sample: children split their parent's ptex square.
        const double u = (pp.u + double(s)) * size, v = (pp.v + double(tt)) * size;
        uint32_t node = n, leaf_patch = patch;
        while (h.node_first_child[node] != kNone) {
          uint32_t next = kNone;
          for (uint32_t c = 0; c < h.node_children[node] && next == kNone; ++c) {
            const uint32_t child = h.node_first_child[node] + c;
            if (h.node_patch[child] == kNone) continue;
            const PatchParam& q = param(patch_of(child));
            const double cs = 1.0 / double(1u << q.depth), eps = 1e-9;
            if (u >= q.u * cs - eps && u <= (q.u + 1) * cs + eps && v >= q.v * cs - eps &&
                v <= (q.v + 1) * cs + eps)
              next = child;
          }
          if (next == kNone) throw std::logic_error("measure vertex errors: a sample has no child");
          node = next;
          leaf_patch = patch_of(node);
        }
        const PatchParam& q = param(leaf_patch);
        const double cs = double(1u << q.depth);
        deep[j] = {leaf_patch, float(std::clamp(u * cs - q.u, 0.0, 1.0)),
                   float(std::clamp(v * cs - q.v, 0.0, 1.0))};
      }
  });
  const std::vector<float> points = t.points(cage.positions);
  std::vector<float> pa(3 * at.size()), pb(3 * deep.size());
  evaluate_patches(t, points, at, pa.data());
  evaluate_patches(t, points, deep, pb.data());
  for (size_t i = 0; i < caps.size(); ++i) {
    const uint32_t n = caps[i];
    double err = 0;
    for (size_t j = i * kPer; j < (i + 1) * kPer; ++j)
      err = std::max(
          err, std::hypot(double(pa[3 * j]) - pb[3 * j], double(pa[3 * j + 1]) - pb[3 * j + 1],
                          double(pa[3 * j + 2]) - pb[3 * j + 2]));
    for (uint32_t k = h.node_src_offsets[n]; k < h.node_src_offsets[n + 1]; ++k) {
      const uint32_t v = h.node_src[k];
      const float* c = &cage.positions[3 * size_t(v)];
      double reach = 0;
      for (size_t j = i * kPer; j < (i + 1) * kPer; ++j)
        reach = std::max(reach, std::hypot(double(pb[3 * j]) - c[0], double(pb[3 * j + 1]) - c[1],
                                           double(pb[3 * j + 2]) - c[2]));
      const size_t slot = size_t(v) * size_t(depth) + h.node_level[n];
      m.level_error[slot] = std::max(m.level_error[slot], float(err));
      m.level_reach[slot] = std::max(m.level_reach[slot], float(reach));
    }
  }
}

namespace {

// Hysteresis: a deeper previous depth holds until the continuous need falls `hysteresis`
// levels below it.
int hold(std::span<const uint8_t> previous, size_t v, int depth, double need,
         const DepthOptions& o) {
  if (!previous.empty() && previous[v] > depth && need > previous[v] - 1 - o.hysteresis)
    return previous[v];
  return depth;
}

// The measured error bound of v at depth d (object units) and the reach of its end caps.
double measured_error(const VertexErrorModel& m, size_t v, int d, double& reach) {
  const int levels = m.levels;
  const double r = double(m.mu[v]);
  const size_t slot = v * size_t(levels) + size_t(std::min(d, levels - 1));
  double e = kSampleMargin * m.level_error[slot] + double(m.k[v]) * std::pow(r, levels);
  reach = m.level_reach[slot];
  if (d >= levels) {  // below the hierarchy: the error shrinks as the model says
    const double f = std::pow(r, d - levels + 1);
    e *= f, reach *= f;
  }
  return e;
}

// The shallowest depth whose measured error projects within the tolerance, with hysteresis
// against `previous`: the continuous need interpolates the error between levels.
int measured_depth(const Mesh& cage, const VertexErrorModel& m, const CameraView& camera,
                   const DepthOptions& o, size_t v, std::span<const uint8_t> previous) {
  const float* p = &cage.positions[3 * v];
  // Every end cap v's depth governs lies within its reach at some level (the margin covers
  // the patch between samples).
  double reach = m.radius[v];
  for (int d = 0; d < m.levels; ++d)
    reach = std::max(reach, double(m.level_reach[v * size_t(m.levels) + size_t(d)]));
  if (camera.ball_outside(p, kSampleMargin * reach)) return o.min_depth;
  auto ratio = [&](int d) {
    double at;
    const double e = measured_error(m, v, d, at);
    return e * camera.scale_at(p, at) / o.tolerance_px;
  };
  int depth = 0;
  double here = ratio(0), above = here;
  while (depth < 12 && here > 1.0) above = here, here = ratio(++depth);
  double need;
  if (depth == 0) {
    need = here > 0 ? std::log(here) / std::log(1.0 / double(m.mu[v])) : -1e9;
  } else {
    const double span = std::log(above / std::max(here, 1e-300));
    need = depth - 1 + (span > 0 ? std::min(1.0, std::log(above) / span) : 1.0);
  }
  return hold(previous, v, depth, need, o);
}

}  // namespace

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
  if (model.levels < 0 || model.level_error.size() != nv * size_t(model.levels) ||
      model.level_reach.size() != model.level_error.size())
    throw InputError("select depths: the measured errors are another cage's");
  if (!(o.tolerance_px > 0))
    throw InputError(
        fmt::format("select depths: tolerance {} px must be positive", o.tolerance_px));
  if (o.min_depth < 0 || o.max_depth > 12 || o.min_depth > o.max_depth)
    throw InputError(
        fmt::format("select depths: depth range {}-{} (0-12)", o.min_depth, o.max_depth));
  const CameraView view(camera);  // the frame once, not per vertex
  std::vector<uint8_t> d(nv, uint8_t(o.min_depth));
  if (estimate_px) estimate_px->assign(nv, 0.0f);
  for (size_t v = 0; v < nv; ++v) {
    if (!overrides.empty() && overrides[v] != 255) {
      d[v] = std::min<uint8_t>(overrides[v], 12);
    } else if (model.levels > 0) {
      const int depth = measured_depth(cage, model, view, o, v, previous);
      d[v] = uint8_t(std::clamp(depth, o.min_depth, o.max_depth));
    } else if (model.k[v] > 0) {
      // The error left at depth d lies in the end caps, within radius * r^d of v (the ring
      // shrinks by at most r per level): take the scale there, and the shallowest d that is
      // enough for its own region.
      const double r = double(model.mu[v]), k = double(model.k[v]);
      auto need_at = [&](int depth) {
        const double reach = model.radius[v] * std::pow(r, std::max(depth, 0));
        const double s = view.scale_at(&cage.positions[3 * v], reach);
        return std::log(k * s / o.tolerance_px) / std::log(1.0 / r);
      };
      int depth = 0;
      double need = need_at(0);
      while (depth < 12 && need > depth + 1e-9) need = need_at(++depth);
      d[v] = uint8_t(std::clamp(hold(previous, v, depth, need, o), o.min_depth, o.max_depth));
    }
    if (estimate_px && model.levels > 0) {
      double reach;
      const double e = measured_error(model, v, d[v], reach);
      (*estimate_px)[v] = float(e * view.scale_at(&cage.positions[3 * v], reach));
    } else if (estimate_px && model.k[v] > 0) {
      const double reach = model.radius[v] * std::pow(double(model.mu[v]), d[v]);
      (*estimate_px)[v] = float(model.k[v] * view.scale_at(&cage.positions[3 * v], reach) *
                                std::pow(double(model.mu[v]), d[v]));
    }
  }
  return d;
}

}  // namespace limn
