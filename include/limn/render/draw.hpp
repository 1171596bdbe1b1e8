// limn render: drawing limn's surfaces with OpenGL 4.5 (a current context is needed).
//
// PatchDrawer draws a patch table's limit surface on the GPU with tessellation shaders: regular
// B-spline patches (boundary rows folded, single creases exact) and Gregory end caps, evaluated
// as limn's CPU evaluator does. Tessellation rates are powers of two per patch edge, taken from
// the cage edge or cage face the edge lies on and the patch's level, so two patches sharing an
// edge always agree, and a patch edge bordering finer patches (its transition bit) takes exactly
// the sum of their rates: no cracks. A cage line bordering only faces wholly out of view gets one
// segment (the faces' patches are off screen), so close-ups of large cages tessellate only what
// is seen. Per-patch data reaches the shaders through the vertex index
// (never gl_PrimitiveID, which llvmpipe restarts every 1024 patch vertices).
// MeshDrawer draws polygon meshes (fan-triangulated) with normals, vertex or face colours.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/render/texture.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn {

struct DrawOptions {
  float color[3] = {0.78f, 0.78f, 0.80f};  ///< base colour (RGB 0-1) without other colouring
  bool outline = false;                    ///< patch outlines (patches) or polygon edges (meshes)
  bool depth_colors = false;  ///< patches: colour by refinement level (subdiv's depth ramp)
  /// Patches: about one tessellation segment per this many pixels of projected cage edge (rates
  /// are powers of two, 1-32 per patch edge). Ignored when `factor` > 0.
  float pixels_per_segment = 8.0f;
  int factor = 0;  ///< patches: this many segments per patch edge (1-32); 0: screen-space rates
  /// Colour from an octree texture (limn paint) looked up at each fragment's position and
  /// normal, over the base or depth colour; null: none.
  const GpuOctreeTexture* texture = nullptr;
  bool texture_nearest = false;  ///< nearest texel, not filtered (trilinear + mip by footprint)
  /// A painted material's RMH texture (limn/paint/material.hpp; null: none): roughness and
  /// metallic shaded physically (GGX), height as a bump of `height_scale` model units per unit.
  /// Looked up filtered at each fragment, as the base colour.
  const GpuOctreeTexture* material = nullptr;
  float height_scale = 0.0f;
  /// A checker of this many squares per UV unit, tinted by (u, v) so flips and seams show; 0:
  /// off. Meshes with UVs, and patch tables of cages with linear UVs (FVarInterpolation::all);
  /// without UVs the colour stays.
  float uv_checker = 0.0f;
};

/// What a draw did. GPU time is measured with a timer query (0 when the driver has none).
struct DrawStats {
  size_t patches = 0;      ///< patches (or polygons) drawn
  uint64_t triangles = 0;  ///< triangles rasterised (a primitives query)
  double gpu_ms = 0, cpu_ms = 0;
};

class PatchDrawer {
 public:
  /// Uploads the patches of `table` built from `cage` (a selection too), with `points` (the
  /// table's points, or its hierarchy's for a selection: 3 floats each). Throws InputError when
  /// the points are too few for the table's indices. O(patches + cage edges).
  PatchDrawer(const Mesh& cage, const PatchTable& table, std::span<const float> points);
  ~PatchDrawer();
  PatchDrawer(const PatchDrawer&) = delete;
  PatchDrawer& operator=(const PatchDrawer&) = delete;

  /// Replaces the points (an animated cage: the same table, new positions). O(points).
  void set_points(std::span<const float> points);
  /// Replaces the patches with another table of the same cage reading the same points (a new
  /// selection from the hierarchy after a view change): only the patch arrays are uploaded; the
  /// points, the compiled shaders and the cage's edges stay. Throws InputError when the table is
  /// another cage's or reads past the points. O(patches).
  void set_patches(const PatchTable& table);
  /// Draws into the bound framebuffer (RenderTarget::begin) seen by `camera`. Only the cage's
  /// per-edge screen rates are computed and uploaded per draw (O(cage edges)).
  DrawStats draw(const Camera& camera, const DrawOptions& options);

  /// The points the GPU tessellates, captured with transform feedback instead of drawn: for
  /// each, the patch (regular first, then end caps, as PatchCoord::patch), its patch-local
  /// (s, t) and the position the shaders computed. What tests hold to limn's CPU evaluator.
  struct Capture {
    std::vector<PatchCoord> coords;
    std::vector<float> positions;  ///< 3 per coordinate
  };
  Capture capture(const Camera& camera, const DrawOptions& options);

 private:
  void upload_patches(const PatchTable& table);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class MeshDrawer {
 public:
  /// Uploads `mesh` (any polygons, concave ones too: ear-clipped in their plane; its normals when
  /// it has them, else per-vertex area-weighted ones, or each face's own with `flat`; its vertex
  /// colours when it has them). `face_colors`: RGB per face, overriding. O(corners^2) worst case
  /// per polygon, O(corners) for convex ones.
  explicit MeshDrawer(const Mesh& mesh, std::span<const float> face_colors = {}, bool flat = false);
  ~MeshDrawer();
  MeshDrawer(const MeshDrawer&) = delete;
  MeshDrawer& operator=(const MeshDrawer&) = delete;
  DrawStats draw(const Camera& camera, const DrawOptions& options);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace limn
