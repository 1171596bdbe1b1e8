#include "jobs.hpp"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <stdexcept>

#include "limn/atlas/uv_metrics.hpp"
#include "limn/paint/brush.hpp"
#include "limn/simplify/distance.hpp"
#include "limn/simplify/validate.hpp"
#include "limn/subdiv/refine.hpp"
#include "reports.hpp"
#include "stopwatch.hpp"

namespace limn::jobs {

std::string option_name(Names names, std::string_view dashed) {
  if (names == Names::cli) return "--" + std::string(dashed);
  std::string s(dashed);
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
}

Camera view_camera(const Mesh& mesh, int width, int height, const std::optional<Camera>& view) {
  Camera cam = frame_camera(mesh, width, height);
  if (view) {
    for (int k = 0; k < 3; ++k) cam.eye[k] = view->eye[k], cam.target[k] = view->target[k];
    cam.fovy_deg = view->fovy_deg;
  }
  return cam;
}

void check(const SimplifyJob& o, Names names) {
  const auto name = [names](std::string_view n) { return option_name(names, n); };
  if (o.method != "greedy" && o.method != "lloyd")
    throw InputError(fmt::format("{} {}: expected 'greedy' or 'lloyd'", name("method"), o.method));
  if (o.seeding != "curvature" && o.seeding != "random")
    throw InputError(
        fmt::format("{} {}: expected 'curvature' or 'random'", name("seeding"), o.seeding));
  if (o.proxies && (*o.proxies < 1 || *o.proxies > 10000000))
    throw InputError(fmt::format("{} {}: must be 1-10000000", name("proxies"), *o.proxies));
  if (o.target_error && !(*o.target_error > 0 && std::isfinite(*o.target_error)))
    throw InputError(
        fmt::format("{} {}: must be a positive number", name("target-error"), *o.target_error));
  if (!(o.split_threshold >= 0 && std::isfinite(o.split_threshold)))
    throw InputError(
        fmt::format("{} {}: must be a number >= 0", name("split-threshold"), o.split_threshold));
  if (o.iterations < 1 || o.iterations > 10000)
    throw InputError(fmt::format("{} {}: must be 1-10000", name("iterations"), o.iterations));
  if (o.distance && (*o.distance < 1 || *o.distance > 100000000))
    throw InputError(
        fmt::format("{} {}: must be 1-100000000 samples", name("distance"), *o.distance));
}

SimplifyOutcome simplify(const Mesh& mesh, const SimplifyJob& o, std::string_view name) {
  VsaOptions vo;
  vo.proxies = o.proxies.value_or(o.target_error ? 10 : 100);
  vo.target_error = o.target_error.value_or(0.0);
  vo.max_proxies = o.max_proxies;
  vo.fill = !o.no_fill;
  vo.method = o.method == "lloyd" ? VsaMethod::lloyd : VsaMethod::greedy;
  vo.seeding.method = o.seeding == "random" ? SeedingMethod::random : SeedingMethod::curvature;
  vo.seeding.seed = o.seed;
  vo.lloyd.iterations = o.iterations;
  vo.teleports = o.teleports;
  vo.meshing.split_threshold = o.split_threshold;
  vo.meshing.polygons = o.polygons;
  Stopwatch laps;
  SimplifyOutcome out{simplify_vsa(mesh, vo, name), {}};
  laps.lap();
  const SimplifiedCheck check = validate_simplified(out.result.output.mesh, bounding_box(mesh));
  if (!check.ok())
    throw std::runtime_error(fmt::format("{}: the simplified mesh is invalid ({}); nothing written",
                                         name, check.first_problem));
  const double t_validate = laps.lap();
  // The distance report samples and ray-casts the output (most of a run's time on meshes of
  // tens of thousands of faces): only when asked.
  nlohmann::json distance = nullptr;
  if (o.distance)
    distance =
        reports::distance_json(surface_distance(out.result.output.mesh, mesh, *o.distance, o.seed));
  const double t_distance = laps.lap();
  out.report = reports::simplify_json(mesh, vo, out.result);
  out.report["distance"] = distance;
  out.report["valid"] = true;
  nlohmann::json timings = reports::simplify_timings_json(out.result.stats);
  timings["validate"] = t_validate;
  timings["distance"] = o.distance ? nlohmann::json(t_distance) : nlohmann::json(nullptr);
  out.report["timings_ms"] = timings;
  return out;
}

void check_uniform(int level, Names names) {
  if (level < 0 || level > 8)
    throw InputError(fmt::format("{} {}: level must be 0-8", option_name(names, "uniform"), level));
}

namespace {

// The refined mesh with its per-level counts and phase timings.
struct Refined {
  Mesh mesh;
  nlohmann::json levels = nlohmann::json::array(), timings = nlohmann::json::object();
};

Refined refine_uniform_job(const Mesh& cage, int level, bool limit, std::string_view name,
                           Names names) {
  // Every level multiplies corners by 4 (after the first, which makes one quad per corner).
  // The lean path needs ~70 bytes per output quad; with limit every level, its stencils and the
  // limit masks are kept (~500 bytes per quad).
  const double faces = double(cage.corner_count()) * std::pow(4.0, level - 1);
  const double cap = limit ? 4e7 : 3.5e8;
  if (level > 0 && faces > cap)
    throw InputError(fmt::format("{}: level {}{} would make {:.3g} faces; limn stops at {:.3g}",
                                 name, level, limit ? " with " + option_name(names, "limit") : "",
                                 faces, cap));
  const SubdivOptions options = subdiv_options(cage);
  Refined result;
  Mesh& out = result.mesh;
  nlohmann::json& levels = result.levels;
  nlohmann::json& timings = result.timings;
  Stopwatch laps;
  if (!limit) {
    // Lean: only the last level is kept, stencils are applied chunk by chunk and dropped.
    SubdivideStats st;
    out = limn::subdivide_uniform(cage, level, options, &st);
    for (size_t k = 0; k < st.levels.size(); ++k)
      levels.push_back({{"level", k},
                        {"vertices", st.levels[k].vertices},
                        {"faces", st.levels[k].faces},
                        {"edges", st.levels[k].edges},
                        {"stencil_entries", st.levels[k].stencil_entries}});
    timings["topology"] = st.topology_ms;
    timings["stencils_and_apply"] = st.stencils_ms;
    timings["output"] = st.output_ms;
    return result;
  }
  // UVs refined as face-varying data and pushed to their own limit.
  const FaceVaryingInput uv_channel{cage.uv_indices, cage.uvs.size() / 2, true};
  const bool uv = !cage.uv_indices.empty();
  const UniformRefinement r = refine_uniform(cage, level, options, {&uv_channel, uv ? 1u : 0u});
  timings["topology_refine_stencils"] = laps.lap();
  std::vector<float> pos = r.positions(cage, level);
  timings["apply"] = laps.lap();
  const RefinedLevel& L = r.levels.back();
  const LimitStencils ls = limit_stencils(r, level);
  std::vector<float> p(pos.size()), t1(pos.size()), t2(pos.size());
  apply_stencils(ls.position, pos.data(), p.data(), 3);
  apply_stencils(ls.tangent1, pos.data(), t1.data(), 3);
  apply_stencils(ls.tangent2, pos.data(), t2.data(), 3);
  out.normals = normals_from_tangents(t1, t2);
  out.positions = std::move(p);
  if (cage.colors.size() == 4 * cage.vertex_count()) {
    std::vector<float> c = cage.colors, next;
    for (const StencilTable& t : r.stencils) {
      next.assign(4 * t.size(), 0.0f);
      apply_stencils(t, c.data(), next.data(), 4);
      c.swap(next);
    }
    out.colors.resize(c.size());
    apply_stencils(ls.position, c.data(), out.colors.data(), 4);
  }
  std::vector<uint32_t> corner_uv;
  if (uv) {
    const FaceVaryingLevels& fl = r.face_varying[0];
    const std::vector<float> last = fl.values(cage.uvs.data(), 2, level);
    out.uvs.resize(last.size());
    apply_stencils(fl.limit, last.data(), out.uvs.data(), 2);
    corner_uv = fl.corner_values.back();
  }
  timings["limit"] = laps.lap();
  // Holes are refined for their neighbours but make no surface.
  for (size_t f = 0; f < L.face_count(); ++f) {
    if (L.face_hole[f]) continue;
    const uint32_t b = L.face_offsets[f], e = L.face_offsets[f + 1];
    out.add_face(std::span<const uint32_t>(L.face_vertices.data() + b, e - b));
    if (uv) out.uv_indices.insert(out.uv_indices.end(), &corner_uv[b], &corner_uv[b] + (e - b));
  }
  out.normal_indices = out.face_vertices;
  // Remaining sharpness travels as OpenSubdiv tags, so the result can be refined further.
  for (size_t e = 0; e < L.edge_count(); ++e)
    if (L.edge_sharpness[e] > 0.0f) {
      out.crease_edges.insert(out.crease_edges.end(),
                              {L.edge_vertices[2 * e], L.edge_vertices[2 * e + 1]});
      out.crease_sharpness.push_back(L.edge_sharpness[e]);
    }
  for (size_t v = 0; v < L.vertex_count(); ++v)
    if (L.vertex_sharpness[v] > 0.0f) {
      out.corner_vertices.push_back(static_cast<uint32_t>(v));
      out.corner_sharpness.push_back(L.vertex_sharpness[v]);
    }
  out.tags = cage.tags;
  for (size_t k = 0; k < r.levels.size(); ++k) {
    const RefinedLevel& l = r.levels[k];
    levels.push_back({{"level", k},
                      {"vertices", l.vertex_count()},
                      {"faces", l.face_count()},
                      {"edges", l.edge_count()},
                      {"stencil_entries", k == 0 ? 0 : r.stencils[k - 1].indices.size()}});
  }
  return result;
}

}  // namespace

UniformOutcome subdivide_uniform(const Mesh& cage, int level, bool limit, std::string_view name,
                                 Names names) {
  check_uniform(level, names);
  Refined r = refine_uniform_job(cage, level, limit, name, names);
  nlohmann::json report = {{"level", level},
                           {"limit", limit},
                           {"levels", std::move(r.levels)},
                           {"output_vertices", r.mesh.vertex_count()},
                           {"output_faces", r.mesh.face_count()},
                           {"timings_ms", std::move(r.timings)}};
  return {std::move(r.mesh), std::move(report)};
}

void check_paint_depth(int depth, Names names) {
  if (depth < 1 || depth > octree::kMaxDepth)
    throw InputError(
        fmt::format("{} {}: must be 1-{}", option_name(names, "depth"), depth, octree::kMaxDepth));
}

PaintOutcome paint(const Mesh& mesh, const StrokeScript& script, Rgba8 background,
                   std::optional<MaterialTexture> start, const MaterialDefaults& defaults) {
  rmh_background(defaults);  // checks them
  Stopwatch laps;
  const PaintSurface surface(mesh);
  const double t_surface = laps.lap();
  PaintOutcome out{start ? std::move(*start)
                         : MaterialTexture::from_color(OctreeTexture::create(surface, background)),
                   {}};
  MaterialTexture& tex = out.texture;
  const double t_create = laps.lap();
  PaintHistory history;
  const ScriptResult r = run_strokes(tex, surface, script, history, defaults);
  const double t_paint = laps.lap();
  // Compact: no free blocks, each subtree in one stretch of the pool (the undo history ends
  // here anyway).
  history.clear();
  tex.color.compact();
  if (tex.rmh) tex.rmh->compact();
  size_t dabs = 0, missed = 0, changed = 0, leaves = 0, bricks = 0, rays = 0, tasks = 0,
         threaded = 0;
  double stroke_ms = 0;
  for (const StrokeStats& s : r.strokes) {
    dabs += s.dabs, missed += s.dabs_missed, changed += s.samples_changed;
    leaves += s.leaves_created, bricks += s.bricks_created, rays += s.rays, stroke_ms += s.ms;
    tasks += s.tasks, threaded += s.tasks_threaded;
  }
  nlohmann::json picks = nlohmann::json::array();
  for (const PickResult& p : r.picks)
    picks.push_back({{"entry", p.command},
                     {"found", p.found},
                     {"rgba", {p.rgba[0], p.rgba[1], p.rgba[2], p.rgba[3]}},
                     {"roughness", p.channels[0]},
                     {"metallic", p.channels[1]},
                     {"height", p.channels[2]}});
  out.report = {
      {"entries", script.commands.size()},
      {"strokes", r.strokes.size()},
      {"dabs", dabs},
      {"dabs_missed", missed},
      {"samples_changed", changed},
      {"leaves_created", leaves},
      {"bricks_created", bricks},
      {"occlusion_rays", rays},
      {"ms_per_dab", dabs ? stroke_ms / double(dabs) : 0.0},
      // Task cells the dabs visited, and of them those on TBB's threads.
      {"threads",
       {{"max",
         std::min(size_t(tbb::this_task_arena::max_concurrency()),
                  tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism))},
        {"task_cells", tasks},
        {"task_cells_threaded", threaded}}},
      {"undos", r.undos},
      {"redos", r.redos},
      {"picks", picks},
      {"texture", reports::material_json(tex)},
      {"timings_ms", {{"surface_bvh", t_surface}, {"texture", t_create}, {"paint", t_paint}}}};
  return out;
}

