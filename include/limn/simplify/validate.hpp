// limn simplify: the validity contract of a simplified mesh, checked from scratch.
//
// The checks use nothing but the output's face lists (sorted edge and face keys), not the corner
// table the simplifier used, so the two can disagree.
#pragma once

#include <string>

#include "limn/mesh/mesh.hpp"

namespace limn {

struct SimplifiedCheck {
  size_t faces = 0, edges = 0, boundary_edges = 0;
  size_t non_manifold_edges = 0;  ///< undirected edges used by three or more faces
  size_t inconsistent_edges = 0;  ///< a directed edge used twice (two faces disagree)
  size_t duplicate_faces = 0;     ///< faces over the same vertex set as an earlier face
  size_t degenerate_faces = 0;    ///< repeated vertex, or area <= 1e-12 x (bbox diagonal)^2
  size_t outside_bbox = 0;        ///< vertices outside the input's bounding box (or not finite)
  size_t unreferenced_vertices = 0;
  std::string first_problem;  ///< one line describing the first problem found, empty when valid
  bool ok() const { return first_problem.empty(); }
};

/// Checks that `out` is an edge-manifold, consistently oriented mesh without duplicate or
/// degenerate faces or unreferenced vertices, all of whose vertices lie in `input_bbox`.
/// O(corners log corners).
SimplifiedCheck validate_simplified(const Mesh& out, const Box& input_bbox);

}  // namespace limn
