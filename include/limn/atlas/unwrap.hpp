// limn atlas: an automatic UV atlas for any manifold mesh.
//
// Charts come from variational shape approximation split top-down: a chart is kept when it is a
// topological disk whose conformal map (LSCM, Levy et al. 2002) has no flipped triangle, a simple
// boundary, a Sander L2 stretch at most `max_stretch` and a compact shape (over half of its
// convex hull); otherwise VSA cuts it in two along its sharpest feature and both halves are tried
// again. Then chart borders are smoothed and neighbours merged while the merged chart still
// passes. Charts are scaled to their surface area, turned to their smallest bounding rectangle
// and packed by their rasterised outlines (with a gutter) into one atlas or into UDIM tiles.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

struct UnwrapOptions {
  /// Largest Sander L2 stretch a chart may keep (1 = isometric up to scale); charts above it are
  /// cut. Lower gives less distortion and more charts.
  double max_stretch = 1.003;
  /// Side of the square atlas or of each UDIM tile, in texels.
  int size = 1024;
  /// Texels per model unit; 0 = the largest density whose charts fit in `tiles` tiles of `size`.
  double texels_per_unit = 0;
  /// Most tiles to use: 1 gives one atlas in [0,1]^2; more gives UDIM tiles (u tile = tile % 10,
  /// v tile = tile / 10; tile 1001 + index).
  int tiles = 1;
  /// Free texels kept around every chart, so bilinear filtering and a few mip levels of a baked
  /// texture never read a neighbouring chart.
  int padding = 2;
};

struct UnwrapStats {
  size_t charts = 0;
  size_t splits = 0;           ///< charts cut in two on the way
  size_t tiles = 0;            ///< tiles used (1 for a single atlas)
  int size = 0;                ///< texels per tile side
  double texels_per_unit = 0;  ///< the density used
  /// Texels the charts and their padding take over all texels of the tiles used: how well the
  /// packing fills them, as xatlas computes its utilisation (set texels of its padded chart
  /// images over the atlas).
  double utilization = 0;
  /// Texels any chart's triangles touch (no padding) over all texels of the tiles used.
  double coverage = 0;
  double stretch_l2 = 0;    ///< Sander's L2 over the mesh (1 is optimal)
  double stretch_linf = 0;  ///< Sander's Linf (largest singular value, normalised)
  double chart_ms = 0, pack_ms = 0;
};

/// A mesh with UVs (OpenGL convention, v up) and the chart of each face.
struct UnwrapResult {
  Mesh mesh;                         ///< the input with its uvs and uv_indices replaced
  std::vector<uint32_t> face_chart;  ///< per face
  std::vector<uint32_t> chart_tile;  ///< per chart: tile index (UDIM 1001 + index)
  UnwrapStats stats;
};

/// Unwraps `mesh` (any polygons; fans are used for the maps). Throws InputError naming `name`
/// when the mesh is non-manifold, inconsistently oriented or empty (see prepare_surface), when an
/// option is out of range, or when the charts cannot fit in `tiles` tiles at `texels_per_unit`.
/// Parallel over charts. About O(F log F) for charts, plus O(tiles * size^2) for packing.
UnwrapResult unwrap_mesh(const Mesh& mesh, const UnwrapOptions& options = {},
                         std::string_view name = "mesh");

}  // namespace limn
