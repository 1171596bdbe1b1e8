// limn io: mesh files. OBJ (with OpenSubdiv `t` tags), PLY (ascii, binary LE/BE), OFF; binary
// glTF out. The target limn::io (src/io/), apart from limn::mesh so that a program using only
// the algorithms links no file-format package (tinyobjloader, tinygltf).
//
// Readers are strict: any malformed, truncated or hostile input throws InputError with one line
// naming the file, the line or element, and the problem. Header counts are checked against the
// file size before anything is allocated. Writers build the whole file in memory and publish it
// with an atomic rename, so a failed write never leaves a partial file behind.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "limn/mesh/file.hpp"
#include "limn/mesh/mesh.hpp"

namespace limn {

enum class MeshFormat { automatic, obj, ply, off, glb };

/// "obj", "ply", "off", "glb" (case-insensitive) -> format; anything else -> automatic.
MeshFormat format_from_name(std::string_view name);
/// Format from the file extension; `automatic` when unknown.
MeshFormat format_from_path(const std::filesystem::path& path);

/// Reads a mesh. `format == automatic` picks by extension, then by the file's first bytes.
/// Throws InputError for unreadable paths, directories and bad content. O(file size).
Mesh read_mesh(const std::filesystem::path& path, MeshFormat format = MeshFormat::automatic);

/// Parses a mesh held in memory. `name` is used in error messages. Throws InputError.
Mesh read_mesh_memory(std::string_view data, MeshFormat format, std::string_view name);

/// Format-specific parsers (what read_mesh dispatches to); all validate their result.
Mesh read_obj(std::string_view data, std::string_view name);
Mesh read_ply(std::string_view data, std::string_view name);
Mesh read_off(std::string_view data, std::string_view name);

struct WriteOptions {
  MeshFormat format = MeshFormat::automatic;  ///< automatic: by extension.
  bool ascii = false;                         ///< PLY only: ascii instead of binary little-endian.
};

/// Serialises a mesh to a byte string in the given (non-automatic) format.
std::string write_mesh_memory(const Mesh& mesh, MeshFormat format, bool ascii_ply = false);

/// Writes a mesh atomically (temp file in the same folder, then rename). Throws InputError for a
/// format that cannot be chosen, std::runtime_error when the file cannot be written.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& opt = {});

/// What writing `mesh` as `format` would lose: "uv", "normals", "colors", "alpha" (colour
/// alpha other than 1: OBJ keeps RGB), "creases", "corners", "holes", "tags" (OpenSubdiv scheme
/// tags), in that order; empty when the file keeps everything. OBJ keeps all but alpha; PLY and
/// GLB keep UVs, normals and colours (seams split into separate vertices) but no subdivision
/// tags; OFF keeps geometry only. O(V + corners).
std::vector<std::string> dropped_attributes(const Mesh& mesh, MeshFormat format);

/// Per-format writers (what write_mesh dispatches to), appending to `out`.
void write_obj(const Mesh& mesh, std::string& out);
void write_ply(const Mesh& mesh, std::string& out, bool ascii);
void write_off(const Mesh& mesh, std::string& out);
/// Binary glTF 2.0: faces fan-triangulated, smooth normals (or the mesh's own), COLOR_0 when the
/// mesh has vertex colours; corners are split only where attributes differ.
void write_glb(const Mesh& mesh, std::string& out);

}  // namespace limn
