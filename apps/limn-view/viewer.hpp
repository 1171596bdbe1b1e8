// limn-view: the window (GLFW, OpenGL 4.5 core), the Dear ImGui panel, mouse and keyboard, and
// the scripted mode.
#pragma once

#include <filesystem>
#include <vector>

#include "scene.hpp"
#include "script.hpp"

namespace limn::view {

struct ViewerOptions {
  int width = 1280, height = 800;  ///< window size, screen coordinates
  int samples = 4;                 ///< multisampling of the window's framebuffer (0: none)
  bool ui = true;                  ///< show the panel
  std::vector<Action> script;      ///< run in order, one per frame
  /// Scripted: after the script, draw this many frames, write `screenshot` (if any) and exit.
  bool scripted = false;
  size_t frames = 0;
  std::filesystem::path screenshot;
};

/// Opens the window and runs until it is closed (or the script is done). Throws
/// std::runtime_error when no window or OpenGL 4.5 context can be made (no display), and
/// whatever a scripted action throws (InputError for bad input, e.g. a texture file).
void run_viewer(Scene& scene, const ViewerOptions& options);

}  // namespace limn::view
