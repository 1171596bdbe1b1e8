// limn render: a PNG of a mesh, or of its adaptive limit surface drawn with tessellation shaders,
// rendered headless (EGL; Mesa's llvmpipe without a GPU).
#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <sstream>

#include "adaptive.hpp"
#include "common.hpp"
#include "limn/paint/file.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"

namespace limn::cli {

void add_render(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "Render a mesh or its adaptive limit surface to PNG");
  struct Opts {
    std::string mesh, out, format, background = "1,1,1", texture;
    bool adaptive = false, wireframe = false, flat = false, nearest = false, json = false,
         weld = false;
    float uv_checker = 0.0f;
    int samples = 4;
    AdaptiveOpts a;
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
                  "Colour from an octree texture (.lot, limn paint) painted on this surface");
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
    int w = 1280, h = 720;
    check_adaptive(o->a, w, h);

    Stopwatch sw;
    const Mesh mesh = read_input(o->mesh, o->format, o->weld);
    std::optional<OctreeTexture> texture;
    if (!o->texture.empty()) texture = load_lot(o->texture);
    nlohmann::json timings = {{"read", sw.lap()}};
    GlContext gl;
    timings["context"] = sw.lap();
    std::optional<GpuOctreeTexture> gpu_texture;
    if (texture) gpu_texture.emplace(*texture);
    RenderTarget target(w, h, o->samples);
    DrawOptions d;
    d.outline = o->wireframe;
    d.depth_colors = o->a.depth_colors;
    d.pixels_per_segment = pps;
    d.factor = fixed_tess ? o->a.tess : 0;
    d.texture = gpu_texture ? &*gpu_texture : nullptr;
    d.texture_nearest = o->nearest;
    d.uv_checker = o->uv_checker;
    if (d.uv_checker > 0 && mesh.uv_indices.empty())
      throw InputError(fmt::format("{}: --uv-checker: the mesh has no UVs", o->mesh));
    DrawStats st;
    nlohmann::json patches = nullptr;
    Camera cam;
    if (o->adaptive) {
      const AdaptiveSurface surf = build_adaptive(mesh, o->a, w, h, sw, timings);
      cam = surf.cam;
      PatchDrawer drawer(mesh, surf.table, surf.points);
      timings["upload"] = sw.lap();
      target.begin(bg);
      st = drawer.draw(cam, d);
      patches = {{"regular", surf.table.regular_params.size()},
                 {"gregory", surf.table.gregory_params.size()}};
    } else {
      cam = frame_camera(mesh, w, h);
      if (!o->a.camera.empty()) cam = parse_camera(o->a.camera, cam);
      MeshDrawer drawer(mesh, {}, o->flat);
      timings["upload"] = sw.lap();
      target.begin(bg);
      st = drawer.draw(cam, d);
    }
    timings["draw"] = sw.lap();
    write_png(o->out, w, h, target.read_rgba());
    timings["write"] = sw.lap();
    if (o->json) {
      nlohmann::json j = {{"input", o->mesh},
                          {"output", o->out},
                          {"renderer", gl.renderer()},
                          {"texture", texture ? nlohmann::json(o->texture) : nlohmann::json()},
                          {"resolution", {w, h}},
                          {"camera",
                           {{"eye", {cam.eye[0], cam.eye[1], cam.eye[2]}},
                            {"target", {cam.target[0], cam.target[1], cam.target[2]}},
                            {"fovy_deg", cam.fovy_deg}}},
                          {"drawn", st.patches},
                          {"patches", patches},
                          {"triangles", st.triangles},
                          {"gpu_ms", st.gpu_ms},
                          {"cpu_draw_ms", st.cpu_ms},
                          {"timings_ms", timings}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: {} {} drawn, {} triangles, {}x{} ({:.1f} ms)\n", o->mesh, o->out,
                 st.patches, o->adaptive ? "patches" : "polygons", st.triangles, w, h, sw.ms());
    }
  });
}

}  // namespace limn::cli
