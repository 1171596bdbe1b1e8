// limn shape: write a built-in procedural shape.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common.hpp"
#include "limn/mesh/shapes.hpp"

namespace limn::cli {

void add_shape(CLI::App& app) {
  auto* cmd = app.add_subcommand("shape", "Write a built-in procedural shape");
  struct Opts {
    std::string name, out;
    uint64_t seed = 1;
    bool list = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("NAME", o->name, fmt::format("Shape: {}", fmt::join(shape_names(), ", ")));
  cmd->add_option("-o,--output", o->out, "Output mesh (.obj, .ply, .off, .stl, .glb)");
  cmd->add_option("--seed", o->seed, "Seed for the random placement of extraordinary vertices");
  cmd->add_flag("--list", o->list, "List the shape names");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts and timings");
  cmd->callback([o] {
    if (o->list) {
      for (const auto& n : shape_names()) fmt::print("{}\n", n);
      return;
    }
    if (o->name.empty()) throw InputError("shape: a NAME is required (see --list)");
    if (o->out.empty()) throw InputError("shape: -o OUTPUT is required");
    Stopwatch sw;
    const Mesh mesh = make_shape(o->name, o->seed);
    const double t_make = sw.lap();
    write_mesh(mesh, o->out);
    const double t_write = sw.lap();
    if (o->json) {
      nlohmann::json j = {
          {"shape", o->name},           {"seed", o->seed},
          {"output", o->out},           {"vertices", mesh.vertex_count()},
          {"faces", mesh.face_count()}, {"timings_ms", {{"build", t_make}, {"write", t_write}}}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: {} vertices, {} faces\n", o->name, o->out, mesh.vertex_count(),
                 mesh.face_count());
    }
  });
}

}  // namespace limn::cli
