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

#include "limn/simplify/vsa.hpp"

namespace limn {

/// Meshes a complete partition (every face assigned, clusters edge-connected). May split
/// clusters of `p` when a cluster cannot be meshed otherwise (counted in stats). Throws
/// std::runtime_error if no valid mesh results after repeated splits. Time O(corners) for the
/// chains plus O(n^3) per cluster polygon of n vertices.
SimplifiedMesh polygonize(const VsaSurface& s, Partition& p, const MeshingOptions& options = {});

}  // namespace limn
