// limn simplify: a polygon or triangle mesh from a VSA partition (Jin, Wu, Liu sec. 3.4).
//
// Anchors are the vertices where three or more cluster-boundary edges meet (two clusters on a
// mesh boundary make three: two boundary edges and the edge between the clusters), plus vertices
// where several fans of faces meet. Chains of cluster-boundary edges join anchors; a chain AB
// keeps its vertex P farthest from segment AB while d(P, AB)/|AB| exceeds the split threshold,
// recursively. Each cluster's boundary loops, through the kept vertices, make its polygon; the
// polygon is triangulated by a minimum-area dynamic programme. A cluster with holes is first cut
// into simple polygons by pairs of bridge edges.
//
// Validity is enforced, not hoped for: loops without anchors keep at least three vertices; two
// chains that would become the same edge are split further; a diagonal or triangle that already
// exists elsewhere is vetoed; a cluster the programme cannot triangulate is fanned from one of its
// interior vertices, and as a last resort split in two and the meshing redone. Output vertices
// are input vertices, so the output lies within the input's bounding box.
#pragma once

#include <cstdint>
#include <vector>

#include "limn/simplify/partition.hpp"

namespace limn {

struct MeshingOptions {
  /// Chains are split at their farthest vertex P while d(P, AB)/|AB| exceeds this.
  double split_threshold = 0.5;
  /// One polygon per cluster (a cluster with holes: one per piece its bridges cut it into;
  /// a polygon with a repeated vertex or no area comes out as triangles); false: triangles.
  bool polygons = false;
};

struct MeshingStats {
  size_t anchors = 0;         ///< vertices where chains meet (including forced ones)
  size_t forced_anchors = 0;  ///< anchors added on loops that had none
  size_t chains = 0;
  size_t kept_vertices = 0;   ///< output vertices
  size_t forced_splits = 0;   ///< chain splits beyond the threshold, for validity
  size_t bridges = 0;         ///< edges cutting a cluster with holes into simple polygons
  size_t polygons = 0;        ///< polygons written as one face (polygon output)
  size_t triangulated = 0;    ///< polygons written as triangles by the dynamic programme
  size_t fans = 0;            ///< clusters fanned from an interior vertex instead
  size_t cluster_splits = 0;  ///< clusters split because nothing else gave a valid mesh
};

struct SimplifiedMesh {
  Mesh mesh;                            ///< the output (positions are input positions)
  std::vector<uint32_t> face_cluster;   ///< per output face: its cluster
  std::vector<uint32_t> vertex_source;  ///< per output vertex: the input vertex it copies
  MeshingStats stats;
};

/// Meshes a complete partition (every face assigned, clusters edge-connected). May split
/// clusters of `p` when a cluster cannot be meshed otherwise (counted in stats). Throws
/// std::runtime_error if no valid mesh results after repeated splits. Time O(corners) for the
/// chains plus O(n^3) per cluster polygon of n vertices.
SimplifiedMesh polygonize(const VsaSurface& s, Partition& p, const MeshingOptions& options = {});

}  // namespace limn
