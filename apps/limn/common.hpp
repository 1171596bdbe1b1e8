// Shared pieces of the limn CLI: command registration, timing, stats formatting.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "../common/reports.hpp"
#include "../common/stopwatch.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/repair.hpp"
#include "limn/mesh/topology.hpp"

namespace limn::cli {

using jobs::Stopwatch;
using reports::material_json;
using reports::repair_json;
using reports::stats_json;
using reports::texture_json;

void add_info(CLI::App& app);
void add_convert(CLI::App& app);
void add_shape(CLI::App& app);
void add_demo(CLI::App& app);
void add_subdivide(CLI::App& app);
void add_simplify(CLI::App& app);
void add_paint(CLI::App& app);
void add_bake(CLI::App& app);
void add_render(CLI::App& app);
void add_repair(CLI::App& app);
void add_unwrap(CLI::App& app);

/// Reads a command's input mesh: `format` from the option named `format_option` (empty: by
/// extension, then content), `weld` from --weld (glTF: seams merged back into one cage vertex
/// each); `dropped_degenerate` (optional) receives the triangles dropped for repeating a vertex.
Mesh read_input(const std::string& path, const std::string& format, bool weld,
                size_t* dropped_degenerate = nullptr, const char* format_option = "--format");
/// Adds --weld to a command that reads a mesh.
void add_weld_flag(CLI::App& cmd, bool& weld);

/// --repair and --weld-tolerance of a command that reads a mesh.
struct RepairFlags {
  bool on = false;
  double tolerance = RepairOptions{}.weld_tolerance;
};
/// Adds --repair and --weld-tolerance to a command.
void add_repair_flags(CLI::App& cmd, RepairFlags& repair);
/// read_input, then with --repair: the file is read as a polygon soup (faces may repeat a
/// vertex) and repaired, its summary printed as one line on stderr. `report` receives the
/// counts as JSON (repair_json), or null without --repair. InputError when nothing is left.
Mesh read_input(const std::string& path, const std::string& format, bool weld,
                const RepairFlags& repair, nlohmann::json& report);
/// Reads `path` with `r` as a polygon soup (faces may repeat a vertex); `dropped` receives the
/// triangles STL and glTF drop while reading for repeating a vertex.
Mesh read_soup(const std::string& path, ReadOptions r, size_t& dropped);
/// Repairs `soup` read from `path` (repair_mesh with weld tolerance `tolerance`), counting the
/// `dropped` triangles as degenerate faces too, prints the summary line on stderr and returns the
/// result; InputError naming `path` when it has no faces before or after.
Mesh repair_input(const Mesh& soup, size_t dropped, const std::string& path, double tolerance,
                  RepairReport& report);
/// One line: "welded 3 vertices, dropped 2 degenerate faces, ..." or "nothing to repair".
std::string repair_summary(const RepairReport& r);

/// `--format` values accepted for input/output overrides.
MeshFormat parse_format_option(const std::string& value, const char* option);

/// The options to write OUT with: `to` (--to) or the extension gives the format, `ascii` PLY's
/// encoding. InputError naming OUT when neither gives a format limn writes.
WriteOptions output_options(const std::string& out, const std::string& to, bool ascii);

/// "a,b,c,..." -> numbers; InputError "OPTION S: 'item' is not a number" for any other item.
std::vector<float> parse_numbers(const std::string& s, const char* option);

/// Writes `mesh` to `path` (atomically, format by extension or `opt`) and returns what was lost
/// on the way as a JSON array of names: `lost` (what the command itself could not carry, e.g.
/// "uv" through a step without UV support) followed by what the file format cannot store
/// (dropped_attributes). When it is not empty, one warning line on stderr names them.
nlohmann::json write_output(const Mesh& mesh, const std::string& path,
                            std::vector<std::string> lost = {}, const WriteOptions& opt = {});

/// InputError "PATH: WHAT folder DIR does not exist" unless the folder `path` goes into exists:
/// checked before minutes of work are spent.
void check_writable_folder(const std::string& path, const char* what);

/// Human-readable multi-line summary of the stats.
std::string stats_text(const MeshStats& s);

}  // namespace limn::cli
