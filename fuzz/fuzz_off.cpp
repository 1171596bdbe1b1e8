// libFuzzer target: the OFF reader must either return a valid mesh or throw InputError; the mesh
// written back must read again with the same vertices and faces.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_off(in, "fuzz.off");
  } catch (const limn::InputError&) {
    return 0;
  }
  std::string text;
  limn::write_off(m, text);
  const limn::Mesh r = limn::read_off(text, "roundtrip.off");  // must not throw
  if (r.vertex_count() != m.vertex_count() || r.face_count() != m.face_count() ||
      r.positions != m.positions || r.face_vertices != m.face_vertices ||
      r.face_offsets != m.face_offsets)
    __builtin_trap();
  return 0;
}
