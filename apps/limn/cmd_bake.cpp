// limn bake: an octree texture into per-vertex colours (PLY, GLB, OBJ, OFF) or into the mesh's
// UV layout as a PNG with a dilated gutter.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <filesystem>

#include "common.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/file.hpp"

namespace limn::cli {

namespace {

struct BakeOpts {
  std::string texture, mesh, out, format, resolution;
  int size = 1024, gutter = 8;
  bool nearest = false, json = false, weld = false;
  RepairFlags repair;
};

void run(const BakeOpts& o, CLI::App* cmd) {
  const std::filesystem::path out(o.out);
  std::string ext = out.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  const bool png = ext == ".png";
  if (!png && format_from_path(out) == MeshFormat::automatic)
    throw InputError(fmt::format(
        "{}: cannot tell the output from the extension (.ply, .glb, .obj, .off or .png)", o.out));
  check_writable_folder(o.out, "output");
  int w = o.size, h = o.size;
  if (!o.resolution.empty()) {
    if (cmd->count("--size")) throw InputError("--size and --resolution exclude each other");
    const size_t x = o.resolution.find('x');
    try {
      if (x == std::string::npos) throw std::invalid_argument(o.resolution);
      size_t a = 0, b = 0;
      w = std::stoi(o.resolution.substr(0, x), &a);
      h = std::stoi(o.resolution.substr(x + 1), &b);
      if (a != x || b != o.resolution.size() - x - 1) throw std::invalid_argument(o.resolution);
    } catch (const std::exception&) {
      throw InputError(
          fmt::format("--resolution {}: expected WxH, such as 2048x1024", o.resolution));
    }
  }
  if (png && (w < 1 || h < 1 || w > 16384 || h > 16384))
    throw InputError(fmt::format("image size {}x{}: each side must be 1-16384", w, h));
  if (o.gutter < 0 || o.gutter > 1024) throw InputError("--gutter: must be 0-1024 pixels");

  Stopwatch sw;
  const OctreeTexture tex = load_lot(o.texture);
  const double t_tex = sw.lap();
  nlohmann::json repaired;
  Mesh mesh = read_input(o.mesh, o.format, o.weld, o.repair, repaired);
  const double t_mesh = sw.lap();
  BakeOptions bo;
  bo.filtered = !o.nearest;
  nlohmann::json j = {{"texture", o.texture},
                      {"mesh", o.mesh},
                      {"repair", repaired},
                      {"output", o.out},
                      {"filter", o.nearest ? "nearest" : "trilinear"}};
  if (png) {
    if (mesh.uvs.empty())
      throw InputError(fmt::format(
          "{}: the mesh has no texture coordinates; bake to .ply or .glb for vertex colours",
          o.mesh));
    const Image img = bake_uv_texture(tex, mesh, w, h, o.gutter, bo);
    const double t_bake = sw.lap();
    write_file_atomic(out, encode_png(img));
    size_t covered = 0;
    for (size_t i = 3; i < img.rgba.size(); i += 4) covered += img.rgba[i] != 0;
    j["mode"] = "uv";
    j["image"] = {{"width", w}, {"height", h}, {"gutter", o.gutter}, {"opaque_texels", covered}};
    j["timings_ms"] = {{"read_texture", t_tex},
                       {"read_mesh", t_mesh},
                       {"bake", t_bake},
                       {"write", sw.lap()},
                       {"total", sw.ms()}};
  } else {
    mesh.colors = bake_vertex_colors(tex, mesh, bo);
    const double t_bake = sw.lap();
    write_mesh(mesh, out);
    float bg[4];
    rgba8_to_float(tex.background(), bg);
    size_t painted = 0;
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      bool differs = false;
      for (int k = 0; k < 4; ++k)
        differs |= std::fabs(mesh.colors[4 * v + size_t(k)] - bg[k]) > 0.5f / 255.0f;
      painted += differs;
    }
    j["mode"] = "vertex";
    j["vertices"] = mesh.vertex_count();
    j["painted_vertices"] = painted;
    j["timings_ms"] = {{"read_texture", t_tex},
                       {"read_mesh", t_mesh},
                       {"bake", t_bake},
                       {"write", sw.lap()},
                       {"total", sw.ms()}};
  }
  if (o.json) {
    fmt::print("{}\n", j.dump(2));
  } else if (png) {
    fmt::print("{} on {} -> {}: {}x{} texels, {} opaque ({} px gutter), {:.0f} ms\n", o.texture,
               o.mesh, o.out, w, h, j["image"]["opaque_texels"].get<size_t>(), o.gutter, sw.ms());
  } else {
    fmt::print("{} on {} -> {}: {} vertices, {} painted, {:.0f} ms\n", o.texture, o.mesh, o.out,
               mesh.vertex_count(), j["painted_vertices"].get<size_t>(), sw.ms());
  }
}

}  // namespace

void add_bake(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bake", "Bake an octree texture into per-vertex colours or a UV texture PNG");
  auto o = std::make_shared<BakeOpts>();
  cmd->add_option("TEXTURE", o->texture, "Octree texture (.lot)")->required();
  cmd->add_option("MESH", o->mesh, "Mesh to bake onto (OBJ, PLY, OFF, STL, glTF/GLB)")->required();
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("-o,--output", o->out,
                  "Output: .ply/.glb/.obj/.off (vertex colours) or .png (needs the mesh's UVs)")
      ->required();
  cmd->add_option("--size", o->size, "PNG: square image side in texels (default 1024)");
  cmd->add_option("--resolution", o->resolution, "PNG: WxH instead of --size");
  cmd->add_option("--gutter", o->gutter, "PNG: texels of dilation around the charts (default 8)");
  cmd->add_flag("--nearest", o->nearest, "Nearest lookups instead of trilinear");
  cmd->add_option("--format", o->format, "Mesh format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->callback([o, cmd] { run(*o, cmd); });
}

}  // namespace limn::cli
