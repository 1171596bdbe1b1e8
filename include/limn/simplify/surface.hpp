// limn simplify: a mesh prepared for variational shape approximation (VSA).
//
// VSA partitions faces into edge-connected clusters and scores a cluster by its area S and its
// area-weighted normal sum N (Cohen-Steiner, Alliez, Desbrun 2004, L2,1 metric). Both come from
// one double-precision vector area per face, computed once here next to the corner table that
// gives face adjacency across edges.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/mesh/topology.hpp"

namespace limn {

struct VsaSurface {
  const Mesh* mesh = nullptr;  ///< the input; must outlive the surface
  Topology topo;
  std::vector<double> area;  ///< per face, squared model units (0 for a degenerate face)
  std::vector<double> vec;   ///< 3 per face: area times unit normal (Newell vector area)
  double total_area = 0;
  Box bbox;
  size_t components = 0;  ///< edge-connected components of faces
  /// Per vertex: 0 unused, 1 interior (one closed fan of faces), 2 on the mesh boundary (one open
  /// fan), 3 non-manifold (several fans meet there).
  std::vector<uint8_t> vertex_kind;

  size_t face_count() const { return area.size(); }
  /// The face across the edge of corner c, or kNone on a mesh boundary. O(1).
  uint32_t across(uint32_t c) const {
    const uint32_t t = topo.corner_twin[c];
    return t == kNone ? kNone : topo.corner_face[t];
  }
  /// The next outgoing corner around the vertex of outgoing corner c (counter-clockwise for
  /// counter-clockwise faces), or kNone at a mesh boundary. O(1).
  uint32_t rotate(uint32_t c) const { return topo.corner_twin[topo.corner_prev[c]]; }
  /// Unit normal of face f into out (zero for a degenerate face). O(1).
  void normal(uint32_t f, double out[3]) const;
};

/// Builds the corner table and per-face vector areas. Throws InputError naming `name` and the
/// offending element when the mesh has no faces, an edge shared by three or more faces, an edge
/// whose two faces disagree on orientation, or two faces over the same vertices. Zero-area faces
/// and vertices where separate fans meet are accepted. O(corners) plus build_topology.
VsaSurface prepare_surface(const Mesh& mesh, std::string_view name = "mesh");

}  // namespace limn
