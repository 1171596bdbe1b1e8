// limn repair: a polygon soup made into a clean, oriented, manifold mesh (limn/mesh/repair.hpp).
#include <fmt/format.h>

#include "common.hpp"

namespace limn::cli {

void add_repair(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "repair",
      "Repair a mesh: weld near vertices, drop degenerate and duplicate faces, orient each piece "
      "consistently (closed ones outward), split non-manifold edges and vertices, drop "
      "unreferenced vertices");
  struct Opts {
    std::string in, out, from, to;
    double tolerance = RepairOptions{}.weld_tolerance;
    bool ascii = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("IN", o->in, "Input mesh (.obj, .ply, .off, .stl, .gltf, .glb)")->required();
  cmd->add_option("-o,--output", o->out, "Repaired mesh (.obj, .ply, .off, .stl, .glb)")
      ->required();
  cmd->add_option("--weld-tolerance", o->tolerance,
                  "Weld vertices closer than this fraction of the bounding-box diagonal "
                  "(0: only equal positions)")
      ->check(CLI::Range(0.0, 0.1));
  cmd->add_option("--from", o->from,
                  "Input format, overriding the extension (obj, ply, off, stl, gltf, glb)");
  cmd->add_option("--to", o->to,
                  "Output format, overriding the extension (obj, ply, off, stl, glb)");
  cmd->add_flag("--ascii", o->ascii, "Write ascii PLY instead of binary little-endian");
  cmd->add_flag("--json", o->json, "Print one JSON object with the counts and timings");
  cmd->callback([o] {
    Stopwatch sw;
    const WriteOptions w = output_options(o->out, o->to, o->ascii);
    ReadOptions r;
    r.format = parse_format_option(o->from, "--from");
    size_t dropped = 0;
    const Mesh soup = read_soup(o->in, r, dropped);
    const double t_read = sw.lap();
    RepairReport report;
    const Mesh mesh = repair_input(soup, dropped, o->in, o->tolerance, report);
    const double t_repair = sw.lap();
    const nlohmann::json lost = write_output(mesh, o->out, {}, w);
    const double t_write = sw.lap();
    if (o->json) {
      const nlohmann::json j = {
          {"input", o->in},
          {"output", o->out},
          {"input_vertices", soup.vertex_count()},
          {"input_faces", soup.face_count() + dropped},
          {"vertices", mesh.vertex_count()},
          {"faces", mesh.face_count()},
          {"weld_tolerance", o->tolerance},
          {"repair", repair_json(report)},
          {"dropped", lost},
          {"timings_ms", {{"read", t_read}, {"repair", t_repair}, {"write", t_write}}}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: {} vertices, {} faces ({:.1f} ms)\n", o->in, o->out,
                 mesh.vertex_count(), mesh.face_count(), sw.ms());
    }
  });
}

}  // namespace limn::cli
