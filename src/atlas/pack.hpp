// Packing charts into square tiles by their rasterised outlines. Internal header of the atlas
// layer.
//
// Each chart is rasterised conservatively (every texel its triangles touch) at the texel density,
// grown by the padding, and kept as runs of texels per row. Charts go largest first, each at the
// lowest row (then leftmost column) and quarter turn where its runs meet no taken texel, so small
// charts settle into the hollows the large ones leave. A free-run count per texel lets the search
// jump past every start a taken texel rules out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "atlas/chart.hpp"

namespace limn::atlas {

/// A chart's UVs turned to their smallest bounding rectangle, at the origin, wider than tall (in
/// model units; see orient_chart).
struct ChartExtent {
  double width = 0, height = 0;
};

/// Turns the chart's UVs so their bounding rectangle is the smallest over the directions of their
/// convex hull's edges, wider than tall, with its lower-left corner at the origin. O(V log V).
ChartExtent orient_chart(Chart& chart);

struct Placement {
  uint32_t tile = 0;
  int turns = 0;     ///< quarter turns counter-clockwise, 0-3
  int x = 0, y = 0;  ///< the chart's padded box's lower-left texel in its tile
};

struct PackOptions {
  int size = 1024;
  int tiles = 1;
  int padding = 2;
  double texels_per_unit = 0;  ///< 0: the largest that fits
};

struct Packing {
  bool fits = false;
  double texels_per_unit = 0;
  size_t tiles = 0;    ///< tiles used
  size_t covered = 0;  ///< texels the charts touch (before padding)
  std::vector<Placement> placements;
};

/// Packs the oriented charts. With texels_per_unit 0, searches for the largest density that fits
/// (about 12 packings). O(packings * (texels + charts * size * chart width)).
Packing pack_charts(const std::vector<Chart>& charts, const std::vector<ChartExtent>& extents,
                    const PackOptions& options);

/// The tile texel coordinates (v up) of UV point (u, v) of a chart placed by `p`.
inline void placed_texel(double u, double v, const ChartExtent& e, const Placement& p,
                         double texels_per_unit, int padding, double out[2]) {
  const double a[4] = {u, e.height - v, e.width - u, v};
  const double b[4] = {v, u, e.height - v, e.width - u};
  out[0] = p.x + padding + a[p.turns] * texels_per_unit;
  out[1] = p.y + padding + b[p.turns] * texels_per_unit;
}

}  // namespace limn::atlas
