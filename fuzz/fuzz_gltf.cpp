// libFuzzer target: the glTF reader (JSON and GLB bytes alike) must either return a valid mesh or
// throw InputError; welding must keep it valid, and the mesh written back as GLB must read again
// with the same triangles. Memory only: external buffers resolve against a folder that does not
// exist, so no URI can reach a file.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/weld.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_gltf(in, "fuzz.gltf", "/nonexistent-limn-fuzz-dir");
  } catch (const limn::InputError&) {
    return 0;
  }
  limn::validate(limn::weld_vertices(m), "welded");  // throws (and so crashes) if invalid
  if (m.face_count() == 0) return 0;
  std::string glb;
  limn::write_glb(m, glb);
  const limn::Mesh r = limn::read_gltf(glb, "roundtrip.glb", "/nonexistent-limn-fuzz-dir");
  if (r.face_offsets != m.face_offsets) __builtin_trap();
  for (size_t c = 0; c < m.corner_count(); ++c)
    for (size_t k = 0; k < 3; ++k)
      if (r.positions[3 * size_t(r.face_vertices[c]) + k] !=
          m.positions[3 * size_t(m.face_vertices[c]) + k])
        __builtin_trap();
  return 0;
}
