// limn procedural shapes: deterministic cages for the demo, tests and benchmarks, so nothing
// depends on files outside the repository.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

/// Unit cube centred at the origin: 8 vertices, 6 quads, outward orientation.
Mesh make_cube();

/// Quad torus (major radius 1, minor radius 0.4) on a `major` x `minor` grid, with one
/// extraordinary vertex per entry of `valences` (each 3..12). Each is made by replacing a
/// rectangular block of quads with a fan of n quads around a new centre vertex; the valence-3
/// vertices that keep the Euler characteristic at 0 appear on the block's rim.
/// Throws std::invalid_argument when the grid is too small to place them apart. O(major*minor).
Mesh make_torus(int major, int minor, std::span<const int> valences);

/// A smooth-shading test cage: an open box (3x3 quads per side, no lid) with infinitely sharp
/// creases on the bottom rim, semi-sharp creases (sharpness 2.5) up two vertical edges, tagged
/// corners, a hole face, and the open top as a boundary loop.
Mesh make_crease_cage();

/// Terrain-like height field: `n` x `n` quads (open boundary) with extraordinary vertices of
/// valence 3, 5, 6 scattered roughly every `spacing` cells, deterministic from `seed`.
/// n = 895 gives ~801k quads, the size of the seed paper's terrain scene.
Mesh make_terrain(int n, uint64_t seed, int spacing = 24);

/// Closed torus-like cage of `major` x `minor` quads with dense extraordinary vertices (about one
/// vertex in ten), deterministic from `seed`. 1600 x 500 gives ~800k quads.
Mesh make_dense_torus(int major, int minor, uint64_t seed);

/// Names accepted by make_shape: cube, torus, cage, terrain, torus-dense (+ "-small" variants of
/// the big two, a few thousand quads, for fast tests).
std::vector<std::string> shape_names();

/// Builds a named shape with its default parameters. Throws InputError for an unknown name.
Mesh make_shape(std::string_view name, uint64_t seed = 1);

}  // namespace limn
