// limn convert: mesh format conversion (OBJ, PLY, OFF in; OBJ, PLY, OFF, GLB out).
#include <fmt/format.h>

#include "common.hpp"

namespace limn::cli {

void add_convert(CLI::App& app) {
  auto* cmd = app.add_subcommand("convert", "Convert a mesh between OBJ, PLY, OFF and binary glTF");
  struct Opts {
    std::string in, out, from, to;
    bool ascii = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("IN", o->in, "Input mesh")->required();
  cmd->add_option("OUT", o->out, "Output mesh (.obj, .ply, .off, .glb)")->required();
  cmd->add_option("--from", o->from, "Input format, overriding the extension");
  cmd->add_option("--to", o->to, "Output format, overriding the extension");
  cmd->add_flag("--ascii", o->ascii, "Write ascii PLY instead of binary little-endian");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts and timings");
  cmd->callback([o] {
    Stopwatch sw;
    WriteOptions w;
    w.format = parse_format_option(o->to, "--to");
    w.ascii = o->ascii;
    if (w.format == MeshFormat::automatic && format_from_path(o->out) == MeshFormat::automatic)
      throw InputError(
          fmt::format("{}: cannot tell the output format from the extension (use "
                      ".obj, .ply, .off or .glb, or --to)",
                      o->out));
    const Mesh mesh = read_mesh(o->in, parse_format_option(o->from, "--from"));
    const double t_read = sw.lap();
    write_mesh(mesh, o->out, w);
    const double t_write = sw.lap();
    if (o->json) {
      nlohmann::json j = {{"input", o->in},
                          {"output", o->out},
                          {"vertices", mesh.vertex_count()},
                          {"faces", mesh.face_count()},
                          {"timings_ms", {{"read", t_read}, {"write", t_write}}}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: {} vertices, {} faces ({:.1f} ms)\n", o->in, o->out,
                 mesh.vertex_count(), mesh.face_count(), sw.ms());
    }
  });
}

}  // namespace limn::cli
