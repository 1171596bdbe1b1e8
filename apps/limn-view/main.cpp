// limn-view: the interactive viewer. Composes the library layers (subdiv, paint, simplify,
// render) behind a GLFW window and a Dear ImGui panel; no algorithm lives here.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <new>
#include <string>

#include "../common/image_size.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/version.hpp"
#include "scene.hpp"
#include "script.hpp"
#include "viewer.hpp"

namespace {

void parse_size(const std::string& s, int& w, int& h) {
  limn::app::parse_image_size(s, "--size", "1280x800", 64, 16384, w, h);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "limn-view: view a subdivision surface with per-vertex adaptive depth, paint it without "
      "UVs, simplify it",
      "limn-view"};
  app.footer(
      "Mouse: left drag orbits (paints in paint mode), right drag pans (orbits in paint mode), "
      "middle or shift drag pans, wheel zooms. Keys: Ctrl+Z undo, Ctrl+Y or Ctrl+Shift+Z redo, "
      "F frame the model, W wireframe, Tab panel, F12 screenshot (limn-view-NNN.png).");
  app.set_version_flag("--version", std::string("limn-view ") + limn::version());
  std::string mesh, shape, size = "1280x800", script, screenshot, format;
  int samples = 4;
  size_t frames = 0;
  bool no_ui = false;
  app.add_option("MESH", mesh,
                 "Control cage or mesh (OBJ with OpenSubdiv tags, PLY, OFF); default: the "
                 "built-in torus cage");
  app.add_option("--shape", shape, "Open a built-in shape instead (cube, torus, cage, ...)");
  app.add_option("--format", format, "Input format, overriding the extension (obj, ply, off)");
  app.add_option("--size", size, "Window size WxH (default 1280x800)");
  app.add_option("--samples", samples, "Multisampling of the window (0-16, default 4)");
  app.add_option("--script", script,
                 "Run the actions of this JSON file, then exit (see apps/limn-view/script.hpp)");
  app.add_option("--frames", frames, "Scripted: draw N frames (after the script), then exit");
  app.add_option("--screenshot", screenshot,
                 "Scripted: write the last frame to this PNG before exiting");
  app.add_flag("--no-ui", no_ui, "Hide the panel (Tab toggles it)");
  try {
    app.parse(argc, argv);
    limn::view::ViewerOptions o;
    parse_size(size, o.width, o.height);
    if (samples < 0 || samples > 16) throw limn::InputError("--samples: must be 0-16");
    if (!mesh.empty() && !shape.empty()) throw limn::InputError("give MESH or --shape, not both");
    if (!screenshot.empty() && std::filesystem::path(screenshot).extension() != ".png")
      throw limn::InputError(screenshot + ": the screenshot must be a .png file");
    limn::MeshFormat fmt = limn::MeshFormat::automatic;
    if (!format.empty()) {
      fmt = limn::format_from_name(format);
      if (fmt == limn::MeshFormat::automatic || fmt == limn::MeshFormat::glb)
        throw limn::InputError("--format " + format + ": expected obj, ply or off");
    }
    o.samples = samples, o.ui = !no_ui;
    o.frames = frames, o.screenshot = screenshot;
    o.scripted = !script.empty() || frames > 0 || !screenshot.empty();
    if (!script.empty()) o.script = limn::view::read_script(script);
    // Input first: a bad file is reported before any window opens.
    std::string name = mesh.empty() ? (shape.empty() ? "torus" : shape) : mesh;
    limn::Mesh m = mesh.empty() ? limn::make_shape(name) : limn::read_mesh(mesh, fmt);
    if (m.face_count() == 0) throw limn::InputError(name + ": the mesh has no faces");
    limn::view::Scene scene(std::move(m), name);
    limn::view::run_viewer(scene, o);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const limn::InputError& e) {
    std::fprintf(stderr, "limn-view: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "limn-view: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "limn-view: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
