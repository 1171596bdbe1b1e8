// limn subdivide: uniform Catmull-Clark refinement, or the feature-adaptive limit surface.
// --uniform without --limit runs the lean path (subdivide_uniform): only the last level is ever
// kept. --adaptive builds a patch table (fixed depth, or a depth per vertex from a camera and a
// pixel tolerance) and writes its watertight tessellation.
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <sstream>

#include "../common/jobs.hpp"
#include "adaptive.hpp"
#include "common.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"

namespace limn::cli {

namespace {

void run_adaptive(const std::string& mesh, const std::string& out_path, const std::string& format,
                  bool weld, const RepairFlags& repair, const AdaptiveOpts& a, bool json) {
  if (format_from_path(out_path) == MeshFormat::automatic)
    throw InputError(fmt::format("{}: cannot tell the output format from the extension", out_path));
  int w = 1280, h = 720;
  check_adaptive(a, w, h);
  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh cage = read_input(mesh, format, weld, repair, repaired);
  nlohmann::json timings = {{"read", sw.lap()}};
  const AdaptiveSurface surf = build_adaptive(cage, a, w, h, sw, timings);
  const bool dynamic = a.dynamic, measured = surf.measured;
  const int depth = surf.depth;
  const Camera& cam = surf.cam;
  const PatchTable& table = surf.table;
  const PatchStats& ps = surf.stats;
  const std::vector<float>& points = surf.points;
  const VertexErrorModel& model = surf.model;
  const std::vector<uint8_t>& vdepth = surf.vdepth;
  const std::vector<float>& estimate = surf.estimate;
  TessellateOptions to;
  to.factor = a.tess;
  if (a.tess_px > 0) to.camera = &cam, to.pixels_per_segment = a.tess_px;
  to.depth_colors = a.depth_colors;
  const Mesh out = tessellate_patches(cage, table, points, to);
  timings["tessellate"] = sw.lap();
  // UVs come along in every interpolation mode (smooth ones through face-varying patches).
  std::vector<std::string> lost;
  if (!cage.uv_indices.empty() && out.uv_indices.empty()) lost.emplace_back("uv");
  if (!cage.colors.empty() && out.colors.empty()) lost.emplace_back("colors");
  if (!cage.normal_indices.empty() && out.normal_indices.empty()) lost.emplace_back("normals");
  const nlohmann::json dropped = write_output(out, out_path, lost);
  timings["write"] = sw.lap();

  // Histogram of the depth of the irregular vertices (the ones that need any).
  std::map<int, size_t> hist;
  double worst_px = 0;
  for (size_t v = 0; v < cage.vertex_count(); ++v) {
    if (model.k[v] <= 0) continue;
    ++hist[dynamic ? vdepth[v] : depth];
    double x, y;
    if (cam.project(&cage.positions[3 * v], x, y) && x >= 0 && y >= 0 && x <= w && y <= h)
      worst_px = std::max(worst_px, double(estimate[v]));
  }
  const size_t nreg = table.regular_params.size(), ngreg = table.gregory_params.size();
  if (json) {
    nlohmann::json by_level = nlohmann::json::array();
    for (size_t k = 0; k < ps.regular_by_level.size(); ++k)
      by_level.push_back(
          {{"level", k}, {"regular", ps.regular_by_level[k]}, {"gregory", ps.gregory_by_level[k]}});
    nlohmann::json histogram = nlohmann::json::object();
    for (const auto& [d, n] : hist) histogram[std::to_string(d)] = n;
    size_t boundary = 0, transition = 0;
    for (const auto* params : {&table.regular_params, &table.gregory_params})
      for (const PatchParam& p : *params)
        boundary += p.boundary != 0, transition += p.transition != 0;
    nlohmann::json j = {
        {"input", mesh},
        {"repair", repaired},
        {"output", out_path},
        {"mode", dynamic ? "tolerance" : "depth"},
        {"depth", dynamic ? a.max_depth : depth},
        {"tolerance_px", dynamic ? nlohmann::json(a.tolerance) : nlohmann::json(nullptr)},
        {"errors", measured ? "measured" : "estimated"},
        {"camera",
         {{"eye", {cam.eye[0], cam.eye[1], cam.eye[2]}},
          {"target", {cam.target[0], cam.target[1], cam.target[2]}},
          {"fovy_deg", cam.fovy_deg},
          {"resolution", {w, h}}}},
        {"patches",
         {{"total", nreg + ngreg},
          {"regular", nreg},
          {"gregory", ngreg},
          {"boundary", boundary},
          {"transition", transition},
          {"by_level", by_level}}},
        {"vertex_depth_histogram", histogram},
        {"estimated_max_error_px", worst_px},
        {"points", table.point_count()},
        {"tess", a.tess_px > 0 ? nlohmann::json({{"pixels_per_segment", a.tess_px}})
                               : nlohmann::json(a.tess)},
        {"output_vertices", out.vertex_count()},
        {"output_faces", out.face_count()},
        {"dropped", dropped},
        {"timings_ms", timings}};
    fmt::print("{}\n", j.dump(2));
  } else {
    fmt::print(
        "{} -> {}: {} patches ({} regular, {} end caps), {} triangles, estimated max "
        "error {:.3g} px ({:.1f} ms)\n",
        mesh, out_path, nreg + ngreg, nreg, ngreg, out.face_count(), worst_px, sw.ms());
  }
}

}  // namespace

void add_subdivide(CLI::App& app) {
  auto* cmd = app.add_subcommand("subdivide", "Catmull-Clark subdivision of a cage");
  struct Opts {
    std::string mesh, out, format;
    int uniform = -1;
    bool limit = false, json = false, adaptive = false, weld = false;
    RepairFlags repair;
    AdaptiveOpts a;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("MESH", o->mesh,
                  "Control cage (OBJ with OpenSubdiv tags, PLY, OFF, STL, glTF/GLB)")
      ->required();
  cmd->add_option("-o,--output", o->out,
                  "Output mesh: .obj (UVs, normals, colours, tags), .ply/.glb (UVs, normals, "
                  "colours; seams split), .off/.stl (geometry only)")
      ->required();
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("--uniform", o->uniform, "Refine every face L times (0-8)");
  cmd->add_flag("--limit", o->limit, "Push the points to the limit surface, with limit normals");
  cmd->add_flag("--adaptive", o->adaptive,
                "Feature-adaptive limit surface: patches, tessellated watertight");
  add_adaptive_options(*cmd, o->a, false);
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts per level and timings");
  cmd->callback([o, cmd] {
    const bool uniform = cmd->count("--uniform") > 0;
    if (o->adaptive == uniform)
      throw InputError("subdivide: give exactly one of --uniform L and --adaptive");
    if (!o->adaptive)
      for (const char* a : {"--depth", "--tolerance", "--max-depth", "--errors", "--camera",
                            "--resolution", "--tess", "--tess-px", "--depth-colors"})
        if (cmd->count(a)) throw InputError(fmt::format("{} goes with --adaptive", a));
    if (o->adaptive) {
      if (o->limit) throw InputError("--limit goes with --uniform (--adaptive is the limit)");
      o->a.dynamic = cmd->count("--tolerance") > 0;
      if (cmd->count("--tess-px") && cmd->count("--tess"))
        throw InputError("--tess and --tess-px exclude each other");
      if (cmd->count("--tess-px") && !(o->a.tess_px > 0 && std::isfinite(o->a.tess_px)))
        throw InputError(
            fmt::format("--tess-px {}: must be a positive number of pixels", o->a.tess_px));
      run_adaptive(o->mesh, o->out, o->format, o->weld, o->repair, o->a, o->json);
      return;
    }
    jobs::check_uniform(o->uniform, jobs::Names::cli);
    if (format_from_path(o->out) == MeshFormat::automatic)
      throw InputError(fmt::format("{}: cannot tell the output format from the extension", o->out));
    Stopwatch sw;
    nlohmann::json repaired;
    const Mesh cage = read_input(o->mesh, o->format, o->weld, o->repair, repaired);
    const double t_read = sw.lap();
    jobs::UniformOutcome result =
        jobs::subdivide_uniform(cage, o->uniform, o->limit, o->mesh, jobs::Names::cli);
    const Mesh& out = result.mesh;
    sw.lap();
    const nlohmann::json dropped = write_output(out, o->out);
    const double t_write = sw.lap();

    if (o->json) {
      nlohmann::json j = std::move(result.report);
      j["input"] = o->mesh;
      j["repair"] = repaired;
      j["output"] = o->out;
      j["dropped"] = dropped;
      j["timings_ms"]["read"] = t_read;
      j["timings_ms"]["write"] = t_write;
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: level {}{}, {} vertices, {} faces ({:.1f} ms)\n", o->mesh, o->out,
                 o->uniform, o->limit ? " (limit)" : "", out.vertex_count(), out.face_count(),
                 sw.ms());
    }
  });
}

}  // namespace limn::cli
