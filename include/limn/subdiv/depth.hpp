// limn subdiv: view-dependent isolation depth per vertex (the "FPU" of Lin, Wang, Sun 2018,
// in the sound form of ../shared/design/subdivision.md).
//
// Around an irregular vertex v the error of the patches at depth d shrinks like r_v^d. The design
// note's r = mu_n (the sub-subdominant eigenvalue of the Catmull-Clark subdivision matrix) holds
// for the error normal to the surface; measured at equal parameters (what limn's tests bound)
// the end caps' error shrinks like max(lambda_n, 1/2), lambda_n the subdominant eigenvalue, so
// limn uses that. With K_v the depth-0 error in object units and s_v the projected scale in
// pixels per unit near v,
//     d_v = clamp(ceil(log(K_v s_v / tau) / log(1 / r_v)), d_min, d_max)
// keeps the screen error under tau pixels. K_v = c_n * D_v: D_v is the largest second difference
// of v's ring, c_n a factor per valence calibrated against deep reference surfaces
// (bench/calibrate_depth.cpp prints it).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {

/// A pinhole camera: eye, target, up (object units), vertical field of view and image size.
struct Camera {
  float eye[3] = {0, 0, 5}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  float fovy_deg = 45.0f;
  int width = 1280, height = 720;
  /// Pixels per object unit at point p: f_px / z with z the depth along the view axis (z is
  /// clamped to 1e-6 of the eye-target distance, so points at or behind the eye count as very
  /// near: they get the deepest level, which is safe). `radius` > 0: the largest scale within
  /// that distance of p (z reduced by radius).
  double scale_at(const float p[3], double radius = 0) const;
  /// Projects p to pixel coordinates (x right, y down); false when p is behind the eye.
  bool project(const float p[3], double& x, double& y) const;
  /// The ball of `radius` around p lies wholly outside the view (beyond a side of the image or
  /// behind the eye), so nothing in it can be seen. Conservative: false when unsure.
  bool ball_outside(const float p[3], double radius) const;
};

/// A camera's projection set up once for many points (the view axis and frame, the focal length
/// in pixels): the same results as Camera::project, ball_outside and scale_at, which build one
/// per call. O(1) per point.
class CameraView {
 public:
  explicit CameraView(const Camera& c);
  /// Camera::project.
  bool project(const float p[3], double& x, double& y) const {
    if (!framed_) return false;
    const double d[3] = {double(p[0]) - eye_[0], double(p[1]) - eye_[1], double(p[2]) - eye_[2]};
    const double z = dot(d, f_);
    if (z <= 0) return false;
    x = half_w_ + f_px_ * dot(d, r_) / z;
    y = half_h_ - f_px_ * dot(d, u_) / z;
    return true;
  }
  /// Camera::ball_outside.
  bool ball_outside(const float p[3], double radius) const {
    if (!(distance_ > 0) || !framed_) return false;
    const double d[3] = {double(p[0]) - eye_[0], double(p[1]) - eye_[1], double(p[2]) - eye_[2]};
    const double z = dot(d, f_), x = dot(d, r_), y = dot(d, u_);
    if (z + radius <= 0) return true;
    return (std::abs(x) - hx_ * z) * nx_ > radius || (std::abs(y) - hy_ * z) * ny_ > radius;
  }
  /// Camera::scale_at.
  double scale_at(const float p[3], double radius = 0) const {
    if (!(distance_ > 0)) return 0.0;
    const double d[3] = {double(p[0]) - eye_[0], double(p[1]) - eye_[1], double(p[2]) - eye_[2]};
    const double z = std::max(dot(d, f_) - radius, 1e-6 * distance_);
    return f_px_ / z;
  }

 private:
  static double dot(const double* a, const double* b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  }
  double eye_[3], f_[3] = {}, r_[3] = {}, u_[3] = {};
  double distance_ = 0, f_px_ = 0, half_w_ = 0, half_h_ = 0;
  double hx_ = 0, hy_ = 0, nx_ = 0, ny_ = 0;
  bool framed_ = false;  // the up vector is not along the view axis
};

