// limn subdiv: feature-adaptive patch tables (FAS, Niessner et al. 2012) with a depth per vertex
// (Lin et al. 2018), and their evaluation.
//
// A patch table covers the limit surface of a Catmull-Clark cage with patches of two kinds:
// - regular: a bicubic B-spline patch of 16 points, exact wherever its face and 1-ring are
//   regular; boundary and corner patches are regular patches whose missing row or column is
//   extrapolated (bit e of PatchParam::boundary, the edge-e convention below);
// - gregory: an end cap (Loop, Schaefer, Ni, Castano 2009, "Approximating subdivision surfaces
//   with Gregory patches for hardware tessellation"), 20 points, around whatever a regular patch
//   cannot express at the depth reached (extraordinary vertices, creases, corners); built like
//   OpenSubdiv's Far GREGORY_BASIS end caps, so the two agree at the same isolation depth.
// Faces are refined around irregular features level by level (refine_sparse) until each
// feature's own depth: every extraordinary vertex may stop at a different level.
//
// Parameterisation (OpenSubdiv's Ptex convention): every cage quad is one ptex face, every other
// cage face gives one ptex face per corner (its level-1 quads). A patch covers the square
// [u, u + 2^-depth] x [v, v + 2^-depth] of its ptex face, in units of 2^-depth. Patch edge e
// runs from patch corner e to corner e + 1: edge 0 is v = 0, 1 is u = 1, 2 is v = 1, 3 is u = 0.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {

/// single_crease: a regular patch (in the regular arrays) with one semi-sharp crease along its
/// edge PatchParam::crease_edge, evaluated exactly (Niessner, Loop, Greiner 2012: across the
/// crease the patch is the limit of a cubic curve with a semi-sharp vertex).
enum class PatchType : uint8_t { regular = 0, gregory = 1, single_crease = 2 };

/// Where a patch lies and how it meets its neighbours. 24 bytes, for GPU buffers as is.
struct PatchParam {
  uint32_t ptex = 0;       ///< ptex face
  uint16_t u = 0, v = 0;   ///< origin in the ptex face, in units of 2^-depth
  uint8_t depth = 0;       ///< depth in the ptex face (level, less one under a non-quad face)
  uint8_t level = 0;       ///< refinement level the patch's points come from
  uint8_t boundary = 0;    ///< bit e: edge e is on the boundary (regular patches)
  uint8_t transition = 0;  ///< bit e: edge e borders finer patches (split it when tessellating)
  uint32_t base_face = 0;  ///< cage face
  PatchType type = PatchType::regular;
  uint8_t corner = 0;       ///< under a non-quad cage face: which corner's ptex face; else 0
  uint8_t crease_edge = 0;  ///< single_crease: the edge the crease runs along
  uint8_t reserved = 0;
  float sharpness = 0;  ///< single_crease: the crease's sharpness at the patch's level
};
static_assert(sizeof(PatchParam) == 24, "PatchParam is uploaded to GPUs as is");

struct PatchOptions {
  SubdivOptions subdiv;
  /// Isolation depth (FAS's L, OpenSubdiv's adaptive isolation level) of every irregular
  /// feature when no per-vertex depth is given; the cap of per-vertex depths otherwise. 0-12.
  int depth = 3;
  /// Infinitely sharp creases and corners become regular boundary and corner patches where the
  /// faces between them are regular (OpenSubdiv's useInfSharpPatch), instead of isolating them
  /// to `depth` like other features: fewer patches, and exact.
  bool inf_sharp_patches = true;
  /// A regular face with one semi-sharp crease along an edge (sharpness the same along the crease
  /// through its 4 x 4 points) becomes one exact single-crease patch instead of being isolated
  /// until the sharpness decays (OpenSubdiv's useSingleCreasePatch).
  bool single_crease_patches = true;
  /// Cages of more faces are isolated region by region, each region about this many faces with
  /// its neighbourhood (0: regions of 16384 faces, for cages of more than 32768): the working
  /// memory is a region's, not a whole level's, and regions are isolated in parallel (TBB; the
  /// table is the same for any thread count). The patches are the same as a whole-cage build's;
  /// points that patches on both sides of a region border use are stored once per region.
  uint32_t batch_faces = 0;
};

