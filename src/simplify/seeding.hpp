// limn simplify: initial partitions for VSA.
//
// Adaptive seeding (Jin, Wu, Liu sec. 4): each face gets the mean |K| of its vertices (Meyer et
// al. Gaussian curvature); the budget per cluster is D = (1/K) sum a_j |K(T_j)|. A cluster grows
// from an unassigned seed face, taking adjacent unassigned faces in order of |n(T) - n_C| (n_C
// its current proxy normal), until its integrated |K| exceeds D; it then still takes faces whose
// deviation is below a small threshold, so a plane becomes one cluster. Seeds are picked at
// random (seeded, reproducible) among unassigned faces until K clusters exist or every face is
// taken; the greedy optimiser absorbs what is left.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "limn/simplify/vsa.hpp"

namespace limn {

/// Seeds a partition; faces may be left unassigned (see absorb_unassigned). O(F log F).
Partition seed_partition(const VsaSurface& s, const SeedingOptions& options,
                         SeedingStats* stats = nullptr);

/// Assigns every unassigned face: regions flood outwards from assigned faces in order of the
/// L2,1 error a |n(T) - n_C|^2 against each cluster's proxy normal (Cohen-Steiner et al.'s
/// flooding). A component of the mesh that holds no cluster gets a new cluster of its own.
/// Returns the number of clusters added. Clusters stay edge-connected. O(F log F).
size_t absorb_unassigned(const VsaSurface& s, Partition& p);

/// Floods unassigned faces from the assigned ones with fixed proxy normals (3 per cluster),
/// lowest L2,1 error first. Faces no assigned face reaches stay unassigned. O(F log F).
void flood_unassigned(const VsaSurface& s, Partition& p, std::span<const double> normals);

/// The same, growing only from the given (assigned) faces; costs O(n log n) in the n faces it
/// reaches, not O(F).
void flood_from(const VsaSurface& s, Partition& p, std::span<const uint32_t> sources,
                std::span<const double> normals);

}  // namespace limn
