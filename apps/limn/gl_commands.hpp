// The commands that draw with OpenGL (render, demo) run in a module the CLI opens only when one
// of them runs (limn-gl.so beside the installed libraries), so the other commands never load the
// GL stack: libepoxy's relocations alone cost ~1.5 ms of every process's start here, a tenth of a
// small `limn simplify`. The CLI parses and checks the options; the module does the work.
#pragma once

#include <string>

#include "adaptive.hpp"

namespace limn::cli {

/// `limn render`'s checked options.
struct RenderJob {
  std::string mesh, out, format, texture;
  bool adaptive = false, wireframe = false, flat = false, nearest = false, json = false,
       weld = false;
  bool fixed_tess = false;  ///< --tess given (else screen-space tessellation at `pps`)
  float uv_checker = 0.0f, pps = 8.0f;
  int samples = 4, width = 1280, height = 720;
  float clear_color[4] = {1, 1, 1, 1};  ///< --background, RGBA
  AdaptiveOpts a;
};

/// `limn demo`'s options.
struct DemoJob {
  std::string dir = "limn-demo";
  bool quick = false, json = false;
};

/// The module's entry points (C names, so the CLI finds them with dlsym; the module exports
/// nothing else).
#define LIMN_GL_ENTRY extern "C" __attribute__((visibility("default")))
using RenderEntry = void (*)(const RenderJob&);
using DemoEntry = void (*)(const DemoJob&);
inline constexpr const char* kRenderEntry = "limn_cli_render";
inline constexpr const char* kDemoEntry = "limn_cli_demo";

/// Opens the GL module (once) and returns its entry point `name`; std::runtime_error naming the
/// module's path when it cannot be opened (a broken install).
void* gl_entry(const char* name);

}  // namespace limn::cli
