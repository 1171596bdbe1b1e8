// limn subdiv: Catmull-Clark refinement into per-level topology and stencil tables.
//
// Rules follow OpenSubdiv's Sdc exactly (OpenSubdiv 3.5 is the conformance oracle): faces of any
// arity, boundaries (edge-only / edge-and-corner), infinitely sharp and semi-sharp creases with
// the uniform or Chaikin decay, corner vertices, dart/crease/corner rules with the fractional
// blend when sharpness decays below 1, and holes.
//
// Child vertices of a level are numbered like OpenSubdiv's Vtr does by default: first one point
// per parent face, then one per parent edge, then one per parent vertex. So the provenance of
// every point is implicit: child i < F is the face point of parent face i, F <= i < F + E the
// edge point of parent edge i - F, and the rest vertex points of parent vertex i - F - E.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

/// How face-varying data (UVs) is interpolated, as OpenSubdiv's Sdc::Options::
/// FVarLinearInterpolation; the numbers are the OBJ tag `t facevaryinginterpolateboundary N`'s.
enum class FVarInterpolation : int8_t {
  none = 0,           ///< smooth everywhere: seams are smooth boundary curves on each side
  corners_only = 1,   ///< values whose span around their vertex is one face stay put
  corners_plus1 = 2,  ///< and junctions of three or more values (OpenSubdiv's "edge corner")
  corners_plus2 = 3,  ///< and seams ending inside the surface (darts), concave corners
  boundaries = 4,     ///< every seam and mesh boundary linear, interiors smooth
  all = 5             ///< bilinear everywhere (OpenSubdiv's default)
};

/// Scheme options (OpenSubdiv's Sdc::Options for Catmull-Clark).
struct SubdivOptions {
  BoundaryInterpolation boundary = BoundaryInterpolation::edge_and_corner;
  CreaseMethod crease_method = CreaseMethod::uniform;
  bool smooth_triangles = false;  ///< Sdc TRI_SUB_SMOOTH instead of TRI_SUB_CATMARK.
  FVarInterpolation face_varying = FVarInterpolation::all;
};

/// Options from a mesh's OpenSubdiv tags; unset tags take the defaults above.
SubdivOptions subdiv_options(const Mesh& mesh);

/// Per-point weights over the points of the previous level (CSR): point i is
/// sum_k w_i[k - offsets[i]] * previous[indices[k]] for k in [offsets[i], offsets[i+1]), where
/// w_i = row_weights(i). Weights are either one per entry (weight_offsets empty: w_i starts at
/// weights[offsets[i]]) or shared (w_i starts at weights[weight_offsets[i]], and rows whose
/// weights are bit for bit equal keep one copy). Refinement and end-cap tables share: a level
/// has only a handful of distinct rows (the smooth rules per valence), so sharing takes their
/// weights from one float per entry to one offset per row, about 40% of the table. Composed
/// and limit stencils keep one weight per entry.
struct StencilTable {
  std::vector<uint32_t> offsets{0};
  std::vector<uint32_t> indices;
  std::vector<uint32_t> weight_offsets;  ///< per row, or empty (see above)
  std::vector<float> weights;
  size_t size() const { return offsets.size() - 1; }
  bool shared() const { return !weight_offsets.empty(); }
  /// Where row i's weights start in `weights`.
  uint32_t weight_start(size_t i) const {
    return weight_offsets.empty() ? offsets[i] : weight_offsets[i];
  }
  /// Row i's weights: offsets[i + 1] - offsets[i] floats.
  const float* row_weights(size_t i) const { return weights.data() + weight_start(i); }
};

/// Applies a stencil table to `channels` interleaved floats per point: out gets size() points.
/// 1 <= channels <= 16. Sums in double. Data-parallel over points (TBB).
/// O(total stencil entries * channels).
void apply_stencils(const StencilTable& table, const float* in, float* out, int channels);

