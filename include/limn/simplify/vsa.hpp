// limn simplify: variational shape approximation end to end (Jin, Wu, Liu; Cohen-Steiner et al.).
//
// prepare_surface -> seed_partition -> absorb_unassigned -> greedy (or Lloyd) optimisation, with
// clusters split at the worst proxy until K is reached (or the error target met) -> polygonize.
#pragma once

#include <string_view>

#include "limn/simplify/cluster_edit.hpp"
#include "limn/simplify/greedy.hpp"
#include "limn/simplify/lloyd.hpp"
#include "limn/simplify/polygonize.hpp"
#include "limn/simplify/seeding.hpp"

namespace limn {

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
