// limn convert: mesh format conversion (OBJ, PLY, OFF, STL, glTF/GLB in; OBJ, PLY, OFF, STL,
// GLB out).
#include <fmt/format.h>

#include "common.hpp"

namespace limn::cli {

void add_convert(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "convert",
      "Convert a mesh: OBJ, PLY, OFF, STL, glTF (.gltf/.glb) in; OBJ, PLY, OFF, STL, GLB out");
  struct Opts {
    std::string in, out, from, to;
    bool ascii = false, json = false, weld = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("IN", o->in, "Input mesh (.obj, .ply, .off, .stl, .gltf, .glb)")->required();
  cmd->add_option("OUT", o->out, "Output mesh (.obj, .ply, .off, .stl, .glb)")->required();
  cmd->add_option("--from", o->from,
                  "Input format, overriding the extension (obj, ply, off, stl, gltf, glb)");
  cmd->add_option("--to", o->to,
                  "Output format, overriding the extension (obj, ply, off, stl, glb)");
  cmd->add_flag("--ascii", o->ascii, "Write ascii PLY instead of binary little-endian");
  cmd->add_flag("--weld", o->weld,
                "glTF input: merge the vertices split at UV/normal seams into one cage vertex "
                "(UVs and normals kept per corner); no effect on other formats");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts and timings");
  cmd->callback([o] {
    Stopwatch sw;
    const WriteOptions w = output_options(o->out, o->to, o->ascii);
    size_t dropped = 0;
    const Mesh mesh = read_input(o->in, o->from, o->weld, &dropped, "--from");
    const double t_read = sw.lap();
    const nlohmann::json lost = write_output(mesh, o->out, {}, w);
    const double t_write = sw.lap();
    if (o->json) {
      nlohmann::json j = {{"input", o->in},
                          {"output", o->out},
                          {"vertices", mesh.vertex_count()},
                          {"faces", mesh.face_count()},
                          {"dropped", lost},
                          {"timings_ms", {{"read", t_read}, {"write", t_write}}}};
      if (dropped) j["dropped_degenerate_triangles"] = dropped;
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: {} vertices, {} faces ({:.1f} ms)\n", o->in, o->out,
                 mesh.vertex_count(), mesh.face_count(), sw.ms());
      if (dropped) fmt::print("dropped {} degenerate triangles on reading\n", dropped);
    }
  });
}

}  // namespace limn::cli
