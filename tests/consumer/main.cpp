// Builds a cube with the installed library and checks its structure.
#include <limn/mesh/shapes.hpp>
#include <limn/mesh/topology.hpp>
#include <limn/version.hpp>

#include <cstdio>

int main() {
  const limn::Mesh cube = limn::make_cube();
  const limn::MeshStats s = limn::analyze(cube, limn::build_topology(cube));
  std::printf("limn %s: cube V=%zu E=%zu F=%zu genus=%lld\n", limn::version(), s.vertices, s.edges,
              s.faces, s.genus);
  return (s.vertices == 8 && s.edges == 12 && s.faces == 6 && s.genus == 0) ? 0 : 1;
}
