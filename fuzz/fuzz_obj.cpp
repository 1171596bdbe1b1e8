// libFuzzer target: the OBJ reader must either return a valid mesh or throw InputError; a written
// and re-read mesh must keep its counts.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_obj(in, "fuzz.obj");
  } catch (const limn::InputError&) {
    return 0;
  }
  std::string text;
  limn::write_obj(m, text);
  const limn::Mesh r = limn::read_obj(text, "roundtrip.obj");  // must not throw
  if (r.vertex_count() != m.vertex_count() || r.face_vertices != m.face_vertices ||
      r.crease_sharpness.size() != m.crease_sharpness.size())
    __builtin_trap();
  return 0;
}
