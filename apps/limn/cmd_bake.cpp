// limn bake: a painted material into per-vertex colours (PLY, OBJ, OFF, or GLB without UVs), or
// into a UV layout (the mesh's own, or a new atlas with --atlas): PNG images (one per UDIM tile
// and channel) with a dilated gutter, or a GLB whose PBR material carries the baked textures.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <utility>

#include "../common/jobs.hpp"
#include "common.hpp"
#include "limn/mesh/file.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/file.hpp"

namespace limn::cli {

namespace {

struct BakeOpts {
  std::string texture, mesh, out, format, resolution, mesh_out;
  std::string mr_out, height_out, normal_out;  // channel images beside a PNG output
  bool normal_map = false;                     // a GLB's normalTexture
  int size = 1024, gutter = 8;
  bool nearest = false, json = false, weld = false, atlas = false;
  jobs::UnwrapJob unwrap;
  RepairFlags repair;
};

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool names_tile(const std::string& out) {
  return out.find("<UDIM>") != std::string::npos || out.find("<udim>") != std::string::npos;
}

// The file of UDIM tile `tile` (UDIM number 1001 + tile): OUT's "<UDIM>" replaced by the number,
// or the number put before the extension ("paint.png" -> "paint.1001.png").
std::filesystem::path tile_path(const std::string& out, int tile) {
  const std::string number = std::to_string(1001 + tile);
  for (const char* token : {"<UDIM>", "<udim>"})
    if (const size_t at = out.find(token); at != std::string::npos)
      return out.substr(0, at) + number + out.substr(at + 6);
  std::filesystem::path p(out);
  return p.replace_extension("." + number + p.extension().string());
}

void run(const BakeOpts& o, CLI::App* cmd) {
  const std::filesystem::path out(o.out);
  const std::string ext = lower_extension(out);
  const bool png = ext == ".png", glb = ext == ".glb";
  if (!png && format_from_path(out) == MeshFormat::automatic)
    throw InputError(fmt::format(
        "{}: cannot tell the output from the extension (.png, .glb, .ply, .obj or .off)", o.out));
  for (const char* flag : {"--tiles", "--texels-per-unit", "--padding", "--max-stretch"})
    if (cmd->count(flag) && !o.atlas) throw InputError(fmt::format("{} needs --atlas", flag));
  if (o.atlas) {
    if (!png && !glb)
      throw InputError("--atlas bakes into a texture: the output must be .png or .glb");
    if (!o.resolution.empty())
      throw InputError("--atlas makes square tiles: use --size, not --resolution");
    if (png && o.mesh_out.empty())
      throw InputError(
          "--atlas with a PNG output needs --mesh-out FILE for the mesh with its new UVs");
  }
  if (!o.mesh_out.empty() && !(png || glb))
    throw InputError("--mesh-out goes with a texture output (.png or .glb)");
  const std::pair<const char*, const std::string*> channel_outs[] = {
      {"--metallic-roughness", &o.mr_out},
      {"--height", &o.height_out},
      {"--normal", &o.normal_out}};
  for (auto [flag, path] : channel_outs) {
    if (path->empty()) continue;
    if (!png) throw InputError(fmt::format("{} goes with a .png output", flag));
    if (lower_extension(*path) != ".png")
      throw InputError(fmt::format("{} {}: must be a .png file", flag, *path));
    check_writable_folder(*path, flag);
  }
  if (o.normal_map && !glb)
    throw InputError("--normal-map goes with a .glb output (with a .png output: --normal FILE)");
  const MeshFormat mesh_out_format = format_from_path(o.mesh_out);
  if (!o.mesh_out.empty() && mesh_out_format == MeshFormat::automatic)
    throw InputError(fmt::format("{}: cannot tell the mesh format from the extension", o.mesh_out));
  check_writable_folder(o.out, "output");
  if (!o.mesh_out.empty()) check_writable_folder(o.mesh_out, "--mesh-out");
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
  if ((png || glb) && (w < 1 || h < 1 || w > 16384 || h > 16384))
    throw InputError(fmt::format("image size {}x{}: each side must be 1-16384", w, h));
  if (o.gutter < 0 || o.gutter > 1024) throw InputError("--gutter: must be 0-1024 pixels");
  jobs::UnwrapJob unwrap = o.unwrap;
  unwrap.size = o.size;
  if (o.atlas) jobs::check(unwrap, jobs::Names::cli);

  Stopwatch sw;
  const MaterialTexture material = load_lot(o.texture);
  const OctreeTexture& tex = material.color;
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
  nlohmann::json timings = {{"read_texture", t_tex}, {"read_mesh", t_mesh}};

  const bool textured = png || (glb && (o.atlas || !mesh.uvs.empty()));
  if (textured && !o.atlas && mesh.uvs.empty())
    throw InputError(fmt::format(
        "{}: the mesh has no texture coordinates: add --atlas to make them, or bake to .ply for "
        "vertex colours",
        o.mesh));
  check_texture_fits(tex, mesh, o.texture, o.mesh);
  // The material channels the outputs asked for cannot hold (height: a GLB holds it as its
  // normal map).
  std::vector<std::string> dropped_channels;
  if (material.rmh) {
    const bool mr = glb ? textured : !o.mr_out.empty();
    const bool height = png ? !o.height_out.empty() : glb && textured && o.normal_map;
    if (!mr) dropped_channels.insert(dropped_channels.end(), {"roughness", "metallic"});
    if (!height) dropped_channels.push_back("height");
  }
  nlohmann::json dropped = dropped_channels;
  if (!textured) {
    mesh.colors = bake_vertex_colors(tex, mesh, bo);
    timings["bake"] = sw.lap();
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
    j["dropped"] = dropped;
  } else {
    if (o.atlas) {
      jobs::UnwrapOutcome u = jobs::unwrap(mesh, unwrap, o.mesh);
      mesh = std::move(u.result.mesh);
      j["atlas"] = std::move(u.report);
      timings["unwrap"] = sw.lap();
    }
    size_t outside = 0;
    const std::vector<int> tiles = uv_tiles(mesh, &outside);
    if (tiles.empty())
      throw InputError(
          fmt::format("{}: no UV triangle lies in a UDIM tile (u, v in [0, 10))", o.mesh));
    if (outside)
      fmt::print(stderr, "limn: warning: {}: {} triangles have UVs outside [0, 10): not baked\n",
                 o.mesh, outside);
    j["triangles_outside_tiles"] = outside;
    if (glb && tiles != std::vector<int>{0})
      throw InputError(fmt::format(
          "{}: the UVs use UDIM tiles beyond 1001, which glTF cannot hold: bake to .png", o.mesh));
    // Everything is baked and encoded first, then written all at once (or not at all).
    std::vector<std::pair<std::filesystem::path, std::string>> files;
    nlohmann::json images = nlohmann::json::array();
    const bool normals = glb ? o.normal_map : !o.normal_out.empty();
    GlbTextures glb_material;
    const MaterialDefaults defaults = material.defaults();
    glb_material.roughness = defaults.roughness, glb_material.metallic = defaults.metallic;
    for (int tile : tiles) {
      bo.tile = tile;
      MaterialImages img = bake_material(material, mesh, w, h, o.gutter, bo, normals);
      size_t opaque = 0;
      for (size_t i = 3; i < img.base_color.rgba.size(); i += 4)
        opaque += img.base_color.rgba[i] != 0;
      // One tile keeps each output's name as given, unless it names the tile with <UDIM>.
      auto path_of = [&](const std::string& name) {
        const bool as_given = tiles == std::vector<int>{0} && !names_tile(name);
        return as_given ? std::filesystem::path(name) : tile_path(name, tile);
      };
      nlohmann::json entry = {{"udim", 1001 + tile}, {"opaque_texels", opaque}};
      if (glb) {
        glb_material.base_color_png = encode_png(img.base_color);
        if (material.rmh) {
          glb_material.metallic_roughness_png = encode_png(img.metallic_roughness);
          // The texture's values are multiplied by the factors: 1 keeps them.
          glb_material.roughness = glb_material.metallic = 1;
        }
        if (normals) glb_material.normal_png = encode_png(img.normal);
        entry["file"] = nullptr;
      } else {
        const std::filesystem::path path = path_of(o.out);
        entry["file"] = path.string();
        files.emplace_back(path, encode_png(img.base_color));
        if (!o.mr_out.empty()) {
          // Without an RMH texture the defaults fill the image.
          if (img.metallic_roughness.rgba.empty()) {
            img.metallic_roughness = img.base_color;
            for (size_t i = 0; i < img.metallic_roughness.rgba.size(); i += 4) {
              uint8_t* px = &img.metallic_roughness.rgba[i];
              px[0] = 255, px[3] = 255;
              px[1] = uint8_t(std::lround(defaults.roughness * 255));
              px[2] = uint8_t(std::lround(defaults.metallic * 255));
            }
          }
          entry["metallic_roughness"] = path_of(o.mr_out).string();
          files.emplace_back(path_of(o.mr_out), encode_png(img.metallic_roughness));
        }
        if (!o.height_out.empty()) {
          if (img.height.values.empty()) {
            img.height.width = w, img.height.height = h;
            img.height.values.assign(size_t(w) * size_t(h),
                                     uint16_t(std::lround(defaults.height * 65535)));
          }
          entry["height"] = path_of(o.height_out).string();
          files.emplace_back(path_of(o.height_out), encode_png16(img.height));
        }
        if (normals) {
          entry["normal"] = path_of(o.normal_out).string();
          files.emplace_back(path_of(o.normal_out), encode_png(img.normal));
        }
      }
      images.push_back(entry);
    }
    timings["bake"] = sw.lap();
    if (glb) {
      files.emplace_back(out, std::string());
      write_glb(mesh, glb_material, files.back().second);
    }
    std::vector<std::string> mesh_dropped;
    if (!o.mesh_out.empty()) {
      mesh_dropped = dropped_attributes(mesh, mesh_out_format);
      files.emplace_back(o.mesh_out, write_mesh_memory(mesh, mesh_out_format));
    }
    write_files_atomic(files);
    if (!mesh_dropped.empty())
      fmt::print(stderr, "limn: warning: {}: dropped {}\n", o.mesh_out,
                 fmt::join(mesh_dropped, ", "));
    for (const std::string& name : mesh_dropped) dropped.push_back(name);
    j["mode"] = glb ? "glb" : "uv";
    size_t opaque = 0;
    for (const auto& t : images) opaque += t["opaque_texels"].get<size_t>();
    j["image"] = {{"width", w}, {"height", h}, {"gutter", o.gutter}, {"opaque_texels", opaque}};
    j["tiles"] = images;
    j["mesh_out"] = o.mesh_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.mesh_out);
    j["dropped"] = dropped;
  }
  if (!dropped_channels.empty())
    fmt::print(stderr,
               "limn: warning: {}: dropped {}: {} cannot hold {} (PNG: --metallic-roughness, "
               "--height; GLB: --normal-map)\n",
               o.texture, fmt::join(dropped_channels, ", "), o.out,
               dropped_channels.size() == 1 ? "it" : "them");
  timings["write"] = sw.lap();
  timings["total"] = sw.ms();
  j["timings_ms"] = timings;
  if (o.json) {
    fmt::print("{}\n", j.dump(2));
  } else if (textured) {
    fmt::print("{} on {} -> {}: {} tile{} of {}x{} texels, {} opaque ({} px gutter), {:.0f} ms\n",
               o.texture, o.mesh, o.out, j["tiles"].size(), j["tiles"].size() == 1 ? "" : "s", w, h,
               j["image"]["opaque_texels"].get<size_t>(), o.gutter, sw.ms());
  } else {
    fmt::print("{} on {} -> {}: {} vertices, {} painted, {:.0f} ms\n", o.texture, o.mesh, o.out,
               mesh.vertex_count(), j["painted_vertices"].get<size_t>(), sw.ms());
  }
}

}  // namespace

