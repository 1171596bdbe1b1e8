// limn mesh welding: merging vertices that sit at exactly the same position.
//
// Formats that store attributes per vertex (glTF, STL's triangle soup) split one surface point
// into several vertices wherever a UV, a normal or simply the next triangle differs. Welding
// restores the connected cage: equal positions become one vertex, while UVs and normals keep
// their own index spaces (one index per corner), as the Mesh layout allows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

/// Groups the points of `xyz` (3 floats each) whose coordinates are bit-equal, -0.0 counting as
/// 0.0. Returns one group index per point; groups are numbered 0, 1, ... in order of their first
/// point. `groups`, when given, receives the number of groups. Precondition: fewer than 2^32
/// points. O(points) expected time, ~12 bytes of scratch per point.
std::vector<uint32_t> weld_map(std::span<const float> xyz, uint32_t* groups = nullptr);

/// Groups the points of `xyz` that lie within `tolerance` (model units, Euclidean) of another
/// point of the group, transitively: two points 0.6 x tolerance apart and a third 0.6 x
/// tolerance beyond the second form one group. Groups are numbered in order of their first
/// point, as weld_map's; tolerance <= 0, or below 1e-15 x the points' extent, is weld_map.
/// Precondition: finite coordinates, fewer than
/// 2^32 points. O(points) expected for surfaces sampled coarser than the tolerance; ~40 bytes of
/// scratch per distinct point.
std::vector<uint32_t> weld_map_within(std::span<const float> xyz, double tolerance,
                                      uint32_t* groups = nullptr);

/// Merges vertices with bit-equal positions (as weld_map) into one vertex each, numbered in order
/// of their first original vertex, which also gives the merged vertex its position and colour.
/// UVs and normals become per-corner indices into tables of their distinct (bit-equal) values in
/// order of first use. Faces that repeat a vertex after the merge are dropped (their count goes
/// to `dropped_faces` when given); hole tags follow their faces, creases whose two ends merge are
/// dropped. Unreferenced vertices are merged too and kept. Precondition: validate(mesh) passes;
/// the result passes it as well. O(V + corners) expected.
Mesh weld_vertices(const Mesh& mesh, size_t* dropped_faces = nullptr);

}  // namespace limn
