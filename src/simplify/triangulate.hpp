// limn simplify: minimum-weight triangulation of a closed, possibly non-planar polygon.
//
// The classic dynamic programme over sub-polygons (Klincsek 1980; Barequet and Sharir 1995;
// Liepa 2003 for hole filling): W(i, j) = min over i < k < j of W(i, k) + W(k, j) + w(i, k, j).
// Every result is combinatorially a triangulated disk whose triangles follow the polygon's
// orientation, so callers get validity from their vetoes (diagonals that must not be used,
// triangles that must not appear) rather than from geometry.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

namespace limn {

/// Whether the diagonal between polygon positions i < j may be used.
using DiagonalOk = std::function<bool(uint32_t i, uint32_t j)>;
/// Weight of triangle (i, j, k), i < j < k; +infinity vetoes it.
using TriangleWeight = std::function<double(uint32_t i, uint32_t j, uint32_t k)>;

/// Triangulates the polygon 0..n-1 (n >= 3). Appends triangles as position triples (i, j, k),
/// i < j < k, to `out` and returns true; returns false (out unchanged) when every triangulation
/// uses a vetoed diagonal or triangle. Time O(n^3), memory O(n^2) for n <= 192; larger polygons
/// are first cut by a short allowed diagonal between nearly opposite positions.
bool triangulate_polygon(uint32_t n, const DiagonalOk& ok, const TriangleWeight& weight,
                         std::vector<uint32_t>& out);

}  // namespace limn
