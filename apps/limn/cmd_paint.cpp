// limn paint: runs a stroke script (docs/paint-strokes.md) on a mesh into an adaptive octree
// texture (.lot), or prints a texture's counts and sizes (--stats).
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "common.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/strokes.hpp"

namespace limn::cli {

namespace {

struct PaintOpts {
  std::string mesh, strokes, out, texture, stats, background = "0,0,0,0", format;
  int depth = 10;
  bool json = false, weld = false;
  RepairFlags repair;
};

Rgba8 parse_color(const std::string& s, const char* option) {
  std::vector<float> v = parse_numbers(s, option);
  if (v.size() == 3) v.push_back(1.0f);
  if (v.size() != 4)
    throw InputError(fmt::format("{} {}: expected r,g,b[,a] with numbers in [0, 1]", option, s));
  for (float x : v)
    if (!(x >= 0 && x <= 1))
      throw InputError(fmt::format("{} {}: components must be numbers in [0, 1]", option, s));
  return rgba8_from_float(v.data());
}

void check_folder(const std::string& path) {
  const std::filesystem::path dir = std::filesystem::absolute(path).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(fmt::format("{}: the output folder {} does not exist", path, dir.string()));
}

nlohmann::json texture_json(const OctreeTexture& t) {
  const OctreeTextureStats s = t.stats();
  return {
      {"nodes", s.nodes},
      {"general_nodes", s.general_nodes},
      {"bricks", s.bricks},
      {"leaves", s.leaf_cells},
      {"double_sided_leaves", s.double_cells},
      {"samples", s.samples},
      {"painted_samples", s.painted_samples},
      {"max_depth", s.max_depth},
      {"leaves_at_max_depth", s.leaves_at_depth},
      {"bytes", s.bytes},
      {"pool_words", s.pool_words},
      {"free_words", s.free_words},
      {"free_blocks", t.free_blocks().size()},
      {"bytes_per_painted_texel", s.bytes_per_painted_texel},
      {"cube", {{"origin", {t.origin()[0], t.origin()[1], t.origin()[2]}}, {"size", t.size()}}}};
}

void run_stats(const PaintOpts& o) {
  Stopwatch sw;
  const OctreeTexture t = load_lot(o.stats);
  const double t_read = sw.lap();
  nlohmann::json j = texture_json(t);
  j["file"] = o.stats;
  j["timings_ms"] = {{"read", t_read}, {"total", sw.ms()}};
  if (o.json) {
    fmt::print("{}\n", j.dump(2));
    return;
  }
  fmt::print(
      "{}: {} nodes ({} general, {} bricks), {} leaves ({} two-sided), max depth {}, {} bytes, "
      "{:.3f} bytes per painted texel ({} painted samples)\n",
      o.stats, j["nodes"].get<size_t>(), j["general_nodes"].get<size_t>(),
      j["bricks"].get<size_t>(), j["leaves"].get<size_t>(), j["double_sided_leaves"].get<size_t>(),
      j["max_depth"].get<int>(), j["bytes"].get<size_t>(),
      j["bytes_per_painted_texel"].get<double>(), j["painted_samples"].get<size_t>());
}

void run_paint(const PaintOpts& o) {
  const std::filesystem::path out(o.out);
  if (out.extension() != ".lot")
    throw InputError(fmt::format("{}: the texture file name must end in .lot", o.out));
  check_folder(o.out);
  const Rgba8 background = parse_color(o.background, "--background");
  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_read = sw.lap();
  const StrokeScript script = read_strokes(o.strokes, o.depth);
  const double t_parse = sw.lap();
  const PaintSurface surface(mesh);
  const double t_surface = sw.lap();
  OctreeTexture tex =
      o.texture.empty() ? OctreeTexture::create(surface, background) : load_lot(o.texture);
  const double t_create = sw.lap();
  PaintHistory history;
  const ScriptResult r = run_strokes(tex, surface, script, history);
  const double t_paint = sw.lap();
  // Saved compact: no free blocks, each subtree in one stretch of the pool (the undo history
  // ends with this run anyway).
  history.clear();
  tex.compact();
  save_lot(tex, o.out);
  const double t_save = sw.lap();

  size_t dabs = 0, missed = 0, changed = 0, leaves = 0, bricks = 0, rays = 0, tasks = 0,
         threaded = 0;
  double stroke_ms = 0;
  for (const StrokeStats& s : r.strokes) {
    dabs += s.dabs, missed += s.dabs_missed, changed += s.samples_changed;
    leaves += s.leaves_created, bricks += s.bricks_created, rays += s.rays, stroke_ms += s.ms;
    tasks += s.tasks, threaded += s.tasks_threaded;
  }
  if (o.json) {
    nlohmann::json picks = nlohmann::json::array();
    for (const PickResult& p : r.picks)
      picks.push_back({{"entry", p.command},
                       {"found", p.found},
                       {"rgba", {p.rgba[0], p.rgba[1], p.rgba[2], p.rgba[3]}}});
    nlohmann::json j = {{"input", o.mesh},
                        {"repair", repaired},
                        {"strokes_file", o.strokes},
                        {"output", o.out},
                        {"depth", o.depth},
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
                         {{"max", std::min(size_t(tbb::this_task_arena::max_concurrency()),
                                           tbb::global_control::active_value(
                                               tbb::global_control::max_allowed_parallelism))},
                          {"task_cells", tasks},
                          {"task_cells_threaded", threaded}}},
                        {"undos", r.undos},
                        {"redos", r.redos},
                        {"picks", picks},
                        {"texture", texture_json(tex)},
                        {"timings_ms",
                         {{"read_mesh", t_read},
                          {"read_strokes", t_parse},
                          {"surface_bvh", t_surface},
                          {"texture", t_create},
                          {"paint", t_paint},
                          {"save", t_save},
                          {"total", sw.ms()}}}};
    fmt::print("{}\n", j.dump(2));
  } else {
    const OctreeTextureStats st = tex.stats();
    fmt::print(
        "{} -> {}: {} strokes, {} dabs ({} missed the surface), {} samples changed; texture max "
        "depth {}, {} leaves, {} bytes ({:.2f} per painted texel); {:.0f} ms in all\n",
        o.mesh, o.out, r.strokes.size(), dabs, missed, changed, st.max_depth, st.leaf_cells,
        st.bytes, st.bytes_per_painted_texel, sw.ms());
  }
}

}  // namespace

