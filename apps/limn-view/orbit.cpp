#include "orbit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace limn::view {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double dot(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void cross(const double* a, const double* b, double* o) {
  o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2],
  o[2] = a[0] * b[1] - a[1] * b[0];
}

bool normalize(double* v) {
  const double l = std::sqrt(dot(v, v));
  if (!(l > 0)) return false;
  for (int k = 0; k < 3; ++k) v[k] /= l;
  return true;
}

}  // namespace

void OrbitCamera::frame(const Mesh& mesh, int width, int height) {
  const Camera c = frame_camera(mesh, width, height);
  width_ = width, height_ = height, fovy_deg_ = c.fovy_deg;
  double offset[3];
  for (int k = 0; k < 3; ++k)
    target_[k] = c.target[k], offset[k] = double(c.eye[k]) - c.target[k], up_[k] = c.up[k];
  normalize(up_);
  distance_ = std::sqrt(dot(offset, offset));
  min_distance_ = std::max(distance_ * 1e-4, 1e-9);
  // The turntable's frame: the initial view direction flattened onto the plane normal to up, so
  // yaw 0 / pitch p reproduces the framed view exactly.
  const double along = dot(offset, up_);
  for (int k = 0; k < 3; ++k) base_[k] = offset[k] - along * up_[k];
  if (!normalize(base_)) {
    // Looking straight along up: any perpendicular base will do.
    const double x[3] = {1, 0, 0}, z[3] = {0, 0, 1};
    cross(up_, std::abs(up_[0]) < 0.9 ? x : z, base_);
    normalize(base_);
  }
  cross(up_, base_, side_);
  yaw_ = 0;
  pitch_ = distance_ > 0 ? std::asin(std::clamp(along / distance_, -1.0, 1.0)) / kDeg : 0;
  ++revision_;
}

void OrbitCamera::orbit(double yaw_deg, double pitch_deg) {
  yaw_ = std::remainder(yaw_ + yaw_deg, 360.0);
  pitch_ = std::clamp(pitch_ + pitch_deg, -85.0, 85.0);
  ++revision_;
}

void OrbitCamera::pan(double dx_px, double dy_px) {
  const Camera c = camera();
  double f[3], up[3] = {c.up[0], c.up[1], c.up[2]}, right[3], cam_up[3];
  for (int k = 0; k < 3; ++k) f[k] = double(c.target[k]) - c.eye[k];
  normalize(f);
  cross(f, up, right);
  normalize(right);
  cross(right, f, cam_up);
  const double per_px = 2 * distance_ * std::tan(0.5 * fovy_deg_ * kDeg) / std::max(height_, 1);
  for (int k = 0; k < 3; ++k) target_[k] += per_px * (-dx_px * right[k] + dy_px * cam_up[k]);
  ++revision_;
}

void OrbitCamera::zoom(double factor) {
  if (factor > 0 && std::isfinite(factor)) distance_ = std::max(distance_ * factor, min_distance_);
  ++revision_;
}

void OrbitCamera::resize(int width, int height) {
  if (width == width_ && height == height_) return;
  width_ = std::max(width, 1), height_ = std::max(height, 1);
  ++revision_;
}

Camera OrbitCamera::camera() const {
  Camera c;
  c.width = width_, c.height = height_, c.fovy_deg = fovy_deg_;
  const double y = yaw_ * kDeg, p = pitch_ * kDeg;
  for (int k = 0; k < 3; ++k) {
    const double dir =
        std::cos(p) * (std::cos(y) * base_[k] + std::sin(y) * side_[k]) + std::sin(p) * up_[k];
    c.target[k] = float(target_[k]);
    c.eye[k] = float(target_[k] + distance_ * dir);
    c.up[k] = float(up_[k]);
  }
  return c;
}

}  // namespace limn::view
