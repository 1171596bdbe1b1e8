// limn paint: stroke scripts (the JSON file `limn paint --strokes` reads; schema in
// docs/paint-strokes.md) and running them.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "limn/paint/brush.hpp"

namespace limn {

/// One entry of a script.
struct StrokeCommand {
  enum class Type { stroke, fill, pick, undo, redo };
  Type type = Type::stroke;
  bool screen = false;         ///< stroke/pick: points are pixels (needs the camera)
  Brush brush;                 ///< stroke and fill (fill: colour, opacity, blend, depth)
  bool depth_given = false;    ///< the entry set its own depth
  bool fill_refines = false;   ///< fill: "depth" given, refine the whole surface to it first
  std::vector<float> points;   ///< world: xyz per point
  std::vector<double> pixels;  ///< screen: xy per point
};

struct StrokeScript {
  std::optional<PaintCamera> camera;
  std::vector<StrokeCommand> commands;
};

/// Parses a script. Every problem (malformed JSON, a wrong type, an unknown key, a missing field,
/// a value out of range or not finite, more than a million entries or ten million points or
/// dabs) throws InputError with one line naming `name`, the entry and the problem. `depth`: the
/// depth of strokes that give none. O(size).
StrokeScript parse_strokes(std::string_view json, std::string_view name, int depth);
/// Reads and parses a script file.
StrokeScript read_strokes(const std::filesystem::path& path, int depth);

struct PickResult {
  size_t command = 0;  ///< index in the script
  bool found = false;  ///< a painted sample was there
  float rgba[4] = {0, 0, 0, 0};
  float channels[3] = {0, 0, 0};  ///< roughness, metallic, height there (the defaults where none)
};

struct ScriptResult {
  std::vector<StrokeStats> strokes;  ///< one per stroke and fill entry, in order
  std::vector<PickResult> picks;
  size_t undos = 0, redos = 0;  ///< undo/redo entries that had something to act on
};

/// Runs a script on a material, strokes and fills recorded in `history` (so its undo/redo
/// entries work, and a caller can undo further); an entry painting a channel makes the RMH
/// texture with `defaults` when absent. Throws InputError for a screen entry without a camera.
ScriptResult run_strokes(MaterialTexture& m, const PaintSurface& s, const StrokeScript& script,
                         PaintHistory& history, MaterialDefaults defaults = {});

}  // namespace limn
