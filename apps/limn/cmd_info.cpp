// limn info: counts and structure of a mesh.
#include <fmt/format.h>

#include "common.hpp"

namespace limn::cli {

void add_info(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "info", "Print counts and structure of a mesh (OBJ, PLY, OFF, STL, glTF/GLB)");
  struct Opts {
    std::string mesh, format;
    bool json = false, weld = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("MESH", o->mesh, "Mesh file")->required();
  cmd->add_option("--format", o->format,
                  "Input format, overriding the extension (obj, ply, off, stl, gltf, glb)");
  cmd->add_flag("--weld", o->weld,
                "glTF input: merge the vertices split at UV/normal seams into one cage vertex "
                "(UVs and normals kept per corner); no effect on other formats");
  cmd->add_flag("--json", o->json, "Print one JSON object instead of text");
  cmd->callback([o] {
    Stopwatch sw;
    size_t dropped = 0;
    const Mesh mesh = read_input(o->mesh, o->format, o->weld, &dropped);
    const double t_read = sw.lap();
    const Topology topo = build_topology(mesh);
    const double t_topo = sw.lap();
    const MeshStats stats = analyze(mesh, topo);
    const double t_analyze = sw.lap();
    if (o->json) {
      nlohmann::json j = stats_json(stats);
      j["file"] = o->mesh;
      if (dropped) j["dropped_degenerate_triangles"] = dropped;
      j["timings_ms"] = {{"read", t_read}, {"topology", t_topo}, {"analysis", t_analyze}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{}\n{}", o->mesh, stats_text(stats));
      if (dropped) fmt::print("dropped         {} degenerate triangles on reading\n", dropped);
      fmt::print("time            read {:.1f} ms, adjacency {:.1f} ms, analysis {:.1f} ms\n",
                 t_read, t_topo, t_analyze);
    }
  });
}

}  // namespace limn::cli
