// limn's jobs as the CLI runs them, on meshes in memory: option checks, the library calls in
// order, and the JSON report. The CLI adds files around them (read, write, --json); the Python
// module calls the same functions, so both take the same options and give the same results.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "limn/atlas/unwrap.hpp"
#include "limn/mesh/mesh.hpp"
#include "limn/paint/strokes.hpp"
#include "limn/simplify/vsa.hpp"
#include "limn/subdiv/depth.hpp"

namespace limn::jobs {

/// How option names appear in error messages: "--target-error" for the CLI, "target_error" for
/// Python keyword arguments.
enum class Names { cli, python };
/// `dashed` ("target-error") as the caller spells it.
std::string option_name(Names names, std::string_view dashed);

/// The camera of a view: `mesh` framed for a width x height image (frame_camera), with the eye,
/// target and fovy of `view` when given (its up and image size are not used).
Camera view_camera(const Mesh& mesh, int width, int height, const std::optional<Camera>& view);

/// `limn simplify`'s options (its defaults; names as its flags).
struct SimplifyJob {
  std::optional<size_t> proxies;       ///< none: 100, or 10 to start from with target_error
  std::optional<double> target_error;  ///< none: K proxies, no error target
  size_t max_proxies = 0;
  std::string method = "greedy", seeding = "curvature";
  uint64_t seed = 1;
  bool no_fill = false;
  size_t iterations = 30, teleports = 16;
  double split_threshold = 0.5;
  bool polygons = false;
  std::optional<size_t> distance;  ///< points sampled for the distance report; none: no report
};

/// Throws InputError naming the first bad option.
void check(const SimplifyJob& job, Names names);

struct SimplifyOutcome {
  VsaResult result;
  nlohmann::json report;  ///< reports::simplify_json + "distance", "valid", "timings_ms"
};

/// Simplifies `mesh` (named `name` in errors): VSA, the validity check (std::runtime_error when the
/// output is invalid: nothing must be written) and, when asked, the distance report.
SimplifyOutcome simplify(const Mesh& mesh, const SimplifyJob& job, std::string_view name);

/// `limn subdivide --uniform LEVEL [--limit]`: the lean path (only the last level kept), or with
/// `limit` every level refined (UVs as face-varying data) and pushed to the limit surface, with
/// limit normals, UVs and colours. Remaining sharpness comes out as crease and corner tags.
struct UniformOutcome {
  Mesh mesh;
  /// level, limit, levels (per level: vertices, faces, edges, stencil entries), the output's
  /// vertices and faces, timings_ms (per phase)
  nlohmann::json report;
};
/// InputError for a level outside 0-8 (checked before any work: no file needs reading first).
void check_uniform(int level, Names names);
/// InputError for a level outside 0-8 or an output past limn's size cap.
UniformOutcome subdivide_uniform(const Mesh& cage, int level, bool limit, std::string_view name,
                                 Names names);

/// `limn paint`: a stroke script run on `mesh` into `start` (continued) or a new texture with
/// `background`. The texture comes back compact (free blocks dropped, the undo history ended).
struct PaintOutcome {
  MaterialTexture texture;
  /// entries, strokes, dabs (missed), samples changed, leaves and bricks created, occlusion rays,
  /// ms per dab, threads, undos, redos, picks, the texture's stats, timings of the surface BVH,
  /// the texture and the painting
  nlohmann::json report;
};
/// InputError for a paint depth outside 1-octree::kMaxDepth.
void check_paint_depth(int depth, Names names);
/// Paints a new material (colour background `background`; RMH texture, when a channel is
/// painted, at `defaults`) or continues `start`.
PaintOutcome paint(const Mesh& mesh, const StrokeScript& script, Rgba8 background,
                   std::optional<MaterialTexture> start, const MaterialDefaults& defaults = {});

/// `limn unwrap`'s options (its defaults; names as its flags).
struct UnwrapJob {
  double max_stretch = UnwrapOptions{}.max_stretch;
  int size = UnwrapOptions{}.size;
  std::optional<double> texels_per_unit;  ///< none: the densest that fits
  int tiles = 1;
  int padding = UnwrapOptions{}.padding;
};

/// Throws InputError naming the first bad option.
void check(const UnwrapJob& job, Names names);

struct UnwrapOutcome {
  UnwrapResult result;
  /// charts, splits, tiles (UDIM numbers), size, texels_per_unit, utilization, stretch, the
  /// independent check of the layout (measure_uvs: flipped, overlapping texels, coverage), whether
  /// the input's UVs were replaced, timings_ms
  nlohmann::json report;
};

/// Unwraps `mesh` (named `name` in errors) and checks the layout; std::runtime_error when the
/// check finds a flipped triangle or overlapping charts (nothing must be written).
UnwrapOutcome unwrap(const Mesh& mesh, const UnwrapJob& job, std::string_view name);

}  // namespace limn::jobs