void add_paint(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "paint", "Paint strokes onto a mesh into an adaptive octree texture (.lot), no UVs needed");
  auto o = std::make_shared<PaintOpts>();
  cmd->add_option("MESH", o->mesh, "The mesh to paint (OBJ, PLY, OFF, STL, glTF/GLB)");
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("--strokes", o->strokes, "Stroke script (JSON; see docs/paint-strokes.md)");
  cmd->add_option("-o,--output", o->out, "Texture to write (.lot)");
  cmd->add_option("--depth", o->depth,
                  "Leaf level for strokes that give none (default 10: 1024^3 over the mesh's "
                  "bounding cube; 1-16)");
  cmd->add_option("--texture", o->texture, "Continue painting this texture instead of a new one");
  cmd->add_option("--background", o->background,
                  "Colour of unpainted surface in a new texture, r,g,b[,a] (default 0,0,0,0)");
  cmd->add_option("--format", o->format, "Mesh format, overriding the extension");
  cmd->add_option("--stats", o->stats, "Print the counts and sizes of this texture instead");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->callback([o] {
    if (!o->stats.empty()) {
      if (!o->mesh.empty() || !o->strokes.empty() || !o->out.empty())
        throw InputError("--stats takes only a texture (and --json)");
      run_stats(*o);
      return;
    }
    if (o->mesh.empty() || o->strokes.empty() || o->out.empty())
      throw InputError("paint needs MESH, --strokes FILE and -o TEXTURE.lot (or --stats TEXTURE)");
    if (o->depth < 1 || o->depth > octree::kMaxDepth)
      throw InputError(fmt::format("--depth {}: must be 1-{}", o->depth, octree::kMaxDepth));
    run_paint(*o);
  });
}

}  // namespace limn::cli
