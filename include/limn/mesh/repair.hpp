// limn mesh repair: a polygon soup (a scan, an STL, an exported mesh) made into a mesh that
// subdivision, simplification and painting accept, with every change counted.
//
// Welds near vertices, drops degenerate and duplicate faces, orients each connected piece
// consistently (closed pieces outward), cuts non-manifold and unorientable edges and splits
// non-manifold vertices, then drops unreferenced vertices. Every output vertex is an input
// vertex (copies where a vertex was split), so positions are never moved or invented.
#pragma once

#include <cstddef>

#include "limn/mesh/mesh.hpp"

namespace limn {

struct RepairOptions {
  /// Vertices within this fraction of the bounding-box diagonal (of the referenced vertices) of
  /// each other are welded, transitively, into the lowest-numbered one (weld_map_within). 0
  /// welds only bit-equal positions. Range [0, 0.1].
  double weld_tolerance = 1e-6;
};

/// What repair_mesh changed, as counts.
struct RepairReport {
  size_t welded_vertices = 0;        ///< vertices merged into another vertex
  size_t degenerate_faces = 0;       ///< faces dropped: < 3 distinct vertices after welding, or
                                     ///< area <= 1e-12 x diagonal^2
  size_t split_faces = 0;            ///< faces that passed a vertex twice, split into loops
  size_t duplicate_faces = 0;        ///< faces over the vertex set of an earlier face, dropped
  size_t flipped_faces = 0;          ///< faces reversed to agree with their piece
  size_t non_manifold_edges = 0;     ///< edges of 3+ faces, cut apart
  size_t unorientable_edges = 0;     ///< edges cut where the faces could not agree (Moebius)
  size_t split_vertices = 0;         ///< vertex copies added where faces met only at a vertex
  size_t unreferenced_vertices = 0;  ///< vertices no remaining face uses, dropped
  size_t components = 0;             ///< edge-connected pieces of the result
  size_t closed_components = 0;      ///< of which closed (no boundary edge): oriented outward
  /// True when the result differs from the input in anything but vertex and face order.
  bool changed() const {
    return welded_vertices + degenerate_faces + split_faces + duplicate_faces + flipped_faces +
               non_manifold_edges + unorientable_edges + split_vertices + unreferenced_vertices >
           0;
  }
};

/// Repairs `soup`: the result passes validate(), has no edge of more than two faces, no vertex
/// whose faces form more than one fan, no two faces disagreeing on an edge's direction, no
/// duplicate or degenerate face and no unreferenced vertex. Faces keep their input order (a face
/// split into loops gives them in place), vertices theirs (copies follow their original). UVs and
/// normals follow their corners, colours their vertices, holes their faces; creases follow their
/// edges onto every copy, corner tags onto every copy of the vertex. A closed piece is turned
/// outward (positive signed volume; pieces nested inside others are not told apart); an open piece
/// keeps the orientation most of its faces had. The result has no faces when every face was
/// degenerate. Throws InputError when `soup` fails validate_soup or the tolerance is out of range.
/// O(corners log corners) time, ~60 bytes per corner.
Mesh repair_mesh(const Mesh& soup, const RepairOptions& options = {},
                 RepairReport* report = nullptr);

}  // namespace limn
