// The input's attributes onto a simplified mesh: VSA output vertices are input vertices, so
// what the input stores per vertex or per corner can come along. Internal to the simplify layer.
#pragma once

#include <cstdint>
#include <span>

#include "limn/simplify/vsa.hpp"

namespace limn {

// Per-vertex colours are copied from each output vertex's source. UVs and normals are per
// corner: an output corner takes the value its source vertex has in an input face of the same
// cluster as the output face (the region the face stands for), from the lowest-numbered such
// face when a seam runs through the cluster at that vertex; a vertex no face of the cluster
// touches takes its lowest-numbered face's. So a seam between clusters stays a seam. `labels`:
// the cluster of each input face. O(input corners + output corners).
void carry_attributes(const Mesh& input, std::span<const uint32_t> labels, SimplifiedMesh& out);

}  // namespace limn