/// The topology of one refinement level, as flat arrays.
struct RefinedLevel {
  std::vector<uint32_t> face_offsets{0};  ///< CSR faces (level 0 = the cage; later levels quads)
  std::vector<uint32_t> face_vertices;
  std::vector<uint32_t> edge_vertices;  ///< 2 per edge
  std::vector<float> edge_sharpness;    ///< per edge, after decay; kInfiniteSharpness = sharp
  std::vector<float> vertex_sharpness;  ///< per vertex, after decay
  std::vector<uint8_t> face_hole;       ///< per face: 1 when the face is (inside) a hole
  size_t vertex_count() const { return vertex_sharpness.size(); }
  size_t face_count() const { return face_offsets.size() - 1; }
  size_t edge_count() const { return edge_sharpness.size(); }
};

/// Uniform refinement to `depth` levels: levels[0] describes the cage, levels[k] (k >= 1) the
/// k-th refinement, and stencils[k-1] computes level k's points from level k-1's. Each table
/// comes in the paper's three blocks, in child-vertex order: the face-point table (one stencil
/// per level-(k-1) face), the edge-point table (one per edge), the vertex-point table (one per
/// vertex); within a block the rules (smooth, crease, corner, blended) are mixed, each stencil
/// carrying its own weights.
/// One face-varying channel (UVs, or any per-corner data) of a cage: a value index per corner
/// (the order of Mesh::face_vertices) into `value_count` values. Corners of a vertex that share
/// an index are continuous there; a vertex whose corners hold several indices is on a seam.
struct FaceVaryingInput {
  std::span<const uint32_t> corner_values;
  size_t value_count = 0;
  bool limit = false;  ///< also build limit stencils at the last level (FaceVaryingLevels::limit)
};

/// A face-varying channel through the levels of a refinement (OpenSubdiv's Far face-varying
/// levels and PrimvarRefiner::InterpolateFaceVarying): corner_values[k] holds a value index per
/// corner of level k (level 0: the input's), stencils[k-1] computes level k's values from level
/// k-1's (level 0's are the caller's, indexed as the input indexes them).
struct FaceVaryingLevels {
  std::vector<std::vector<uint32_t>> corner_values;
  std::vector<size_t> value_counts;
  std::vector<StencilTable> stencils;
  /// Limit values at the last level (PrimvarRefiner::LimitFaceVarying): one row per value of
  /// the last level, over those values. Empty unless asked for (FaceVaryingInput::limit), or
  /// when the last level is not all quads (depth 0).
  StencilTable limit;
  /// Values (`channels` floats each) of level `level`, from the cage's values. O(entries).
  std::vector<float> values(const float* cage_values, int channels, int level) const;
};

struct UniformRefinement {
  SubdivOptions options;
  std::vector<RefinedLevel> levels;
  std::vector<StencilTable> stencils;
  std::vector<FaceVaryingLevels> face_varying;  ///< one per channel given to refine_uniform
  /// Positions (3 floats per point) of level `level`, by applying the stencils to the cage's.
  std::vector<float> positions(const Mesh& cage, int level) const;
};

/// Composes stencil tables: the result computes `outer`'s points directly from the points `inner`
/// reads (outer after inner). Weights are merged per source point and computed in double.
/// O(sum over outer entries of the inner stencil sizes).
StencilTable compose_stencils(const StencilTable& outer, const StencilTable& inner);

/// Stencils from the cage straight to level `level` (1 <= level <= depth): one pass turns an
/// animated cage into that level's points, like OpenSubdiv's Far::StencilTableFactory without
/// intermediate levels.
StencilTable cage_stencils(const UniformRefinement& r, int level);

struct SparseRefinement;
/// The same for a sparse refinement: cage to the local points of sparse level `level`.
StencilTable cage_stencils(const SparseRefinement& r, int level);

/// Limit stencils over the points of one refinement level: position, and the two tangents whose
/// cross product is the (outward, for counter-clockwise faces) normal. Smooth, dart, crease and
/// corner masks as OpenSubdiv's Catmull-Clark limit masks (Far::PrimvarRefiner::Limit), using
/// the rule of each vertex at that level.
struct LimitStencils {
  StencilTable position, tangent1, tangent2;
};

