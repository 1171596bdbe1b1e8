// limn simplify: discrete Gaussian curvature (Meyer, Desbrun, Schroeder, Barr 2002).
//
// K(v) = (2 pi - sum of the corner angles at v) / A_mixed(v), where A_mixed is the Voronoi area
// of v inside each non-obtuse triangle (1/8 sum |PR|^2 cot Q + |PQ|^2 cot R), and half or a quarter
// of the triangle's area inside obtuse ones (half when the obtuse angle is at v). This is the
// "adaptive seeding" input of Jin, Wu, Liu (sec. 4.1, eq. 11).
#pragma once

#include <span>
#include <vector>

#include "limn/simplify/surface.hpp"

namespace limn {

/// Gaussian curvature per vertex, in 1/length^2. Vertices on the mesh boundary or where several
/// fans meet (no angle defect to speak of), unused vertices and vertices whose faces all have
/// zero area get 0. Polygons are fanned from their first corner; zero-area triangles are skipped.
/// O(corners).
std::vector<double> gaussian_curvature(const VsaSurface& s);

/// Per face: the mean |K| over its vertices (Jin et al.'s kappa_G(T)). O(corners).
std::vector<double> face_abs_curvature(const VsaSurface& s, std::span<const double> vertex_k);

}  // namespace limn
