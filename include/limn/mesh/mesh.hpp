// limn mesh core: a polygon mesh as flat arrays (structure of arrays).
//
// Faces of any arity are stored in CSR form (offsets + one vertex index per corner), the layout
// OpenSubdiv's Far::TopologyDescriptor and GPU index buffers read directly. Optional attributes
// keep their own index spaces like OBJ does, so nothing is welded or split on load.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace limn {

/// Bad input (malformed file, out-of-range index, NaN, ...). The message is one line naming the
/// file or element and the problem; the CLI maps it to exit code 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input that `repair_mesh` (limn/mesh/repair.hpp) fixes: a face that repeats a vertex, a
/// non-manifold edge, faces that disagree on orientation, duplicate faces. The CLI suggests
/// `limn repair` / `--repair` for these.
class RepairableError : public InputError {
 public:
  using InputError::InputError;
};

/// Subdivision boundary rule, as OpenSubdiv's Sdc::Options::VtxBoundaryInterpolation.
enum class BoundaryInterpolation : int8_t {
  unset = -1,
  none = 0,
  edge_only = 1,
  edge_and_corner = 2
};

/// Semi-sharp crease decay, as OpenSubdiv's Sdc::Options::CreasingMethod.
enum class CreaseMethod : int8_t { unset = -1, uniform = 0, chaikin = 1 };

/// Scheme options carried by OpenSubdiv OBJ tags (`t interpolateboundary`, `t creasemethod`, ...).
/// `unset` means the file said nothing; consumers pick their own default.
struct SubdivTags {
  BoundaryInterpolation boundary = BoundaryInterpolation::unset;
  int8_t fvar_boundary = -1;  ///< `t facevaryinginterpolateboundary` value, -1 when absent.
  CreaseMethod crease_method = CreaseMethod::unset;
  bool smooth_triangles = false;  ///< `t smoothtriangles 0/0/1 smooth` (OpenSubdiv TRI_SUB_SMOOTH).
};

/// Sharpness at or above this value is infinitely sharp (OpenSubdiv's SHARPNESS_INFINITE).
inline constexpr float kInfiniteSharpness = 10.0f;

/// A polygon mesh. Invariants (checked by `validate`): every index is in range, every face has at
/// least 3 distinct vertices, positions are finite; attribute index arrays are empty or have one
/// entry per corner.
struct Mesh {
  std::vector<float> positions;           ///< xyz per vertex.
  std::vector<uint32_t> face_offsets{0};  ///< face f spans corners [offsets[f], offsets[f+1]).
  std::vector<uint32_t> face_vertices;    ///< vertex index per corner.

  std::vector<float> normals;            ///< xyz per normal (own index space), optional.
  std::vector<uint32_t> normal_indices;  ///< per corner, empty when there are no normals.
  std::vector<float> uvs;                ///< uv per texture coordinate (own index space).
  std::vector<uint32_t> uv_indices;      ///< per corner, empty when there are no uvs.
  std::vector<float> colors;             ///< RGBA in [0,1] per vertex, optional.

  std::vector<uint32_t> crease_edges;     ///< vertex pairs (2 per crease edge).
  std::vector<float> crease_sharpness;    ///< one per crease edge.
  std::vector<uint32_t> corner_vertices;  ///< vertices tagged as corners.
  std::vector<float> corner_sharpness;    ///< one per corner vertex.
  std::vector<uint32_t> hole_faces;       ///< faces tagged as holes.
  SubdivTags tags;

  size_t vertex_count() const { return positions.size() / 3; }
  size_t face_count() const { return face_offsets.size() - 1; }
  size_t corner_count() const { return face_vertices.size(); }
  uint32_t face_size(size_t f) const { return face_offsets[f + 1] - face_offsets[f]; }
  /// The vertex indices of face f, in order. O(1).
  std::span<const uint32_t> face(size_t f) const {
    return {face_vertices.data() + face_offsets[f], face_size(f)};
  }
  /// Appends a vertex; returns its index. Amortised O(1).
  uint32_t add_vertex(float x, float y, float z);
  /// Appends a face over existing vertices; returns its index. Amortised O(arity).
  uint32_t add_face(std::span<const uint32_t> vertices);
  uint32_t add_face(std::initializer_list<uint32_t> vertices) {
    return add_face(std::span<const uint32_t>(vertices.begin(), vertices.size()));
  }
};

/// Axis-aligned bounding box; empty (min > max) for a mesh without vertices.
struct Box {
  float min[3] = {+INFINITY, +INFINITY, +INFINITY};
  float max[3] = {-INFINITY, -INFINITY, -INFINITY};
  bool empty() const { return min[0] > max[0]; }
  /// Length of the diagonal, 0 when empty.
  float diagonal() const;
};

/// Bounding box of all vertices (referenced or not). O(V).
Box bounding_box(const Mesh& mesh);

/// Vector area of face f (Newell's method; |result| is the area, its direction the normal of a
/// planar polygon, robust for non-convex and non-planar faces). O(arity).
void face_area_vector(const Mesh& mesh, size_t f, float out[3]);

/// Area of face f in squared model units. O(arity).
float face_area(const Mesh& mesh, size_t f);

/// Unit normal of face f, or (0,0,0) for a zero-area face. O(arity).
void face_normal(const Mesh& mesh, size_t f, float out[3]);

/// Area-weighted vertex normals (3 floats per vertex; zero for unreferenced vertices). O(corners).
std::vector<float> vertex_normals(const Mesh& mesh);

/// Returned by repeated_vertex when a face lists each vertex once.
inline constexpr uint32_t kNoRepeat = 0xFFFFFFFFu;

/// A vertex that `face` lists more than once (the smallest such for faces over 16 corners), or
/// kNoRepeat. O(n^2) for n <= 16 corners, where that beats sorting; O(n log n) above, sorting a
/// copy in `scratch`, so a hostile 10^6-gon stays cheap.
uint32_t repeated_vertex(std::span<const uint32_t> face, std::vector<uint32_t>& scratch);

/// Checks the invariants above and throws InputError naming `what` (a file name or "mesh") and the
/// first offending element. O(corners + V).
void validate(const Mesh& mesh, const std::string& what = "mesh");

/// The same checks except that faces may repeat a vertex: what `repair_mesh` accepts (a polygon
/// soup). O(corners + V).
void validate_soup(const Mesh& mesh, const std::string& what = "mesh");

}  // namespace limn
