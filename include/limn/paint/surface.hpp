// limn paint: the surface being painted (triangles, face normals and an Embree 3 BVH for ray casts,
// closest points and box queries) and the camera for screen-space painting.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

/// A pinhole camera (the subdiv layer's conventions): pixel x to the right, y down, pixel centres
/// at +0.5, vertical field of view in degrees.
struct PaintCamera {
  float eye[3] = {0, 0, 5}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  float fovy_deg = 45.0f;
  int width = 1280, height = 720;

  /// The ray through pixel (px, py): unit direction. False when the camera is degenerate
  /// (eye == target, up parallel to the view, fovy outside (0, 180), empty image). O(1).
  bool ray(double px, double py, float dir[3]) const;
  /// Projects p to pixel coordinates; false when p is at or behind the eye. O(1).
  bool project(const float p[3], double& px, double& py) const;
  /// World size of one pixel at p's depth (model units). O(1).
  double world_per_pixel(const float p[3]) const;
  /// Camera validity (see `ray`). O(1).
  bool valid() const;
};

/// A ray or closest-point hit.
struct SurfaceHit {
  float p[3] = {0, 0, 0};  ///< the point on the surface
  float n[3] = {0, 0, 0};  ///< unit face normal (the mesh's orientation)
  uint32_t triangle = 0;   ///< triangle index (faces fanned in order)
  float distance = 0;      ///< ray parameter or distance to the query point
};

/// Triangles (each face fanned from its first corner), unit face normals and an Embree BVH.
/// Read-only after construction (but for what the paint layer derives once, under a lock); the
/// queries are thread-safe.
class PaintSurface {
 public:
  /// Builds the BVH. Throws InputError when the mesh has no faces. O(T log T).
  explicit PaintSurface(const Mesh& mesh);
  ~PaintSurface();
  PaintSurface(const PaintSurface&) = delete;
  PaintSurface& operator=(const PaintSurface&) = delete;

  size_t triangle_count() const { return normals_.size() / 3; }
  /// Corner k (0-2) of triangle t. O(1).
  const float* corner(uint32_t t, int k) const { return &corners_[9 * size_t(t) + 3 * size_t(k)]; }
  /// Unit normal of triangle t, (0,0,0) for a degenerate one. O(1).
  const float* normal(uint32_t t) const { return &normals_[3 * size_t(t)]; }
  /// Whether triangle t is degenerate (no normal): the paint layer skips it everywhere. O(1).
  bool degenerate(uint32_t t) const {
    const float* n = normal(t);
    return n[0] == 0 && n[1] == 0 && n[2] == 0;
  }
  /// Face of the mesh that triangle t comes from. O(1).
  uint32_t face(uint32_t t) const { return faces_[t]; }
  /// octree::tag_for_normal of triangle t's normal, tabulated. O(1).
  int tag(uint32_t t) const { return tags_[t]; }
  /// octree::side_for_normal(cell_tag, normal(t)), tabulated (cell_tag in 0..kTagCount). O(1).
  int side(int cell_tag, uint32_t t) const { return back_[t] >> cell_tag & 1; }
  /// The mesh's bounding box.
  const Box& bounds() const { return bounds_; }

  /// The nearest surface point to p no farther than max_dist. O(log T) expected.
  bool closest_point(const float p[3], float max_dist, SurfaceHit& hit) const;
  /// The first hit along org + t dir, t in [tnear, tfar]. O(log T) expected.
  bool intersect(const float org[3], const float dir[3], float tnear, float tfar,
                 SurfaceHit& hit) const;
  /// True when the segment org + t dir, t in [tnear, tfar], meets the surface.
  bool occluded(const float org[3], const float dir[3], float tnear, float tfar) const;
  /// `occluded` for `count` segments at once, traced in packets (coherent rays, such as one
  /// dab's, share the walk down the BVH): org and dir hold 3 floats per ray; occluded[i] is set
  /// to 1 or 0.
  void occluded_many(size_t count, const float* org, const float* dir, const float* tnear,
                     const float* tfar, uint8_t* occluded) const;
  /// Appends the non-degenerate triangles whose bounds may meet the ball (c, r), sorted by index
  /// (a superset; callers filter exactly). O(log T + answer).
  void triangles_near(const float c[3], float r, std::vector<uint32_t>& out) const;
  /// Appends the non-degenerate triangles meeting the axis-aligned box of centre c and half
  /// size h grown by `slack`, sorted by index: exactly those of triangles_near(c, (h + slack)
  /// sqrt 3) that the paint layer's box test (separating axes, touching counts) keeps, decided
  /// as the BVH reports them instead of gathered first. O(log T + answer).
  void triangles_in_box(const float c[3], float h, float slack, std::vector<uint32_t>& out) const;
  /// Appends the triangles triangles_in_box(c, h, slack) tests, untested: a superset of its
  /// answer, in the BVH's order, a triangle possibly twice. O(log T + answer).
  void box_candidates(const float c[3], float h, float slack, std::vector<uint32_t>& out) const;

  /// The surface's Embree scene and what the paint layer keeps with it (internal:
  /// src/paint/surface_impl.hpp).
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::vector<float> corners_, normals_;
  std::vector<uint32_t> faces_;
  std::vector<uint8_t> tags_;   // per triangle: its normal's tag
  std::vector<uint16_t> back_;  // per triangle: bit k set when its normal is on side 1 of tag k
  Box bounds_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace limn