/// Builds limit stencils for level `level` (>= 1 unless the cage is all quads). O(points *
/// valence). Throws InputError when the level has non-quad faces.
LimitStencils limit_stencils(const UniformRefinement& r, int level);

/// The same for any refined level of quads, uniform or sparse. On a sparse level only the
/// stencils of complete vertices (SparseLevel::vertex_complete) are the limit's; the others see
/// a cut-off ring and are meaningless.
LimitStencils limit_stencils(const RefinedLevel& level);

/// Unit normals (3 floats per point) from two tangent arrays; a zero normal where the tangents
/// are parallel (degenerate geometry).
std::vector<float> normals_from_tangents(const std::vector<float>& t1,
                                         const std::vector<float>& t2);

/// One level of a sparse refinement: the part of the uniformly refined level k that the
/// requested depths need, with local numbering. Vertices are numbered in blocks like a uniform
/// level's, so provenance is implicit: local vertex i is the face point of previous-level face
/// parent_faces[i] for i < parent_faces.size(), then the edge points of parent_edges[], then the
/// vertex points of parent_vertices[] (all empty at level 0, which is the whole cage).
struct SparseLevel {
  RefinedLevel level;
  std::vector<uint32_t> parent_faces, parent_edges, parent_vertices;
  std::vector<uint32_t> face_parent;     ///< per face: the previous-level face it comes from
  std::vector<uint8_t> vertex_complete;  ///< 1 when every face of the uniform level around the
                                         ///< vertex is present (its ring is whole)
  std::vector<uint8_t> vertex_depth;     ///< per vertex: levels still to refine around it
  std::vector<uint8_t> face_depth;       ///< per face: levels still to refine inside it
  std::vector<uint8_t> face_refined;     ///< per face: 1 when the next level has children of it
};

/// Sparse (feature-adaptive) refinement: levels[0] is the cage, stencils[k-1] computes level k's
/// local points from level k-1's. Every point present equals the uniform refinement's point of
/// the same provenance.
struct SparseRefinement {
  SubdivOptions options;
  std::vector<SparseLevel> levels;
  std::vector<StencilTable> stencils;
  /// Positions (3 floats per local point) of level `level`.
  std::vector<float> positions(const Mesh& cage, int level) const;
};

/// Refines only where asked, each place to its own depth (0 <= depth <= 16):
/// - vertex_depth[v] = d: at every level 1 <= k <= d, every child of the faces around v's
///   level-(k-1) descendant is present with complete vertices: the ring around the level-k
///   descendant and its siblings, which is what FAS turns into patches (each has all the
///   control points a B-spline, transition or Gregory patch needs);
/// - face_depth[f] = d: every descendant of face f down to level d is present, with complete
///   vertices.
/// Either span may be empty (no requests of that kind); otherwise it has one entry per cage
/// vertex / face. At level k the requested faces (faces with a vertex or face depth left) are
/// refined whole, and every face sharing a vertex with them gets its children at those shared
/// vertices only (OpenSubdiv's sparse rule): that keeps every child point exact and every child
/// of a requested face whole; so the work per requested vertex is O(valence^2) per level and
/// linear in depth, not 4^depth. SparseLevel::face_refined marks both kinds. Throws InputError for
/// bad spans or cages limn cannot subdivide.
SparseRefinement refine_sparse(const Mesh& cage, std::span<const uint8_t> vertex_depth,
                               std::span<const uint8_t> face_depth, const SubdivOptions& options);

/// A sparse level's adjacency as refine_sparse has it (valid during the call it is passed to).
/// Corners are indices into the level's face_vertices; edges are the level's edge list.
struct LevelAdjacency {
  std::span<const uint32_t> corner_edge;  ///< per corner: the edge of its outgoing half-edge
  std::span<const uint32_t> edge_corner_offsets, edge_corners;      ///< edge -> corners on it
  std::span<const uint32_t> vertex_corner_offsets, vertex_corners;  ///< vertex -> its corners
  /// Per corner: the other corner on its edge, kNone on a boundary, kNonManifold on an edge of
  /// more than two faces. Given to `level_done` for a lean run's last level, whose edge -> corner
  /// lists are then dropped (empty) first; empty otherwise.
  std::span<const uint32_t> corner_twin;
};