void check(const UnwrapJob& o, Names names) {
  const auto name = [names](std::string_view n) { return option_name(names, n); };
  if (!(o.max_stretch >= 1 && o.max_stretch <= 100))
    throw InputError(fmt::format("{} {}: must be 1-100", name("max-stretch"), o.max_stretch));
  if (o.size < 16 || o.size > 16384)
    throw InputError(fmt::format("{} {}: must be 16-16384 texels", name("size"), o.size));
  if (o.tiles < 1 || o.tiles > 100)
    throw InputError(fmt::format("{} {}: must be 1-100 (UDIM 1001-1100)", name("tiles"), o.tiles));
  if (o.padding < 0 || 4 * o.padding >= o.size)
    throw InputError(fmt::format("{} {}: must be 0 or more and under a quarter of {}",
                                 name("padding"), o.padding, name("size")));
  if (o.texels_per_unit && !(*o.texels_per_unit > 0 && std::isfinite(*o.texels_per_unit)))
    throw InputError(fmt::format("{} {}: must be a positive number", name("texels-per-unit"),
                                 *o.texels_per_unit));
}

UnwrapOutcome unwrap(const Mesh& mesh, const UnwrapJob& job, std::string_view name) {
  UnwrapOptions uo;
  uo.max_stretch = job.max_stretch;
  uo.size = job.size;
  uo.texels_per_unit = job.texels_per_unit.value_or(0.0);
  uo.tiles = job.tiles;
  uo.padding = job.padding;
  UnwrapOutcome out{unwrap_mesh(mesh, uo, name), {}};
  const UnwrapStats& st = out.result.stats;
  Stopwatch laps;
  // The layout checked by rasterising it again, independently of the packer.
  const UvMetrics m = measure_uvs(out.result.mesh, job.size);
  const double t_check = laps.lap();
  if (m.flipped || m.overlapping_texels || m.straddling)
    throw std::runtime_error(fmt::format(
        "{}: the atlas failed its check ({} flipped triangles, {} overlapping texels, {} "
        "triangles across tiles); nothing written",
        name, m.flipped, m.overlapping_texels, m.straddling));
  nlohmann::json udim = nlohmann::json::array();
  for (size_t t = 0; t < st.tiles; ++t) udim.push_back(1001 + t);
  out.report = {
      {"charts", st.charts},
      {"splits", st.splits},
      {"tiles", st.tiles},
      {"udim", udim},
      {"size", st.size},
      {"padding", job.padding},
      {"texels_per_unit", st.texels_per_unit},
      {"max_stretch", job.max_stretch},
      {"utilization", st.utilization},
      {"coverage", st.coverage},
      {"stretch_l2", st.stretch_l2},
      {"stretch_linf", st.stretch_linf},
      {"check",
       {{"triangles", m.triangles},
        {"flipped", m.flipped},
        {"overlapping_texels", m.overlapping_texels},
        {"coverage", m.coverage},
        {"stretch_l2", m.stretch_l2},
        {"stretch_linf", m.stretch_linf}}},
      {"replaced_uvs", !mesh.uvs.empty()},
      {"timings_ms", {{"charts", st.chart_ms}, {"pack", st.pack_ms}, {"check", t_check}}}};
  return out;
}

}  // namespace limn::jobs
