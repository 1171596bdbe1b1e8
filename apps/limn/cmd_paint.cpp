// limn paint: runs a stroke script (docs/paint-strokes.md) on a mesh into an adaptive octree
// texture (.lot), or prints a texture's counts and sizes (--stats).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "../common/jobs.hpp"
#include "common.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/strokes.hpp"

namespace limn::cli {

namespace {

struct PaintOpts {
  std::string mesh, strokes, out, texture, stats, background = "0,0,0,0", format;
  std::string channel_defaults;
  std::optional<double> height_scale;
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

void run_stats(const PaintOpts& o) {
  Stopwatch sw;
  const MaterialTexture t = load_lot(o.stats);
  const double t_read = sw.lap();
  nlohmann::json j = material_json(t);
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
  check_writable_folder(o.out, "output");
  const Rgba8 background = parse_color(o.background, "--background");
  Stopwatch sw;
  nlohmann::json repaired;
  const Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_read = sw.lap();
  const StrokeScript script = read_strokes(o.strokes, o.depth);
  const double t_parse = sw.lap();
  std::optional<MaterialTexture> start;
  if (!o.texture.empty()) start = load_lot(o.texture);
  MaterialDefaults defaults;
  if (!o.channel_defaults.empty()) {
    const std::vector<float> v = parse_numbers(o.channel_defaults, "--channel-defaults");
    if (v.size() != 3)
      throw InputError(
          fmt::format("--channel-defaults {}: expected roughness,metallic,height in [0, 1]",
                      o.channel_defaults));
    defaults = {v[0], v[1], v[2]};
    try {
      rmh_background(defaults);
    } catch (const InputError& e) {
      throw InputError(fmt::format("--channel-defaults {}: {}", o.channel_defaults, e.what()));
    }
    if (start && start->rmh)
      throw InputError(fmt::format(
          "--channel-defaults: {} already has material channels with their defaults", o.texture));
  }
  if (o.height_scale && !(*o.height_scale > 0 && std::isfinite(*o.height_scale)))
    throw InputError(fmt::format("--height-scale {}: must be a positive number", *o.height_scale));
  jobs::PaintOutcome painted = jobs::paint(mesh, script, background, std::move(start), defaults);
  if (o.height_scale) painted.texture.height_scale = float(*o.height_scale);
  const MaterialTexture& tex = painted.texture;
  sw.lap();
  save_lot(tex, o.out);
  const double t_save = sw.lap();
  const nlohmann::json& report = painted.report;
  if (o.json) {
    nlohmann::json j = report;
    j["input"] = o.mesh;
    j["repair"] = repaired;
    j["strokes_file"] = o.strokes;
    j["output"] = o.out;
    j["depth"] = o.depth;
    j["timings_ms"]["read_mesh"] = t_read;
    j["timings_ms"]["read_strokes"] = t_parse;
    j["timings_ms"]["save"] = t_save;
    j["timings_ms"]["total"] = sw.ms();
    fmt::print("{}\n", j.dump(2));
  } else {
    const OctreeTextureStats st = tex.color.stats();
    fmt::print(
        "{} -> {}: {} strokes, {} dabs ({} missed the surface), {} samples changed; texture max "
        "depth {}, {} leaves, {} bytes ({:.2f} per painted texel){}; {:.0f} ms in all\n",
        o.mesh, o.out, report["strokes"].get<size_t>(), report["dabs"].get<size_t>(),
        report["dabs_missed"].get<size_t>(), report["samples_changed"].get<size_t>(), st.max_depth,
        st.leaf_cells, st.bytes, st.bytes_per_painted_texel,
        tex.rmh ? fmt::format("; material channels {} bytes", tex.rmh->stats().bytes) : "",
        sw.ms());
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
  cmd->add_option("--channel-defaults", o->channel_defaults,
                  "Roughness, metallic and height where they are not painted, when the material "
                  "channels are first painted: r,m,h in [0, 1] (default 0.5,0,0.5)");
  cmd->add_option("--height-scale", o->height_scale,
                  "Model units that height 1 stands for (bump shading, normal maps; default 2% "
                  "of the texture's cube, or what --texture holds)");
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
    jobs::check_paint_depth(o->depth, jobs::Names::cli);
    run_paint(*o);
  });
}

}  // namespace limn::cli
