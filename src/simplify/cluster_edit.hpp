// limn simplify: edits of a partition's clusters (split, merge), for reaching K, meeting an
// error target and escaping the optimiser's local minima.
#pragma once

#include <cstdint>
#include <vector>

#include "limn/simplify/partition.hpp"

namespace limn {

/// The cluster with the largest energy among those with at least two faces, or kNone. O(K).
uint32_t worst_cluster(const Partition& p);

/// The faces of cluster k, by a search from p.any_face[k] (labels are borrowed as visit marks
/// and restored). O(|C_k|).
std::vector<uint32_t> cluster_faces(const VsaSurface& s, Partition& p, uint32_t k);

/// Splits cluster k in two edge-connected clusters: seeds at its face deviating most from its
/// proxy normal and at the face deviating most from that one, flooded by L2,1 error (the new
/// cluster is appended). Returns the new cluster's id, or kNone when k has fewer than two faces.
/// `faces` receives the faces of both. Precondition: no unassigned faces. O(|C_k| log |C_k|).
uint32_t split_cluster(const VsaSurface& s, Partition& p, uint32_t k,
                       std::vector<uint32_t>* faces = nullptr);

/// Moves every face of cluster `from` into cluster `into` (which must be edge-adjacent to it for
/// the result to stay connected); `from` is left empty. `faces` receives the moved faces.
/// O(|C_from|).
void merge_clusters(const VsaSurface& s, Partition& p, uint32_t into, uint32_t from,
                    std::vector<uint32_t>* faces = nullptr);

/// Increase of E if clusters k and l were merged: 2 (|N_k| + |N_l| - |N_k + N_l|). O(1).
double merge_cost(const Partition& p, uint32_t k, uint32_t l);

/// Drops the last cluster, which must be empty. O(1).
void pop_empty_cluster(Partition& p);

}  // namespace limn
