// libFuzzer target: the PLY reader must either return a valid mesh or throw InputError; the mesh
// written back (binary and ascii) must read again with the same vertices and faces.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limn/io/mesh_io.hpp"

namespace {

void check_round_trip(const limn::Mesh& m, bool ascii) {
  std::string out;
  limn::write_ply(m, out, ascii);
  const limn::Mesh r = limn::read_ply(out, "roundtrip.ply");  // must not throw
  if (r.vertex_count() != m.vertex_count() || r.face_count() != m.face_count() ||
      r.positions != m.positions || r.face_vertices != m.face_vertices ||
      r.face_offsets != m.face_offsets || r.normals != m.normals || r.uvs != m.uvs ||
      r.colors.size() != m.colors.size())
    __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_ply(in, "fuzz.ply");
  } catch (const limn::InputError&) {
    return 0;
  }
  check_round_trip(m, /*ascii=*/false);
  check_round_trip(m, /*ascii=*/true);
  return 0;
}
