// A chart of the atlas: a connected set of faces with its own vertices, and the tests that decide
// whether its map is kept. Internal header of the atlas layer.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "limn/simplify/surface.hpp"

namespace limn::atlas {

struct Chart {
  std::vector<uint32_t> faces;  ///< mesh faces, each once
  /// Per corner of `faces` (face after face, corners in order): its chart vertex. Corners share a
  /// chart vertex when they sit on one mesh vertex and are joined across the chart's inner edges,
  /// so a seam through the chart's own vertex still gives each side its vertex.
  std::vector<uint32_t> corner_vertex;
  std::vector<uint32_t> vertex_source;  ///< per chart vertex: its mesh vertex
  std::vector<uint32_t> triangles;      ///< 3 chart vertices per fan triangle (faces fanned)
  std::vector<uint32_t> boundary;       ///< 2 chart vertices per boundary half-edge
  long euler = 0;                       ///< V - E + F; 1 for a disk
  double area = 0, normal_sum = 0;      ///< sum of face areas, |sum of vector areas|
  std::vector<double> uv;               ///< 2 per chart vertex once mapped
  /// Once kept (mapped, judged and oriented): UV area over the area of the UVs' convex hull, and
  /// the map's Sander stretch (chart_quality).
  double fill = 0, stretch_l2 = 0, stretch_linf = 0;
};

/// Shared scratch arrays for building charts from disjoint face sets on several threads at once:
/// a chart only writes the entries of its own faces and corners.
struct ChartScratch {
  std::vector<uint32_t> face_owner;   ///< per mesh face: the id of the chart being built over it
  std::vector<uint32_t> corner_slot;  ///< per mesh corner: its position in its chart
};

/// Builds the chart over `faces` (connected, each once). `id` must differ from every other chart
/// built with the same scratch. O(corners of the chart).
Chart build_chart(const VsaSurface& s, std::vector<uint32_t> faces, uint32_t id,
                  ChartScratch& scratch);

/// Conformal map of a chart (least-squares conformal map, Levy et al. 2002), scaled so its UV
/// area equals its surface area. Returns false when the system cannot be solved (a chart of
/// degenerate triangles). Sparse Cholesky: about O(V^1.5) for a chart of V vertices.
bool conformal_map(const VsaSurface& s, Chart& chart);

/// The chart projected onto the plane of its summed normal (a fallback for single faces whose
/// map cannot be solved). Scaled like conformal_map.
void planar_map(const VsaSurface& s, Chart& chart);

/// Sander's L2 stretch of the chart's map (area-normalised; 1 is isometric) and the number of
/// triangles flipped or collapsed in UV (among those with a surface area).
struct ChartQuality {
  double stretch_l2 = 0;
  double stretch_linf = 0;
  size_t flipped = 0;
};
ChartQuality chart_quality(const VsaSurface& s, const Chart& chart);

/// True when two boundary edges of the chart's map cross (the map folds over itself although no
/// triangle flips). O(B log B) for B boundary edges in practice (grid buckets).
bool boundary_crosses(const Chart& chart);

/// The edge-connected pieces of faces with equal labels (one per face of `s`), each as face ids,
/// or as names[face] when `names` is given. O(corners).
std::vector<std::vector<uint32_t>> label_pieces(const VsaSurface& s,
                                                std::span<const uint32_t> label,
                                                std::span<const uint32_t> names = {});

/// Cuts a chart's faces in two along its sharpest feature (VSA with two proxies), or in two
/// halves by distance across faces when VSA cannot; returns the edge-connected pieces.
std::vector<std::vector<uint32_t>> split_faces(const VsaSurface& s,
                                               std::span<const uint32_t> faces);

}  // namespace limn::atlas
