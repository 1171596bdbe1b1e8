// limn simplify: variational shape approximation (greedy or Lloyd) into a few feature-aligned
// polygons or triangles, with a report of the energy, the time per phase and, when asked, the
// distance to the input. Nothing is written unless the result passes validate_simplified.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "common.hpp"
#include "limn/simplify/distance.hpp"
#include "limn/simplify/validate.hpp"
#include "limn/simplify/vsa.hpp"

namespace limn::cli {

namespace {

struct SimplifyOpts {
  std::string mesh, out, labels, format, method = "greedy", seeding = "curvature";
  size_t proxies = 100, max_proxies = 0;
  size_t distance = 0;  // points sampled for the distance report; 0: no report
  double target_error = 0, split_threshold = 0.5;
  uint64_t seed = 1;
  size_t iterations = 30, teleports = 16;
  bool polygons = false, json = false, no_fill = false, weld = false;
  RepairFlags repair;
};

// The folder a file will be written into must exist before minutes of work are spent.
void check_writable_folder(const std::string& path, const char* what) {
  const std::filesystem::path dir = std::filesystem::absolute(path).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(fmt::format("{}: {} folder {} does not exist", path, what, dir.string()));
}

void run(const SimplifyOpts& o, CLI::App* cmd) {
  if (format_from_path(o.out) == MeshFormat::automatic)
    throw InputError(fmt::format(
        "{}: cannot tell the output format from the extension (.obj, .ply, .off, .glb)", o.out));
  if (o.method != "greedy" && o.method != "lloyd")
    throw InputError(fmt::format("--method {}: expected 'greedy' or 'lloyd'", o.method));
  if (o.seeding != "curvature" && o.seeding != "random")
    throw InputError(fmt::format("--seeding {}: expected 'curvature' or 'random'", o.seeding));
  if (o.proxies < 1 || o.proxies > 10000000)
    throw InputError(fmt::format("--proxies {}: must be 1-10000000", o.proxies));
  if (cmd->count("--target-error") && !(o.target_error > 0 && std::isfinite(o.target_error)))
    throw InputError(fmt::format("--target-error {}: must be a positive number", o.target_error));
  if (!(o.split_threshold >= 0 && std::isfinite(o.split_threshold)))
    throw InputError(fmt::format("--split-threshold {}: must be a number >= 0", o.split_threshold));
  if (o.iterations < 1 || o.iterations > 10000)
    throw InputError(fmt::format("--iterations {}: must be 1-10000", o.iterations));
  if (cmd->count("--distance") && (o.distance < 1 || o.distance > 100000000))
    throw InputError(fmt::format("--distance {}: must be 1-100000000 samples", o.distance));
  check_writable_folder(o.out, "output");
  if (!o.labels.empty()) check_writable_folder(o.labels, "labels");

  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_read = sw.lap();

  VsaOptions vo;
  vo.proxies = o.proxies;
  if (o.target_error > 0 && !cmd->count("--proxies")) vo.proxies = 10;
  vo.target_error = o.target_error;
  vo.max_proxies = o.max_proxies;
  vo.fill = !o.no_fill;
  vo.method = o.method == "lloyd" ? VsaMethod::lloyd : VsaMethod::greedy;
  vo.seeding.method = o.seeding == "random" ? SeedingMethod::random : SeedingMethod::curvature;
  vo.seeding.seed = o.seed;
  vo.lloyd.iterations = o.iterations;
  vo.teleports = o.teleports;
  vo.meshing.split_threshold = o.split_threshold;
  vo.meshing.polygons = o.polygons;
  const VsaResult r = simplify_vsa(mesh, vo, o.mesh);
  sw.lap();

  const Box box = bounding_box(mesh);
  const SimplifiedCheck check = validate_simplified(r.output.mesh, box);
  if (!check.ok())
    throw std::runtime_error(fmt::format("{}: the simplified mesh is invalid ({}); nothing written",
                                         o.mesh, check.first_problem));
  const double t_validate = sw.lap();
  // The distance report samples and ray-casts the output (most of a run's time on meshes of
  // tens of thousands of faces): only when asked.
  SurfaceDistance dist{};
  if (o.distance) dist = surface_distance(r.output.mesh, mesh, o.distance, o.seed);
  const double t_distance = sw.lap();

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
  const MeshingStats& ms = r.output.stats;
  const double diag = box.diagonal();
  const double e_norm = diag > 0 ? st.energy / (diag * diag) : 0.0;
  const double e_area = st.total_area > 0 ? st.energy / st.total_area : 0.0;
  size_t triangles = 0, polygons = 0;
  for (size_t f = 0; f < r.output.mesh.face_count(); ++f)
    ++(r.output.mesh.face_size(f) == 3 ? triangles : polygons);
  if (o.json) {
    nlohmann::json j = {
        {"input", o.mesh},
        {"output", o.out},
        {"dropped", dropped},
        {"repair", repaired},
        {"labels", o.labels.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.labels)},
        {"method", o.method},
        {"seeding", o.seeding},
        {"proxies_requested", vo.proxies},
        {"target_error",
         o.target_error > 0 ? nlohmann::json(o.target_error) : nlohmann::json(nullptr)},
        {"clusters", st.clusters},
        {"clusters_seeded", st.seeded},
        {"clusters_for_components", st.component_clusters},
        {"clusters_split", st.split_clusters},
        {"teleports", st.teleports},
        {"clusters_split_for_meshing", ms.cluster_splits},
        {"energy", st.energy},
        {"energy_per_area", e_area},
        {"energy_unit_diagonal", e_norm},
        {"surface_area", st.total_area},
        {"input_faces", mesh.face_count()},
        {"input_vertices", mesh.vertex_count()},
        {"output_vertices", r.output.mesh.vertex_count()},
        {"output_faces", r.output.mesh.face_count()},
        {"output_triangles", triangles},
        {"output_polygons", polygons},
        {"meshing",
         {{"split_threshold", o.split_threshold},
          {"anchors", ms.anchors},
          {"forced_anchors", ms.forced_anchors},
          {"chains", ms.chains},
          {"forced_chain_splits", ms.forced_splits},
          {"bridges", ms.bridges},
          {"polygons_written", ms.polygons},
          {"polygons_triangulated", ms.triangulated},
          {"clusters_fanned", ms.fans}}},
        {"distance", o.distance ? nlohmann::json{{"hausdorff", dist.hausdorff},
                                                 {"rms", dist.rms_to_reference},
                                                 {"max_output_to_input", dist.max_to_reference},
                                                 {"max_input_to_output", dist.max_from_reference},
                                                 {"samples", dist.samples},
                                                 {"relative_to", "input bounding-box diagonal"}}
                                : nlohmann::json(nullptr)},
        {"greedy",
         {{"moves", st.greedy.moves},
          {"evaluations", st.greedy.evaluations},
          {"rounds", st.greedy.rounds},
          {"local_connectivity_checks", st.greedy.local_checks},
          {"searched_connectivity_checks", st.greedy.search_checks},
          {"refused_disconnecting", st.greedy.refused_disconnect},
          {"refused_search_budget", st.greedy.refused_budget}}},
        {"lloyd_iterations", st.lloyd.iterations},
        {"valid", check.ok()},
        {"timings_ms",
         {{"read", t_read},
          {"prepare", st.prepare_ms},
          {"seeding", st.seeding_ms},
          {"optimisation", st.optimise_ms},
          {"meshing", st.meshing_ms},
          {"validate", t_validate},
          {"distance", o.distance ? nlohmann::json(t_distance) : nlohmann::json(nullptr)},
          {"write", t_write},
          {"total", sw.ms()}}}};
    fmt::print("{}\n", j.dump(2));
  } else {
    const std::string distance = o.distance
                                     ? fmt::format(", Hausdorff {:.3g} RMS {:.3g} of the diagonal",
                                                   dist.hausdorff, dist.rms_to_reference)
                                     : "";
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
  cmd->add_option("--proxies", o->proxies,
                  "K, the number of clusters (polygons); default 100, or 10 to start from with "
                  "--target-error");
  cmd->add_option("--target-error", o->target_error,
                  "Add clusters (splitting the worst) until E / surface area <= this");
  cmd->add_option("--max-proxies", o->max_proxies,
                  "Cap on K for --target-error (default: a third of the faces)");
  cmd->add_option("--method", o->method,
                  "'greedy' (local greedy optimiser, default) or 'lloyd' (Lloyd iterations)");
  cmd->add_option("--seeding", o->seeding,
                  "'curvature' (adaptive, default) or 'random' seed clusters");
  cmd->add_option("--seed", o->seed, "Random seed for the choice of seed faces (default 1)");
  cmd->add_flag("--no-fill", o->no_fill,
                "Keep the number of clusters the curvature seeding reaches when it is below K "
                "(default: split the worst clusters up to K)");
  cmd->add_option("--iterations", o->iterations, "--method lloyd: at most N iterations (30)");
  cmd->add_option("--teleports", o->teleports,
                  "--method greedy: after convergence, up to N merge-and-split moves that lower E "
                  "(default 16; 0 is the published method)");
  cmd->add_option("--split-threshold", o->split_threshold,
                  "Split a polygon edge AB at its farthest boundary vertex P while "
                  "d(P, AB)/|AB| exceeds this (default 0.5; smaller keeps more vertices)");
  cmd->add_flag("--polygons", o->polygons,
                "Write one polygon per cluster (clusters with holes come out as triangles)");
  cmd->add_option("--labels", o->labels,
                  "Write the cluster id of every input face, one per line, in file order");
  cmd->add_option("--distance", o->distance,
                  "Also measure the Hausdorff and RMS distance between output and input, with "
                  "this many points sampled (200000 when given without a value: --distance or "
                  "--distance=N)")
      ->expected(0, 1)
      ->default_str("200000");
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json,
                "Print one JSON object: E, E/area, K, counts, timings, and with --distance the "
                "Hausdorff and RMS distance");
  cmd->callback([o, cmd] { run(*o, cmd); });
}

}  // namespace limn::cli