/// Counts and timings of one build.
struct PatchStats {
  std::vector<size_t> regular_by_level, gregory_by_level;  ///< patches per refinement level
  size_t points = 0;      ///< refined points (all levels) plus end-cap points
  double refine_ms = 0;   ///< sparse refinement with classification
  double patches_ms = 0;  ///< gathering patch points and end-cap stencils
                          ///< (region builds: both summed over the regions' threads)
};

/// Flat, GPU-ready patch table. Points are numbered globally: the cage's, then each refined
/// level's points (level_offsets[k] is the first of level k), then the end-cap corner points
/// (P, Ep, Em: one per corner fan and edge, shared by the end caps meeting there), then the
/// end-cap face points (Fp, Fm, over corner points and ring points). A level
/// keeps only the refined points that patches use, directly or through the next level's
/// stencils (in the refinement's order), so its stencils are no more than drawing needs.
struct PatchTable {
  SubdivOptions options;
  std::vector<uint32_t> level_offsets;       ///< first point of each level; back() = end-cap base
  std::vector<StencilTable> level_stencils;  ///< level k-1 local points -> level k local points
  StencilTable gregory_stencils;             ///< refined points -> end-cap corner points
  StencilTable gregory_face_stencils;        ///< refined and corner points -> face points
  std::vector<uint32_t> regular_points;      ///< 16 per regular patch, row-major (4 v + u)
  std::vector<uint32_t> gregory_points;      ///< 20 per end cap (corner i: P, Ep, Em, Fp, Fm)
  std::vector<PatchParam> regular_params, gregory_params;
  uint32_t ptex_count = 0;
  std::vector<uint32_t> ptex_of_face;  ///< first ptex face of each cage face (size faces + 1)
  bool selection = false;              ///< made by select_patches: its points are the hierarchy's

  size_t point_count() const {
    return level_offsets.back() + gregory_stencils.size() + gregory_face_stencils.size();
  }
  size_t patch_count() const { return regular_params.size() + gregory_params.size(); }
  /// Every point (3 floats each) from the cage positions: refinement level by level, then the
  /// end-cap points. O(stencil entries). Throws InputError for a selection (use its
  /// hierarchy's table).
  std::vector<float> points(std::span<const float> cage_positions) const;
  /// The same into `out` (3 * point_count() floats), for callers that recompute the points
  /// every frame: no allocation, and no fresh pages to fault in (on the 800k-quad dense torus,
  /// 15M points, the fresh vector's page faults and zero fill cost several times the stencils).
  void points(std::span<const float> cage_positions, std::span<float> out) const;
};

/// Builds the patch table. vertex_depth (empty, or one entry per cage vertex, each 0-16) gives
/// each vertex its own isolation depth; empty means options.depth everywhere (classic FAS). A
/// face is refined at level k when it has an irregular corner whose depth is not yet reached;
/// new points inherit depth from what they come from (vertex points from their vertex, edge and
/// face points the largest of their ends). Non-quad cage faces are always refined once.
/// O(patches * ring size); throws InputError for cages limn cannot subdivide.
PatchTable build_patches(const Mesh& cage, const PatchOptions& options,
                         std::span<const uint8_t> vertex_depth = {}, PatchStats* stats = nullptr);

/// PatchHierarchy::node_patch of an end cap: this bit | its index among the end caps.
inline constexpr uint32_t kPatchGregory = 0x80000000u;

