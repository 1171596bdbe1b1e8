// libFuzzer target: the STL reader must either return a valid, welded mesh or throw InputError;
// the mesh written back as binary STL must read again as the same mesh, with nothing dropped.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/weld.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_stl(in, "fuzz.stl");
  } catch (const limn::InputError&) {
    return 0;
  }
  // Already welded: welding again changes nothing.
  if (limn::weld_vertices(m).vertex_count() != m.vertex_count()) __builtin_trap();
  std::string out;
  limn::write_stl(m, out);
  size_t dropped = 1;
  const limn::Mesh r = limn::read_stl(out, "roundtrip.stl", &dropped);  // must not throw
  if (dropped != 0 || r.positions != m.positions || r.face_vertices != m.face_vertices ||
      r.face_offsets != m.face_offsets)
    __builtin_trap();
  return 0;
}
