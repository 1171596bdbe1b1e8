// limn render: a PNG of a mesh, or of its adaptive limit surface drawn with tessellation shaders.
// The options are checked here; the drawing runs in the GL module (render_run.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "gl_commands.hpp"

namespace limn::cli {

void add_render(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "Render a mesh or its adaptive limit surface to PNG");
  struct Opts : RenderJob {
    std::string background = "1,1,1";
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("MESH", o->mesh,
                  "Mesh or control cage (OBJ with OpenSubdiv tags, PLY, OFF, STL, glTF/GLB)")
      ->required();
  cmd->add_option("-o,--output", o->out, "Output image (.png)")->required();
  add_weld_flag(*cmd, o->weld);
  cmd->add_flag("--adaptive", o->adaptive,
                "Draw the feature-adaptive limit surface (patches on the GPU), not the mesh");
  add_adaptive_options(*cmd, o->a, true);
  cmd->add_flag("--wireframe", o->wireframe, "Outline the patches (or the mesh's polygons)");
  cmd->add_option("--texture", o->texture,
                  "Colour from an octree texture (.lot, limn paint) painted on this surface, and "
                  "its material channels shaded (GGX roughness and metalness, height as bump)");
  cmd->add_flag("--nearest", o->nearest, "--texture: nearest texel, not filtered");
  cmd->add_flag("--flat", o->flat, "Mesh: one normal per polygon (faceted), not per vertex");
  cmd->add_option("--uv-checker", o->uv_checker,
                  "Mesh with UVs: show them as a checker of N squares per UV unit");
  cmd->add_option("--samples", o->samples, "Multisampling (1-16, default 4)");
  cmd->add_option("--background", o->background, "Background colour r,g,b (0-1, default white)");
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts and timings");
  cmd->callback([o, cmd] {
    if (std::filesystem::path(o->out).extension() != ".png")
      throw InputError(fmt::format("{}: the output must be a .png file", o->out));
    if (!o->adaptive)
      for (const char* a : {"--depth", "--tolerance", "--max-depth", "--errors", "--tess",
                            "--tess-px", "--depth-colors"})
        if (cmd->count(a)) throw InputError(fmt::format("{} goes with --adaptive", a));
    if (o->adaptive && o->flat) throw InputError("--flat is for meshes, not --adaptive");
    if (cmd->count("--uv-checker") && !(o->uv_checker > 0 && o->uv_checker <= 1024))
      throw InputError(fmt::format("--uv-checker {}: squares per UV unit, 0-1024", o->uv_checker));
    if (o->nearest && o->texture.empty()) throw InputError("--nearest goes with --texture");
    if (o->samples < 1 || o->samples > 16)
      throw InputError(fmt::format("--samples {}: must be 1-16", o->samples));
    o->a.dynamic = cmd->count("--tolerance") > 0;
    const bool fixed_tess = cmd->count("--tess") > 0;
    if (fixed_tess && cmd->count("--tess-px"))
      throw InputError("--tess and --tess-px exclude each other");
    if (fixed_tess && (o->a.tess < 1 || o->a.tess > 32))
      throw InputError(fmt::format("--tess {}: must be 1-32 on the GPU", o->a.tess));
    const float pps = cmd->count("--tess-px") ? o->a.tess_px : 8.0f;
    if (!(pps > 0 && std::isfinite(pps)))
      throw InputError(fmt::format("--tess-px {}: must be a positive number of pixels", pps));
    float bg[4] = {1, 1, 1, 1};
    {
      std::stringstream in(o->background);
      std::string item;
      int k = 0;
      for (; std::getline(in, item, ','); ++k) {
        size_t used = 0;
        float x = -1;
        try {
          x = std::stof(item, &used);
        } catch (const std::exception&) {
        }
        if (k > 2 || used != item.size() || !(x >= 0 && x <= 1))
          throw InputError(fmt::format("--background {}: three numbers 0-1", o->background));
        bg[k] = x;
      }
      if (k != 3)
        throw InputError(fmt::format("--background {}: three numbers 0-1", o->background));
    }
    check_adaptive(o->a, o->width, o->height);
    o->fixed_tess = fixed_tess, o->pps = pps;
    std::copy(bg, bg + 4, o->clear_color);
    reinterpret_cast<RenderEntry>(gl_entry(kRenderEntry))(*o);
  });
}

}  // namespace limn::cli