/// Every patch a cage can need down to a depth, as a tree per cage face (OpenSubdiv's Bfr patch
/// trees, Brainerd et al. 2016): the patch table of depth d_max everywhere plus, at every level,
/// a patch (an end cap) over each face that goes deeper. A new view then only selects nodes
/// (select_patches): nothing is refined again and no stencil is rebuilt.
struct PatchHierarchy {
  PatchTable table;             ///< every node's patch; its points serve every selection
  std::vector<uint32_t> roots;  ///< the node of each covered cage face
  std::vector<uint8_t> node_level, node_force;  ///< force: always refined (non-quads)
  std::vector<uint32_t> node_patch;  ///< regular index, or kPatchGregory | end-cap index; or kNone
  std::vector<uint32_t> node_first_child;  ///< children are consecutive; kNone for leaves
  std::vector<uint32_t> node_children;
  std::vector<uint32_t> node_neighbours;  ///< 4 per node: the node across each patch edge
  std::vector<uint32_t> node_src_offsets{0}, node_src;  ///< cage vertices whose depth refines it
  size_t node_count() const { return node_level.size(); }
};

/// Builds the hierarchy down to options.depth (d_max). About build_patches' cost at that depth
/// plus one end cap per refined face.
PatchHierarchy build_patch_hierarchy(const Mesh& cage, const PatchOptions& options);

/// The patches of a per-vertex depth (one entry per cage vertex, capped at the hierarchy's
/// depth): the same patches, transition bits included, as build_patches(cage, {depth = d_max},
/// vertex_depth). The result has the patch arrays only (no stencils): evaluate it with
/// hierarchy.table.points(). O(nodes visited), no refinement.
PatchTable select_patches(const PatchHierarchy& hierarchy, std::span<const uint8_t> vertex_depth);

/// A point on a patch: which patch (regular first, then end caps: index regular_params.size() +
/// i is end cap i) and patch-local (s, t) in [0, 1]^2.
struct PatchCoord {
  uint32_t patch = 0;
  float s = 0, t = 0;
};

/// Finds patches by ptex coordinates: a quadtree per ptex face.
class PatchMap {
 public:
  explicit PatchMap(const PatchTable& table);
  /// The patch over ptex face `ptex` at (u, v) in [0, 1]^2, with its local coordinates.
  /// O(depth). Throws InputError for a ptex face out of range.
  PatchCoord find(uint32_t ptex, double u, double v) const;

 private:
  struct Node {
    uint32_t child[4];  // high bit set: a patch; else a node; kNone: nothing
  };
  std::vector<Node> nodes_;  // nodes_[ptex] is the root of ptex face ptex
  std::vector<uint8_t> depth_;
  const PatchTable* table_;
};

/// A point of a ptex face: (u, v) in [0, 1]^2.
struct PtexCoord {
  uint32_t ptex = 0;
  float u = 0, v = 0;
};

/// Where patch coordinate c lies on its ptex face. O(1).
PtexCoord ptex_coord(const PatchTable& table, const PatchCoord& c);

/// Face-varying values (UVs) interpolated linearly, FVarInterpolation::all (OpenSubdiv's default;
/// its face-varying patches are then bilinear at every depth): over a cage quad, bilinear in its
/// corners' values; over a non-quad face's corner ptex face, bilinear in that corner's value,
/// the midpoints of its two edges and the face's mean. `width` (1-4) floats per value, indexed
/// by channel.corner_values; du/dv (when not null) per ptex unit. Throws InputError for a ptex
/// face out of range or a channel of the wrong size. O(log faces) per coordinate.
void evaluate_linear_face_varying(const Mesh& cage, const FaceVaryingInput& channel,
                                  const float* values, int width, std::span<const PtexCoord> coords,
                                  float* out, float* du = nullptr, float* dv = nullptr);

/// The four corners of each ptex face's bilinear map that evaluate_linear_face_varying
/// interpolates: per ptex face (PatchTable::ptex_of_face's order), the values at (0,0), (1,0),
/// (1,1), (0,1), `width` floats each (what a GPU needs to draw linear UVs). O(corners).
std::vector<float> ptex_corner_values(const Mesh& cage, const FaceVaryingInput& channel,
                                      const float* values, int width);

