// limn-view: an orbit camera (turntable around a target) producing limn's pinhole Camera.
#pragma once

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/depth.hpp"

namespace limn::view {

class OrbitCamera {
 public:
  /// Frames `mesh` as limn's CLI does (frame_camera): the same first view in both tools.
  void frame(const Mesh& mesh, int width, int height);
  /// Turntable: yaw around the initial up axis, pitch toward it (clamped short of the poles), in
  /// degrees.
  void orbit(double yaw_deg, double pitch_deg);
  /// Moves the target (and eye) by a drag of (dx, dy) pixels, so the point under the cursor at
  /// the target's depth stays under it.
  void pan(double dx_px, double dy_px);
  /// Distance to the target times `factor` (> 0).
  void zoom(double factor);
  /// The image size the camera maps to (the framebuffer's).
  void resize(int width, int height);
  Camera camera() const;
  /// Changes whenever the view does: callers re-select view-dependent data only then.
  unsigned long revision() const { return revision_; }

 private:
  double target_[3] = {0, 0, 0};
  double up_[3] = {0, 1, 0}, base_[3] = {0, 0, 1}, side_[3] = {1, 0, 0};  // orthonormal frame
  double yaw_ = 0, pitch_ = 0, distance_ = 5, min_distance_ = 1e-4;
  float fovy_deg_ = 45;
  int width_ = 1280, height_ = 720;
  unsigned long revision_ = 0;
};

}  // namespace limn::view
