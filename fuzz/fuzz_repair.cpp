// libFuzzer target: an OBJ read as a polygon soup and repaired must come out valid, edge- and
// vertex-manifold and consistently oriented, with every vertex at an input vertex's position.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/repair.hpp"
#include "limn/mesh/topology.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh soup;
  try {
    soup = limn::read_obj(in, "fuzz.obj", /*soup=*/true);
  } catch (const limn::InputError&) {
    return 0;
  }
  const limn::Mesh m = limn::repair_mesh(soup);  // must not throw
  limn::validate(m);                             // throws (and so fails) when broken
  const limn::Topology t = limn::build_topology(m);
  const limn::MeshStats s = limn::analyze(m, t);
  if (s.non_manifold_edges || s.non_manifold_vertices || s.inconsistent_edges ||
      s.unreferenced_vertices)
    __builtin_trap();
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    bool found = false;
    for (size_t w = 0; w < soup.vertex_count() && !found; ++w)
      found = std::equal(&m.positions[3 * v], &m.positions[3 * v] + 3, &soup.positions[3 * w]);
    if (!found) __builtin_trap();
  }
  return 0;
}
