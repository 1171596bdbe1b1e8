// limn simplify: variational shape approximation (greedy or Lloyd) into a few feature-aligned
// polygons or triangles, with a report of the energy, the time per phase and, when asked, the
// distance to the input. Nothing is written unless the result passes validate_simplified.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "../common/jobs.hpp"
#include "common.hpp"
#include "limn/simplify/vsa.hpp"

namespace limn::cli {

namespace {

struct SimplifyOpts {
  std::string mesh, out, labels, format;
  jobs::SimplifyJob job;
  bool json = false, weld = false;
  RepairFlags repair;
};

void run(const SimplifyOpts& o) {
  if (format_from_path(o.out) == MeshFormat::automatic)
    throw InputError(fmt::format(
        "{}: cannot tell the output format from the extension (.obj, .ply, .off, .glb)", o.out));
  jobs::check(o.job, jobs::Names::cli);
  check_writable_folder(o.out, "output");
  if (!o.labels.empty()) check_writable_folder(o.labels, "labels");

  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_read = sw.lap();
  const jobs::SimplifyOutcome outcome = jobs::simplify(mesh, o.job, o.mesh);
  const VsaResult& r = outcome.result;
  sw.lap();

  // Vertices are input vertices: colours, UVs and normals come along (carry_attributes); the
  // subdivision tags describe the input's edges and faces, which are gone.
  std::vector<std::string> lost;
  if (!mesh.crease_sharpness.empty()) lost.emplace_back("creases");
  if (!mesh.corner_sharpness.empty()) lost.emplace_back("corners");
  if (!mesh.hole_faces.empty()) lost.emplace_back("holes");
  const nlohmann::json dropped = write_output(r.output.mesh, o.out, lost);
  if (!o.labels.empty()) {
    std::string text;
    text.reserve(r.labels.size() * 4);
    for (uint32_t k : r.labels) text += fmt::format("{}\n", k);
    try {
      write_file_atomic(o.labels, text);
    } catch (...) {
      std::error_code ec;
      std::filesystem::remove(o.out, ec);  // no half of a result
      throw;
    }
  }
  const double t_write = sw.lap();

  const VsaStats& st = r.stats;
  const double e_area = st.total_area > 0 ? st.energy / st.total_area : 0.0;
  size_t polygons = 0;
  for (size_t f = 0; f < r.output.mesh.face_count(); ++f)
    polygons += r.output.mesh.face_size(f) != 3;
  if (o.json) {
    nlohmann::json j = outcome.report;
    j["input"] = o.mesh;
    j["output"] = o.out;
    j["dropped"] = dropped;
    j["repair"] = repaired;
    j["labels"] = o.labels.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.labels);
    j["timings_ms"]["read"] = t_read;
    j["timings_ms"]["write"] = t_write;
    j["timings_ms"]["total"] = sw.ms();
    fmt::print("{}\n", j.dump(2));
  } else {
    const nlohmann::json& d = outcome.report["distance"];
    const std::string distance =
        d.is_null() ? ""
                    : fmt::format(", Hausdorff {:.3g} RMS {:.3g} of the diagonal",
                                  d["hausdorff"].get<double>(), d["rms"].get<double>());
    fmt::print(
        "{} -> {}: {} clusters, E/area {:.4g}, {} vertices, {} faces ({} polygons){} (seeding "
        "{:.0f} ms, optimisation {:.0f} ms, meshing {:.0f} ms; {:.0f} ms in all)\n",
        o.mesh, o.out, st.clusters, e_area, r.output.mesh.vertex_count(),
        r.output.mesh.face_count(), polygons, distance, st.seeding_ms, st.optimise_ms,
        st.meshing_ms, sw.ms());
  }
}

}  // namespace

void add_simplify(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "simplify", "Variational shape approximation: a few feature-aligned polygons (or triangles)");
  auto o = std::make_shared<SimplifyOpts>();
  cmd->add_option("MESH", o->mesh,
                  "Input mesh (OBJ, PLY, OFF, STL, glTF/GLB); edge-manifold, oriented")
      ->required();
  cmd->add_option("-o,--output", o->out, "Output mesh (.obj, .ply, .off, .stl, .glb)")->required();
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("--proxies", o->job.proxies,
                  "K, the number of clusters (polygons); default 100, or 10 to start from with "
                  "--target-error");
  cmd->add_option("--target-error", o->job.target_error,
                  "Add clusters (splitting the worst) until E / surface area <= this");
  cmd->add_option("--max-proxies", o->job.max_proxies,
                  "Cap on K for --target-error (default: a third of the faces)");
  cmd->add_option("--method", o->job.method,
                  "'greedy' (local greedy optimiser, default) or 'lloyd' (Lloyd iterations)");
  cmd->add_option("--seeding", o->job.seeding,
                  "'curvature' (adaptive, default) or 'random' seed clusters");
  cmd->add_option("--seed", o->job.seed, "Random seed for the choice of seed faces (default 1)");
  cmd->add_flag("--no-fill", o->job.no_fill,
                "Keep the number of clusters the curvature seeding reaches when it is below K "
                "(default: split the worst clusters up to K)");
  cmd->add_option("--iterations", o->job.iterations, "--method lloyd: at most N iterations (30)");
  cmd->add_option("--teleports", o->job.teleports,
                  "--method greedy: after convergence, up to N merge-and-split moves that lower E "
                  "(default 16; 0 is the published method)");
  cmd->add_option("--split-threshold", o->job.split_threshold,
                  "Split a polygon edge AB at its farthest boundary vertex P while "
                  "d(P, AB)/|AB| exceeds this (default 0.5; smaller keeps more vertices)");
  cmd->add_flag("--polygons", o->job.polygons,
                "Write one polygon per cluster (clusters with holes come out as triangles)");
  cmd->add_option("--labels", o->labels,
                  "Write the cluster id of every input face, one per line, in file order");
  cmd->add_option("--distance", o->job.distance,
                  "Also measure the Hausdorff and RMS distance between output and input, with "
                  "this many points sampled (200000 when given without a value: --distance or "
                  "--distance=N)")
      ->expected(0, 1)
      ->default_str("200000");
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json,
                "Print one JSON object: E, E/area, K, counts, timings, and with --distance the "
                "Hausdorff and RMS distance");
  cmd->callback([o] { run(*o); });
}

}  // namespace limn::cli