/// A camera looking at the bounding box's centre from +z (slightly raised), framing the whole
/// box in a width x height image.
Camera frame_camera(const Mesh& mesh, int width, int height);

/// `view` moved along its view axis and sideways (its direction, up, field of view and image
/// kept) so that every point (3 floats each) projects inside the image with `margin` (a
/// fraction of the image's width and height) free on each side, the points' extent spanning
/// the image on one axis and centred on the other: a shape fills the picture, whatever its
/// proportions. The target moves to the view axis at the middle of the points' depth range.
/// Returns `view` unchanged for no points or a margin outside [0, 0.45]. O(points).
Camera fit_camera(const Camera& view, std::span<const float> points, double margin = 0.04);

/// The subdominant (lambda) and sub-subdominant (mu) eigenvalues of the Catmull-Clark
/// subdivision matrix of a smooth interior vertex of valence n >= 3.
void catmark_eigenvalues(int valence, double& lambda, double& mu);

/// Depth-0 error constants, one per cage vertex (object units): 0 for regular vertices, whose
/// patches are exact; K_v = c_n D_v for the others. O(corners).
struct VertexErrorModel {
  std::vector<float> k;         ///< K_v
  std::vector<float> d;         ///< D_v, the ring's largest second difference (object units)
  std::vector<float> mu;        ///< error decay per level r_v (max(lambda_n, 1/2); 1/2 at features)
  std::vector<uint8_t> smooth;  ///< 1: a smooth interior extraordinary vertex (mu = mu_n)
  std::vector<float> radius;    ///< distance to the farthest ring vertex: the scale is taken at
                                ///< the ring's nearest possible point, not only at v
  /// Measured (measure_vertex_errors), levels 0 to levels - 1, levels per vertex: the largest
  /// error in object units of the end caps that stay at that level because of v's depth, and
  /// the farthest of their samples from v. Empty: the depths come from K_v and r_v alone.
  int levels = 0;
  std::vector<float> level_error, level_reach;
};
VertexErrorModel vertex_error_model(const Mesh& cage, const SubdivOptions& options);

/// Replaces the estimate by measurement, for views that select from a hierarchy: every end cap
/// of the hierarchy above its deepest level is compared, on a 5 x 5 grid of samples, with the
/// hierarchy's own deepest surface there, and its error goes to each cage vertex whose depth
/// keeps it (PatchHierarchy::node_src). The error of the deepest level itself (K_v r_v^D) is
/// added, so the bound is against the exact limit; below the hierarchy's depth the error goes
/// on shrinking by r_v per level. Exact per vertex where the valence factors are maxima over
/// many rings, so views need fewer patches for the same tolerance. `hierarchy` must be the
/// cage's. O(end caps * 25 * depth), multi-threaded.
void measure_vertex_errors(const Mesh& cage, const PatchHierarchy& hierarchy,
                           VertexErrorModel& model);

struct DepthOptions {
  float tolerance_px = 0.5f;
  int min_depth = 0, max_depth = 8;
  float hysteresis = 0.25f;  ///< levels: a depth only drops once the need is this far below it
};

/// Per-vertex depths for a view. `previous` (empty, or the last selection) gives hysteresis:
/// depth rises as soon as the view needs it and falls only when the need drops `hysteresis`
/// levels below the current depth, so the tolerance holds while small camera moves do not
/// flicker. `overrides` (empty, or one per vertex; 255 = none) pins depths. `estimate_px`, when
/// given, gets each vertex's estimated screen error at its chosen depth. With measured errors
/// (measure_vertex_errors) a vertex whose end caps all lie outside the view keeps min_depth:
/// what cannot be seen needs no accuracy. O(vertices).
std::vector<uint8_t> select_depths(const Mesh& cage, const VertexErrorModel& model,
                                   const Camera& camera, const DepthOptions& options,
                                   std::span<const uint8_t> previous = {},
                                   std::span<const uint8_t> overrides = {},
                                   std::vector<float>* estimate_px = nullptr);

}  // namespace limn
