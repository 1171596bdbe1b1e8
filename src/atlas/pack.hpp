// Packing charts into square tiles by their rasterised outlines. Internal header of the atlas
// layer.
//
// Each chart is rasterised conservatively (every texel its triangles touch) at the texel density
// and at several angles, grown by the padding, and kept as runs of texels per row. Charts go
// largest first, each at the angle and lowest row (then leftmost column) where its runs meet no
// taken texel and its top ends lowest, so small charts settle into the hollows the large ones
// leave. A free-run count per texel lets the search
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
  double hull_area = 0;  ///< area of the UVs' convex hull
};

/// Turns the chart's UVs so their bounding rectangle is the smallest over the directions of their
/// convex hull's edges, wider than tall, with its lower-left corner at the origin. O(V log V).
ChartExtent orient_chart(Chart& chart);

/// A chart turned by an angle and moved into the positive quadrant: texel = (c u - s v + ox,
/// s u + c v + oy) times the density, plus the padding and the placement.
struct Pose {
  double c = 1, s = 0, ox = 0, oy = 0;
  double width = 0, height = 0;  ///< the turned chart's extent (model units)
};

/// The chart turned by `turn` / `turns` of a full turn counter-clockwise. O(V).
Pose chart_pose(const Chart& chart, int turn, int turns);

struct Placement {
  uint32_t tile = 0;
  int turn = 0;      ///< of PackOptions::turns, counter-clockwise
  int x = 0, y = 0;  ///< the chart's padded box's lower-left texel in its tile
};

struct PackOptions {
  int size = 1024;
  int tiles = 1;
  int padding = 2;
  double texels_per_unit = 0;  ///< 0: the largest that fits
  int turns = 4;               ///< angles tried per chart (a full turn in equal steps)
};

struct Packing {
  bool fits = false;
  double texels_per_unit = 0;
  size_t tiles = 0;    ///< tiles used
  size_t covered = 0;  ///< texels the charts touch (before padding)
  size_t taken = 0;    ///< texels the charts and their padding take
  std::vector<Placement> placements;
  std::vector<Pose> poses;  ///< per chart: the pose of its placement
};

/// Packs the charts. With texels_per_unit 0, searches for the largest density that fits
/// (about 20 packings, each trying three chart orders at most). O(packings * turns * (texels +
/// charts * rows searched)).
Packing pack_charts(const std::vector<Chart>& charts, const PackOptions& options);

/// The tile texel coordinates (v up) of UV point (u, v) of a chart in pose `q` placed by `p`.
inline void placed_texel(double u, double v, const Pose& q, const Placement& p,
                         double texels_per_unit, int padding, double out[2]) {
  out[0] = p.x + padding + (q.c * u - q.s * v + q.ox) * texels_per_unit;
  out[1] = p.y + padding + (q.s * u + q.c * v + q.oy) * texels_per_unit;
}

}  // namespace limn::atlas
