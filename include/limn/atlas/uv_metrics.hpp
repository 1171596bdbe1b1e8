// limn atlas: what a UV layout is worth, measured on the mesh alone (any mesh with UVs, from limn
// or from another tool), so it can check an atlas independently of the code that made it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

struct UvMetrics {
  size_t triangles = 0;  ///< fan triangles of the faces with a surface area
  /// Triangles whose UV image is mirrored or has no area, while their surface triangle has one.
  size_t flipped = 0;
  size_t straddling = 0;  ///< triangles whose UVs reach into more than one unit tile
  size_t tiles = 0;       ///< unit UV tiles (UDIM) that hold triangles
  /// Texel centres inside two or more triangles (rasterised at `size` texels per tile side; a
  /// centre on a shared edge counts for one side only): overlapping charts or folds.
  size_t overlapping_texels = 0;
  size_t covered_texels = 0;  ///< texel centres inside a triangle
  double coverage = 0;        ///< covered_texels over the texels of the tiles that hold triangles
  /// Sander et al. 2001: RMS and largest singular value of the map from texture to surface,
  /// area-weighted over the surface, times sqrt(texture area / surface area); 1 is isometric.
  double stretch_l2 = 0, stretch_linf = 0;
};

/// Measures the mesh's UVs (uvs/uv_indices; faces fanned from their first corner) at `size`
/// texels per tile side. Throws InputError when the mesh has no UVs or size is outside 1-16384.
/// O(corners + texels covered).
UvMetrics measure_uvs(const Mesh& mesh, int size);

/// A picture of UDIM tile `tile`'s layout, size x size RGBA8 (rows top to bottom, v up): each
/// face filled in a colour of its chart (face_chart, one per face; empty: one colour), white
/// elsewhere. For reports. O(size^2 + texels covered).
std::vector<uint8_t> uv_layout_image(const Mesh& mesh, std::span<const uint32_t> face_chart,
                                     int size, int tile = 0);

}  // namespace limn
