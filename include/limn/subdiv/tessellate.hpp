// limn subdiv: watertight tessellation of a patch table into a triangle mesh.
//
// Each patch is cut into factor x factor cells at its own size, so deeper patches give more
// triangles, or each patch edge gets its own rate from its length on screen. Where patches of
// different sizes meet, every patch edge takes the union of the samples that all patches on the
// same line put there (inside a ptex face, and across cage edges and the spokes of non-quad faces),
// and each such sample is one shared vertex, keyed by where it lies on the cage, so the mesh has no
// cracks and no T-junctions by construction; each shared vertex is evaluated once.
#pragma once

#include <span>

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn {

struct TessellateOptions {
  int factor = 4;  ///< segments per patch edge (1-64), unless `camera` is set
  /// Screen-space rates: each patch edge gets about one segment per `pixels_per_segment` of its
  /// projected length (a power of two, 1-64; 64 for edges behind the eye).
  const Camera* camera = nullptr;
  float pixels_per_segment = 8.0f;
  bool normals = true;        ///< store limit normals (from the patch derivatives)
  bool depth_colors = false;  ///< colour each vertex by the refinement level of its patch
};

/// Tessellates `table` (built from `cage`) with `points` = table.points(cage positions). The
/// result has positions (and normals / colours when asked), triangles in counter-clockwise
/// order for counter-clockwise cage faces, and no faces over holes. O(patches * factor^2)
/// plus a hash lookup per patch-edge sample. Throws InputError for a factor out of range or a
/// cage too large to key (2^28 vertices).
Mesh tessellate_patches(const Mesh& cage, const PatchTable& table, std::span<const float> points,
                        const TessellateOptions& options);

/// RGB (0-1) of a refinement level in the depth-colour ramp (blue = shallow, red = deep).
void depth_color(int level, float rgb[3]);

}  // namespace limn
