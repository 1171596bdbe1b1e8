// Builds a cube with the installed library, checks its structure, and measures a distance
// (Embree, opened when first used, through the installed library).
#include <limn/mesh/shapes.hpp>
#include <limn/mesh/topology.hpp>
#include <limn/simplify/distance.hpp>
#include <limn/version.hpp>

#include <cstdio>

int main() {
  const limn::Mesh cube = limn::make_cube();
  const limn::MeshStats s = limn::analyze(cube, limn::build_topology(cube));
  std::printf("limn %s: cube V=%zu E=%zu F=%zu genus=%lld\n", limn::version(), s.vertices, s.edges,
              s.faces, s.genus);
  const limn::SurfaceDistance d = limn::surface_distance(cube, cube, 1000, 1);
  std::printf("distance of the cube to itself: %g\n", d.hausdorff);
  return (s.vertices == 8 && s.edges == 12 && s.faces == 6 && s.genus == 0 && d.hausdorff < 1e-6)
             ? 0
             : 1;
}