/// A face-varying channel's own patches beside a vertex patch table, for the interpolation modes
/// other than FVarInterpolation::all (OpenSubdiv's face-varying patch tables with
/// generateFVarLegacyLinearPatches off): at the level and place of every vertex patch, a regular
/// B-spline patch where the channel's topology is regular there (boundary edges along seams) and
/// a Gregory end cap where it is not. The channel does not drive isolation (as Far without
/// considerFVarChannels). For FVarInterpolation::all the table stays empty: values are bilinear
/// (evaluate_linear_face_varying).
struct FaceVaryingPatches {
  FVarInterpolation interpolation = FVarInterpolation::all;
  PatchTable table;  ///< over the channel's own points: its level 0 is one point per source entry
  std::vector<uint32_t> source;  ///< per level-0 point: the channel's value index it takes

  /// The table's points for components [first, first + min(3, width - first)) of the channel's
  /// values (`width` floats per value), as 3 floats per point (missing components 0), ready
  /// for evaluate_patches or a GPU upload. O(stencil entries). Throws InputError unless
  /// first < width.
  std::vector<float> points(const float* values, size_t width, size_t first = 0) const;
};

/// Builds the patches of `channel` for `table`, which build_patches or select_patches made from
/// `cage` with `options` (options.subdiv.face_varying picks the mode). About the cost of the
/// vertex table's build. Throws InputError for a channel of the wrong size, an index past its
/// values, or a table of another cage.
FaceVaryingPatches build_face_varying_patches(const Mesh& cage, const PatchTable& table,
                                              const FaceVaryingInput& channel,
                                              const PatchOptions& options);

/// Face-varying values (`width` 1-4 floats per value, indexed by channel.corner_values) at ptex
/// coordinates, with derivatives per ptex unit when du/dv are not null: through `patches`, or
/// bilinear for FVarInterpolation::all. O(stencil entries) to make the channel's points, then
/// O(depth) per coordinate. Throws InputError like evaluate_linear_face_varying.
void evaluate_face_varying(const Mesh& cage, const FaceVaryingInput& channel,
                           const FaceVaryingPatches& patches, const float* values, int width,
                           std::span<const PtexCoord> coords, float* out, float* du = nullptr,
                           float* dv = nullptr);

/// The face-varying values of evaluate_grids' points: an n x n grid over every ptex face, in
/// evaluate_grids' order (`width` floats per point: out holds width ptex_count n^2 floats),
/// derivatives per ptex unit when du/dv are not null. 2 <= n <= 65536. O(ptex_count n^2 depth).
void evaluate_face_varying_grids(const Mesh& cage, const FaceVaryingInput& channel,
                                 const FaceVaryingPatches& patches, const float* values, int width,
                                 int n, float* out, float* du = nullptr, float* dv = nullptr);

/// Evaluates limit positions (3 floats per coordinate) and, when du/dv are not null, the first
/// derivatives with respect to the ptex face's u and v (patch-local derivatives scaled by
/// 2^depth). `points` holds PatchTable::points(). Multi-threaded over coordinates (TBB).
void evaluate_patches(const PatchTable& table, std::span<const float> points,
                      std::span<const PatchCoord> coords, float* position, float* du = nullptr,
                      float* dv = nullptr);

/// Uniform tessellation's evaluation: an n x n grid over every ptex face (point (i, j) at
/// (i, j) / (n - 1)), written ptex face by face, row by row: point (f, i, j) is position[3 (f n^2
/// + j n + i)], derivatives in ptex units like evaluate_patches. Each patch evaluates the grid
/// points it holds (the rule of PatchMap::find), so no lookups; regular patches 8 points at once
/// (AVX2 where the CPU has it). Outputs hold 3 ptex_count n^2 floats. 2 <= n <= 65536.
/// O(ptex_count n^2), data-parallel over patches (TBB).
void evaluate_grids(const PatchTable& table, std::span<const float> points, int n, float* position,
                    float* du = nullptr, float* dv = nullptr);

}  // namespace limn
