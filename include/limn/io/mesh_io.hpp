// limn io: mesh files. OBJ (with OpenSubdiv `t` tags), PLY (ascii, binary LE/BE), OFF, STL
// (ascii and binary) in and out; glTF 2.0 (.gltf with external or embedded buffers, .glb) in,
// binary glTF out. The target limn::io (src/io/), apart from limn::mesh so that a program using
// only the algorithms links no file-format package (tinyobjloader, tinygltf).
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

/// File formats. `gltf` is glTF 2.0 JSON (.gltf), `glb` its binary container; both read the same
/// way (the bytes tell them apart), only `glb` can be written.
enum class MeshFormat { automatic, obj, ply, off, glb, stl, gltf };

/// "obj", "ply", "off", "glb", "gltf", "stl" (case-insensitive, optional leading dot) -> format;
/// anything else -> automatic.
MeshFormat format_from_name(std::string_view name);
/// Format from the file extension; `automatic` when unknown.
MeshFormat format_from_path(const std::filesystem::path& path);

struct ReadOptions {
  MeshFormat format = MeshFormat::automatic;  ///< automatic: by extension, then by content.
  /// glTF only (ignored for other formats): merge the vertices glTF splits at UV and normal
  /// seams back into one cage vertex each (weld_vertices), UVs and normals kept per corner.
  bool weld = false;
  /// Folder that a .gltf file's external buffers (`"uri": "x.bin"`) resolve against. read_mesh
  /// uses the file's own folder when this is empty; read_mesh_memory the current directory.
  std::filesystem::path base_dir;
  /// When set, receives the number of triangles dropped for repeating a vertex (STL after its
  /// welding, glTF, and glTF's weld); 0 for the other formats.
  size_t* dropped_degenerate = nullptr;
  /// OBJ, PLY, OFF: keep faces that repeat a vertex (validate_soup instead of validate), for
  /// repair_mesh to clean up. STL and glTF drop such triangles either way.
  bool soup = false;
};

/// Reads a mesh. `format == automatic` picks by extension, then by the file's first bytes.
/// Throws InputError for unreadable paths, directories and bad content. O(file size).
Mesh read_mesh(const std::filesystem::path& path, MeshFormat format = MeshFormat::automatic);
/// The same with options (glTF welding, buffer folder).
Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options);

/// Parses a mesh held in memory. `name` is used in error messages. Throws InputError.
Mesh read_mesh_memory(std::string_view data, MeshFormat format, std::string_view name);
/// The same with options; a .gltf's external buffers resolve against `options.base_dir` (the
/// current directory when empty) and fail with InputError naming the buffer when missing.
Mesh read_mesh_memory(std::string_view data, const ReadOptions& options, std::string_view name);

/// Format-specific parsers (what read_mesh dispatches to); all validate their result, or with
/// `soup` only validate_soup it (faces may repeat a vertex).
Mesh read_obj(std::string_view data, std::string_view name, bool soup = false);
Mesh read_ply(std::string_view data, std::string_view name, bool soup = false);
Mesh read_off(std::string_view data, std::string_view name, bool soup = false);

/// STL, ascii (`solid ... facet normal ... outer loop vertex x y z ...`) or binary (80-byte
/// header, uint32 triangle count, 50 bytes per triangle), told apart by size first (a binary
/// header may start with "solid"), then by content. Vertices with bit-equal positions are welded
/// (-0.0 = 0.0), so the result is an indexed, connected triangle mesh; facet normals and
/// attribute bytes are ignored. Triangles that repeat a vertex after welding are dropped and
/// counted in `dropped_degenerate` when given. Throws InputError (file, line or facet index) for
/// truncated files, a triangle count that disagrees with the size, non-numbers, NaN or infinite
/// coordinates, facets without exactly 3 vertices. O(file size) expected.
Mesh read_stl(std::string_view data, std::string_view name, size_t* dropped_degenerate = nullptr);

/// glTF 2.0, JSON (.gltf) or binary (.glb, told apart by the "glTF" magic), through tinygltf.
/// Reads every triangle primitive of the default scene (scene 0 when none is named; every mesh
/// untransformed when the file has no scene), applying node transforms (matrix or T*R*S, parent
/// first; normals by the inverse transpose, renormalised; winding flipped under a negative
/// determinant), and concatenates them into one mesh. glTF vertices become limn vertices one to
/// one: normals (NORMAL) and UVs (TEXCOORD_0, v flipped back to limn's v-up: v = 1 - v_gltf) are
/// per vertex, so their index arrays equal face_vertices; they are kept only when every
/// primitive has them. COLOR_0 becomes the vertex colours (white where a primitive has none,
/// clamped to [0,1]). Faces are triangles: TRIANGLE_STRIP and TRIANGLE_FAN are converted, and
/// glTF holds no quads to restore; weld_vertices (ReadOptions::weld) turns the split vertices
/// back into a connected cage. Triangles that repeat an index are dropped and counted in
/// `dropped_degenerate` when given. Images are never decoded. Every accessor is bounds-checked
/// against its bufferView and buffer, every index against the vertex count. Throws InputError
/// (file, then mesh/primitive/accessor/node) for points or lines, missing or bad buffers,
/// accessor type mismatches, NaN/Inf, sparse or compressed accessors, cyclic node graphs. External
/// buffers resolve against `base_dir`. O(file size + buffer sizes).
Mesh read_gltf(std::string_view data, std::string_view name, const std::filesystem::path& base_dir,
               size_t* dropped_degenerate = nullptr);

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
/// tags; OFF and STL keep geometry only. O(V + corners).
std::vector<std::string> dropped_attributes(const Mesh& mesh, MeshFormat format);

/// Per-format writers (what write_mesh dispatches to), appending to `out`.
void write_obj(const Mesh& mesh, std::string& out);
void write_ply(const Mesh& mesh, std::string& out, bool ascii);
void write_off(const Mesh& mesh, std::string& out);
/// Binary STL: faces fan-triangulated, each triangle with its unit facet normal (0 for a
/// zero-area one), attribute bytes 0; the 80-byte header never starts with "solid".
void write_stl(const Mesh& mesh, std::string& out);
/// Binary glTF 2.0: faces fan-triangulated, smooth normals (or the mesh's own), COLOR_0 when the
/// mesh has vertex colours; corners are split only where attributes differ.
void write_glb(const Mesh& mesh, std::string& out);

/// The textures of a GLB's pbrMetallicRoughness material, as encoded PNG files (empty: none),
/// embedded in the GLB's binary chunk.
struct GlbTextures {
  std::string base_color_png;          ///< sRGB colour and alpha
  std::string metallic_roughness_png;  ///< linear; green: roughness, blue: metalness
  std::string normal_png;              ///< tangent space, linear
  float metallic = 0, roughness = 1;   ///< factors the textures are multiplied by
};

/// write_glb with the material's textures (the mesh needs UVs for them: TEXCOORD_0). Without a
/// metallic-roughness texture the factors alone apply (metallic 0: a painted dielectric).
void write_glb(const Mesh& mesh, const GlbTextures& textures, std::string& out);

}  // namespace limn
