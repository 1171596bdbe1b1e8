// limn unwrap: an automatic UV atlas (limn/atlas/unwrap.hpp), written as the mesh with new UVs.
#include <fmt/format.h>

#include "../common/jobs.hpp"
#include "common.hpp"

namespace limn::cli {

namespace {

struct UnwrapOpts {
  std::string mesh, out, format;
  jobs::UnwrapJob job;
  bool json = false, weld = false;
  RepairFlags repair;
};

void run(const UnwrapOpts& o) {
  if (format_from_path(o.out) == MeshFormat::automatic)
    throw InputError(fmt::format(
        "{}: cannot tell the output format from the extension (.obj, .glb, .ply, .off)", o.out));
  jobs::check(o.job, jobs::Names::cli);
  check_writable_folder(o.out, "output");

  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_read = sw.lap();
  const jobs::UnwrapOutcome outcome = jobs::unwrap(mesh, o.job, o.mesh);
  sw.lap();
  const nlohmann::json dropped = write_output(outcome.result.mesh, o.out);
  const double t_write = sw.lap();

  const nlohmann::json& r = outcome.report;
  if (o.json) {
    nlohmann::json j = r;
    j["input"] = o.mesh;
    j["output"] = o.out;
    j["repair"] = repaired;
    j["faces"] = mesh.face_count();
    j["dropped"] = dropped;
    j["timings_ms"]["read"] = t_read;
    j["timings_ms"]["write"] = t_write;
    j["timings_ms"]["total"] = sw.ms();
    fmt::print("{}\n", j.dump(2));
  } else {
    const size_t tiles = r["tiles"];
    fmt::print(
        "{} -> {}: {} charts in {} {} of {}x{}, {:.1f}% used, stretch L2 {:.4f} ({:.1f} ms)\n",
        o.mesh, o.out, r["charts"].get<size_t>(), tiles, tiles == 1 ? "atlas" : "UDIM tiles",
        o.job.size, o.job.size, 100 * r["utilization"].get<double>(), r["stretch_l2"].get<double>(),
        sw.ms());
  }
}

}  // namespace

void add_unwrap(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "unwrap",
      "Give a mesh an automatic UV atlas: flat, low-stretch charts (VSA cut until each one's "
      "conformal map is good), packed with a gutter into one square atlas or UDIM tiles");
  auto o = std::make_shared<UnwrapOpts>();
  cmd->add_option("MESH", o->mesh,
                  "Input mesh (.obj, .ply, .off, .stl, .gltf, .glb); any UVs it "
                  "has are replaced")
      ->required();
  cmd->add_option("-o,--output", o->out, "Output mesh with the UVs (.obj, .glb)")->required();
  cmd->add_option("--size", o->job.size,
                  "Texels per side of the atlas or of each UDIM tile (1024)");
  cmd->add_option("--texels-per-unit", o->job.texels_per_unit,
                  "Texel density (texels per model unit); default: the densest whose charts fit");
  cmd->add_option("--tiles", o->job.tiles,
                  "UDIM tiles to use at most (1: one atlas in [0,1]; more: tiles 1001, 1002, ...)");
  cmd->add_option("--padding", o->job.padding, "Free texels around every chart (2)");
  cmd->add_option("--max-stretch", o->job.max_stretch,
                  "Largest Sander L2 stretch a chart keeps before it is cut (1.003)");
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object with the counts, figures and timings");
  cmd->callback([o] { run(*o); });
}

}  // namespace limn::cli
