// limn mesh adjacency: a compact corner (half-edge) table built on demand from a Mesh.
//
// Corner c of face f is the half-edge from face_vertices[c] to the next vertex of f. Every corner
// gets an undirected edge id and its opposite corner, so walking faces around a vertex or across
// an edge is O(1) per step, and non-manifold configurations are represented, not rejected.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

inline constexpr uint32_t kNone = 0xFFFFFFFFu;         ///< no opposite corner: boundary edge.
inline constexpr uint32_t kNonManifold = 0xFFFFFFFEu;  ///< edge shared by more than two faces.

struct Topology {
  std::vector<uint32_t> corner_face;     ///< face of each corner.
  std::vector<uint32_t> corner_next;     ///< next corner in the same face (cyclic).
  std::vector<uint32_t> corner_prev;     ///< previous corner in the same face (cyclic).
  std::vector<uint32_t> corner_edge;     ///< undirected edge id of each corner's half-edge.
  std::vector<uint32_t> corner_twin;     ///< opposite corner, kNone (boundary) or kNonManifold.
  std::vector<uint32_t> edge_vertices;   ///< 2 per edge, smaller vertex first.
  std::vector<uint32_t> edge_faces;      ///< number of faces on each edge (1 boundary, 2 interior).
  std::vector<uint32_t> vertex_offsets;  ///< CSR: corners starting at vertex v are
  std::vector<uint32_t> vertex_corners;  ///<   vertex_corners[vertex_offsets[v] .. v+1).

  size_t edge_count() const { return edge_faces.size(); }
  /// Number of faces around vertex v. O(1).
  uint32_t vertex_face_count(uint32_t v) const { return vertex_offsets[v + 1] - vertex_offsets[v]; }
};

/// Builds the corner table. Precondition: validate(mesh) passes. Time O(corners + sum of squared
/// valences), memory ~36 bytes per corner. Multi-threaded with TBB for large meshes.
Topology build_topology(const Mesh& mesh);

/// The same from raw CSR faces over `vertex_count` vertices (for callers without positions,
/// such as refinement levels). Same preconditions and cost.
Topology build_topology(size_t vertex_count, std::span<const uint32_t> face_offsets,
                        std::span<const uint32_t> face_vertices);

/// Everything `limn info` reports about a mesh's structure.
struct MeshStats {
  size_t vertices = 0, referenced_vertices = 0, unreferenced_vertices = 0;
  size_t faces = 0, corners = 0, edges = 0;
  std::vector<std::pair<uint32_t, size_t>> faces_by_arity;  ///< (arity, count), ascending.
  size_t boundary_edges = 0, boundary_loops = 0, components = 0;
  long long euler_characteristic = 0;  ///< V - E + F over referenced vertices.
  long long genus = -1;  ///< total genus of the closed-up surface; -1 when non-manifold.
  size_t non_manifold_edges = 0, non_manifold_vertices = 0;
  size_t inconsistent_edges = 0;  ///< manifold edges whose two faces disagree on orientation.
  size_t degenerate_faces = 0;    ///< faces of (numerically) zero area.
  size_t extraordinary_vertices = 0;
  std::vector<std::pair<uint32_t, size_t>> valence_histogram;  ///< (edges at vertex, count).
  size_t crease_edges = 0, corner_vertices = 0, hole_faces = 0;
  size_t infinitely_sharp_creases = 0;
  Box bbox;
  double surface_area = 0;
  bool has_normals = false, has_uvs = false, has_colors = false;
  size_t uv_values = 0;      ///< distinct UV entries (the file's `vt`)
  size_t uv_seam_edges = 0;  ///< manifold edges whose two faces disagree on a UV index at an end
};

/// Structural analysis in O(corners + V) after build_topology. A vertex is extraordinary for
/// Catmull-Clark when it is interior with valence != 4, or on the boundary with a face count
/// other than 1 (corner) or 2 (regular boundary). Zero-area means area <= 1e-12 * bbox diag^2.
MeshStats analyze(const Mesh& mesh, const Topology& topo);

}  // namespace limn
