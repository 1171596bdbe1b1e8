// What per-vertex formats (PLY, glTF) need of a mesh whose UVs and normals have indices of their
// own: one vertex per distinct (vertex, uv, normal) corner combination. Internal to io.
#pragma once

#include <cstdint>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

// The mesh with a vertex per distinct (vertex, uv index, normal index) of its corners, numbered
// in corner order; positions and colours copied from the vertex, UVs and normals per vertex
// (uv_indices = normal_indices = face_vertices when present). `source` (optional) receives
// each new vertex's original vertex. Linear in corners (a short list of variants per vertex).
Mesh split_at_seams(const Mesh& m, std::vector<uint32_t>* source = nullptr);

}  // namespace limn