/// Decides which faces of a sparse level to refine: called once per level (0 = the cage) with
/// the level built so far and its adjacency; sets requested[f] = 1 (requested arrives sized to
/// the level's faces, all 0) for each face to refine. Faces sharing a vertex with a requested
/// face get their children at the shared vertices, so each requested face's children have
/// complete vertices; a requested face must have complete vertices itself (a child of a
/// requested face, or a face of the cage). No request
/// ends the refinement; requests past level 16 throw InputError. The levels stay where they are
/// in memory while the refinement runs (they are reserved up front), so a caller may keep
/// pointers to earlier ones.
using SparseRequest =
    std::function<void(size_t level, const SparseLevel& level_so_far,
                       const LevelAdjacency& adjacency, std::vector<uint8_t>& requested)>;

/// Sparse refinement driven level by level (feature-adaptive isolation decides from each
/// level's own topology and sharpness). SparseLevel::vertex_depth and face_depth stay 0.
/// keep_levels = false: a caller that builds what it needs inside `request` (patch tables) gets
/// only the stencils back; level k-1 is dropped once the request for level k has returned, so
/// at most two levels' topology live at a time. Its level-k stencils then have rows only for the
/// points within one ring of the children of the faces requested at level k-1 or of the faces
/// refined from level k (what such a caller and the next level's stencils can read); the other
/// rows are empty.
/// `level_done` (optional) is called once per level, after `request` and after the level's
/// stencils are built (lean runs: and level k-1 dropped), with the level and its adjacency: a
/// caller that only reads a level (patch tables emit their patches there) then holds one
/// level's topology instead of two.
using SparseLevelDone =
    std::function<void(size_t level, const SparseLevel& level_so_far, const LevelAdjacency&)>;
SparseRefinement refine_sparse(const Mesh& cage, const SubdivOptions& options,
                               const SparseRequest& request, bool keep_levels = true,
                               const SparseLevelDone& level_done = {});

/// Counts and timings of a lean uniform subdivision (subdivide_uniform).
struct SubdivideStats {
  struct Level {
    size_t vertices = 0, faces = 0, edges = 0;
    size_t stencil_entries = 0;  ///< entries of the stencils that computed this level
  };
  std::vector<Level> levels;  ///< levels[0] is the cage
  double topology_ms = 0;     ///< cage adjacency and tags, and every derived level's topology
  double stencils_ms = 0;     ///< building each level's stencils and applying them (fused)
  double output_ms = 0;       ///< the last level's faces and remaining sharpness tags
};

/// Uniform subdivision that keeps only what the last level needs: the level-`depth` quads
/// (faces of holes dropped; vertex numbering as refine_uniform's last level), their positions,
/// the sharpness left as crease and corner tags, and the cage's scheme tags. Each level's
/// stencils are built chunk by chunk, applied at once and dropped, and only one level's
/// adjacency lives at a time, so peak memory is about the output mesh plus the level before it
/// (the 800k-quad terrain at level 4, 205M quads, fits on a 24 GB machine). 0 <= depth <= 8;
/// throws InputError like refine_uniform. Multi-threaded (TBB).
Mesh subdivide_uniform(const Mesh& cage, int depth, const SubdivOptions& options,
                       SubdivideStats* stats = nullptr);

/// Refines `cage` uniformly `depth` times (0 <= depth <= 8), and each face-varying channel with
/// it under options.face_varying (seams, corners and creases of the channel's own topology as
/// OpenSubdiv refines them). Throws InputError for cages limn cannot subdivide (see the note on
/// non-manifold input in the implementation) and for channels with the wrong corner count or an
/// index past value_count. Memory and time grow 4x per level.
UniformRefinement refine_uniform(const Mesh& cage, int depth, const SubdivOptions& options,
                                 std::span<const FaceVaryingInput> face_varying = {});

}  // namespace limn
