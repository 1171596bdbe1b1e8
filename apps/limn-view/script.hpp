// limn-view: the scripted mode's actions (a small JSON file), so the viewer can be driven and
// checked without a person at the mouse, e.g. under Xvfb in CI.
//
// The file is a JSON array of actions (or an object with an "actions" array); each action is an
// object with one key:
//   {"orbit": [yaw_deg, pitch_deg]}  {"pan": [dx_px, dy_px]}  {"zoom": factor}  {"frame": true}
//   {"mode": "view" | "paint" | "simplify"}
//   {"display": "cage" | "surface" | "painted" | "clusters" | "simplified"}
//   {"surface": {"dynamic": bool, "depth": 0-10, "tolerance": px, "max_depth": 1-10,
//                "tess_px": px}}                      (any subset of the keys)
//   {"wireframe": bool}  {"depth_colors": bool}  {"ui": bool}
//   {"filtered": bool}                 (painted colour filtered, or the nearest texel)
//   {"stroke": {"points": [[x, y], ...], "radius": px, "color": [r, g, b(, a)], "opacity": o,
//               "hardness": h, "blend": "mix" | "add" | "multiply" | "erase", "depth": d,
//               "spacing": s, "live": bool}}   (window pixels, y down; only "points" is required;
//               live: one point per frame, as a mouse drag delivers them, with the stroke's time
//               split into painting, texture uploads and frames and compared with the library
//               painting the same points alone, on one line of stderr)
//   {"undo": true}  {"redo": true}  {"save_texture": "a.lot"}  {"load_texture": "a.lot"}
//   {"simplify": {"proxies": K}}  {"export": "out.obj"}  {"screenshot": "out.png"}
//   {"frames": N}                     (draw N frames before the next action)
// Paths are relative to the working directory. One action runs per frame, in order.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "limn/paint/brush.hpp"

namespace limn::view {

enum class Mode { view, paint, simplify };
enum class Display { cage, surface, painted, clusters, simplified };

/// Names as the script and the command line spell them ("view", "surface", ...).
const char* mode_name(Mode m);
const char* display_name(Display d);
/// Throws InputError naming `what` for an unknown name.
Mode parse_mode(std::string_view s, std::string_view what);
Display parse_display(std::string_view s, std::string_view what);
BlendMode parse_blend(std::string_view s, std::string_view what);

/// Changes to the surface settings; unset fields stay as they are.
struct SurfaceChange {
  std::optional<bool> dynamic;
  std::optional<int> depth, max_depth;
  std::optional<float> tolerance_px, tess_px;
};

struct Action {
  enum class Kind {
    orbit,
    pan,
    zoom,
    frame,
    mode,
    display,
    surface,
    wireframe,
    depth_colors,
    filtered,
    ui,
    stroke,
    undo,
    redo,
    save_texture,
    load_texture,
    simplify,
    export_mesh,
    screenshot,
    frames
  };
  Kind kind = Kind::frames;
  double x = 0, y = 0;  ///< orbit (degrees), pan (pixels), zoom (x: factor)
  bool flag = false;    ///< wireframe, depth_colors, filtered, ui
  Mode mode = Mode::view;
  Display display = Display::surface;
  SurfaceChange surface;
  std::vector<double> points;  ///< stroke: x, y pairs in window pixels
  Brush brush;                 ///< stroke: radius in pixels
  bool live = false;           ///< stroke: one point per frame
  size_t count = 0;            ///< frames, simplify proxies
  std::filesystem::path path;  ///< save/load texture, export, screenshot
  std::string where;           ///< "FILE: action N" for messages
};

/// Parses a script. Throws InputError naming the file and the action for anything malformed
/// (unknown keys, wrong types, out-of-range values): the script never half-runs.
std::vector<Action> parse_script(std::string_view text, std::string_view name);
/// Reads and parses a script file.
std::vector<Action> read_script(const std::filesystem::path& path);

}  // namespace limn::view