void add_bake(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bake",
      "Bake an octree texture into per-vertex colours, or into UV textures: PNGs (UDIM tiles "
      "name.1001.png, ...; the material channels with --metallic-roughness, --height, --normal) "
      "or a GLB whose PBR material carries them; --atlas makes the UVs");
  auto o = std::make_shared<BakeOpts>();
  cmd->add_option("TEXTURE", o->texture, "Octree texture (.lot)")->required();
  cmd->add_option("MESH", o->mesh, "Mesh to bake onto (OBJ, PLY, OFF, STL, glTF/GLB)")->required();
  add_weld_flag(*cmd, o->weld);
  add_repair_flags(*cmd, o->repair);
  cmd->add_option("-o,--output", o->out,
                  "Output: .png (UV texture; several UDIM tiles: <UDIM> in the name is replaced "
                  "by 1001, 1002, ..., else the number goes before .png), .glb (a material with "
                  "the texture when the mesh has UVs or --atlas, else vertex colours), "
                  ".ply/.obj/.off (vertex colours)")
      ->required();
  cmd->add_flag("--atlas", o->atlas,
                "Unwrap the mesh first (as limn unwrap) and bake into the new atlas");
  cmd->add_option("--mesh-out", o->mesh_out,
                  "Also write the mesh with the UVs baked into (needed with --atlas and .png)");
  cmd->add_option("--size", o->size, "Square image (or atlas tile) side in texels (default 1024)");
  cmd->add_option("--resolution", o->resolution, "WxH instead of --size (not with --atlas)");
  cmd->add_option("--gutter", o->gutter, "Texels of dilation around the charts (default 8)");
  cmd->add_option("--tiles", o->unwrap.tiles, "--atlas: UDIM tiles to use at most (1)");
  cmd->add_option("--texels-per-unit", o->unwrap.texels_per_unit,
                  "--atlas: texel density (default: the densest that fits)");
  cmd->add_option("--padding", o->unwrap.padding, "--atlas: free texels around every chart (2)");
  cmd->add_option("--max-stretch", o->unwrap.max_stretch,
                  "--atlas: largest Sander L2 stretch a chart keeps (1.003)");
  cmd->add_option("--metallic-roughness", o->mr_out,
                  "With a .png output: also bake roughness (green) and metalness (blue), as glTF "
                  "packs them, into this PNG (UDIM names as for -o)");
  cmd->add_option("--height", o->height_out,
                  "With a .png output: also bake height into this 16-bit greyscale PNG");
  cmd->add_option("--normal", o->normal_out,
                  "With a .png output: also bake a tangent-space normal map of the height into "
                  "this PNG (OpenGL convention, +Y along +v)");
  cmd->add_flag("--normal-map", o->normal_map,
                "With a .glb output: add a normal map of the height as the material's "
                "normalTexture");
  cmd->add_flag("--nearest", o->nearest, "Nearest lookups instead of trilinear");
  cmd->add_option("--format", o->format, "Mesh format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->callback([o, cmd] { run(*o, cmd); });
}

}  // namespace limn::cli
