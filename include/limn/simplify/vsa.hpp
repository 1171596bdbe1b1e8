// limn simplify: variational shape approximation end to end (Jin, Wu, Liu; Cohen-Steiner et al.).
//
// prepare_surface -> seed_partition -> absorb_unassigned -> greedy (or Lloyd) optimisation, with
// clusters split at the worst proxy until K is reached (or the error target met) -> polygonize.
// The options and counts of each stage are here; the stages themselves are internal
// (src/simplify/).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/simplify/partition.hpp"

namespace limn {

enum class SeedingMethod {
  curvature,  ///< Jin et al.'s adaptive, curvature-driven growth
  random,     ///< K random seed faces, regions flooded by normal deviation (for comparison)
};

struct SeedingOptions {
  SeedingMethod method = SeedingMethod::curvature;
  size_t clusters = 100;  ///< K, at least 1
  uint64_t seed = 1;      ///< random-number seed for the choice of seed faces
  /// |n(T) - n_C| below which a face still joins a cluster whose curvature budget is spent
  /// (0.035 is about 2 degrees).
  double planar_deviation = 0.035;
};

struct SeedingStats {
  size_t clusters = 0;   ///< clusters the seeding made (curvature seeding may make fewer)
  double budget = 0;     ///< D, in radians (integrated |K| per cluster)
  size_t left_over = 0;  ///< faces no cluster took during growth
};

struct GreedyOptions {
  /// A move is taken only when |N_k| + |N_l| grows by more than this times the moved face's area
  /// (so round-off cannot make two states alternate forever).
  double min_gain = 1e-10;
  /// Faces a connectivity check may visit when the O(1) test around the face is not conclusive;
  /// beyond it the move is refused (never risking a disconnected cluster).
  uint32_t search_budget = 32;
  /// Once the queue runs dry, a cluster's boundary edges are scored again only when its proxy
  /// normal has turned by more than this (about radians) since they were last all queued (edges
  /// next to a move are always scored again). A move that turn could have made worthwhile lowers
  /// E by at most about 4 x drift x the face's area; 0: every change counts, and the result is an
  /// exact local minimum.
  double drift = 1e-2;
  /// Debug hook, called after every accepted move with the face, its old and new cluster and the
  /// predicted drop of E (squared model units). Tests use it to check every move lowers E.
  std::function<void(uint32_t face, uint32_t from, uint32_t to, double drop)> on_move;
};

struct GreedyStats {
  size_t moves = 0;               ///< accepted moves
  size_t evaluations = 0;         ///< boundary edges scored
  size_t rounds = 0;              ///< times the queue ran dry and stale edges were queued again
  size_t local_checks = 0;        ///< connectivity decided by looking around the face (O(1))
  size_t search_checks = 0;       ///< connectivity decided by a bounded search
  size_t refused_disconnect = 0;  ///< improving moves refused: they would split a cluster
  size_t refused_budget = 0;      ///< improving moves refused: the search ran out of budget
  double energy_before = 0, energy_after = 0;
};

struct LloydOptions {
  size_t iterations = 30;        ///< at most this many partition + fit iterations
  bool stop_when_stable = true;  ///< stop early when an iteration changes no label
};

struct LloydStats {
  size_t iterations = 0;       ///< iterations run
  std::vector<double> energy;  ///< E after each iteration
};

struct MeshingOptions {
  /// Chains are split at their farthest vertex P while d(P, AB)/|AB| exceeds this.
  double split_threshold = 0.5;
  /// One polygon per cluster (a cluster with holes: one per piece its bridges cut it into;
  /// a polygon with a repeated vertex or no area comes out as triangles); false: triangles.
  bool polygons = false;
};

struct MeshingStats {
  size_t anchors = 0;         ///< vertices where chains meet (including forced ones)
  size_t forced_anchors = 0;  ///< anchors added on loops that had none
  size_t chains = 0;
  size_t kept_vertices = 0;   ///< output vertices
  size_t forced_splits = 0;   ///< chain splits beyond the threshold, for validity
  size_t bridges = 0;         ///< edges cutting a cluster with holes into simple polygons
  size_t polygons = 0;        ///< polygons written as one face (polygon output)
  size_t triangulated = 0;    ///< polygons written as triangles by the dynamic programme
  size_t fans = 0;            ///< clusters fanned from an interior vertex instead
  size_t cluster_splits = 0;  ///< clusters split because nothing else gave a valid mesh
};

struct SimplifiedMesh {
  Mesh mesh;                            ///< the output (positions are input positions)
  std::vector<uint32_t> face_cluster;   ///< per output face: its cluster
  std::vector<uint32_t> vertex_source;  ///< per output vertex: the input vertex it copies
  MeshingStats stats;
};

enum class VsaMethod {
  greedy,  ///< Jin et al.'s local greedy optimiser (the default)
  lloyd,   ///< Cohen-Steiner et al.'s Lloyd iterations (the baseline)
};

struct VsaOptions {
  size_t proxies = 100;  ///< K, the number of clusters (polygons) wanted
  /// > 0: keep adding proxies (splitting the worst cluster) until E / total area <= this; the
  /// seeding then starts from `proxies` clusters.
  double target_error = 0;
  size_t max_proxies = 0;  ///< cap for target_error (0: a third of the faces)
  /// Curvature seeding can make fewer than K clusters; true splits the worst clusters until K is
  /// reached (false: Jin et al.'s rule, K becomes the number reached).
  bool fill = true;
  /// After the greedy optimiser converges, up to this many "teleports" (after Cohen-Steiner et
  /// al. sec. 3.4): the two adjacent clusters whose merge raises E least are merged and the
  /// worst cluster is split, the optimiser runs, and the result is kept only if E dropped (else
  /// undone; three failures in a row end it). 0 is Jin et al.'s method as published. Greedy
  /// method only.
  size_t teleports = 16;
  VsaMethod method = VsaMethod::greedy;
  SeedingOptions seeding;  ///< its `clusters` is overwritten by `proxies`
  GreedyOptions greedy;
  LloydOptions lloyd;
  MeshingOptions meshing;
};

struct VsaStats {
  size_t seeded = 0;              ///< clusters the seeding made
  size_t component_clusters = 0;  ///< clusters added for mesh components without one
  size_t split_clusters = 0;      ///< clusters added by splits (fill or error target)
  size_t teleports = 0;           ///< merge + split pairs taken
  size_t clusters = 0;            ///< K reached by the partition (before meshing)
  double energy = 0;              ///< E of the partition, squared model units
  double total_area = 0;
  SeedingStats seeding;
  GreedyStats greedy;  ///< accumulated over all greedy runs
  LloydStats lloyd;
  double prepare_ms = 0, seeding_ms = 0, optimise_ms = 0, meshing_ms = 0;
};

/// The optimised partition of a prepared surface. O(F log F) for seeding, then greedy or Lloyd.
Partition vsa_partition(const VsaSurface& s, const VsaOptions& options, VsaStats* stats = nullptr);

struct VsaResult {
  SimplifiedMesh output;         ///< the mesh, per-face clusters, per-vertex sources
  std::vector<uint32_t> labels;  ///< per input face: its cluster (after any meshing splits)
  VsaStats stats;                ///< stats.clusters counts clusters after meshing splits
};

/// Simplifies `mesh`. Throws InputError (naming `name`) for input VSA cannot take: see
/// prepare_surface. Time about O(F log F) plus the meshing.
VsaResult simplify_vsa(const Mesh& mesh, const VsaOptions& options, std::string_view name = "mesh");

}  // namespace limn
