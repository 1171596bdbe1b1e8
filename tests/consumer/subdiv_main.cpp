// A program that uses only the subdivision layer (limn::subdiv, so limn::mesh and limn::core):
// it must link no Embree, tinygltf, tinyobjloader or OpenGL (run.cmake checks its libraries).
#include <limn/mesh/shapes.hpp>
#include <limn/subdiv/refine.hpp>

#include <cstdio>

int main() {
  const limn::Mesh cube = limn::make_cube();
  const limn::Mesh fine = limn::subdivide_uniform(cube, 2, limn::subdiv_options(cube));
  std::printf("cube at level 2: V=%zu F=%zu\n", fine.vertex_count(), fine.face_count());
  // Catmull-Clark on a closed cube: F = 6 * 4^2, V = F + 2 (Euler, all quads).
  return fine.face_count() == 96 && fine.vertex_count() == 98 ? 0 : 1;
}
