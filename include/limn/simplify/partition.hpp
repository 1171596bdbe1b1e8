// limn simplify: a partition of a mesh's faces into clusters, with the L2,1 energy kept current.
//
// Energy (Cohen-Steiner et al. 2004; Jin, Wu, Liu, eq. 7): with unit face normals n_j and areas
// a_j, a cluster C_i has S_i = sum a_j and N_i = sum a_j n_j, and
//   E = sum_i sum_{j in C_i} a_j |n_j - N_i/|N_i||^2 = sum_i 2 (S_i - |N_i|).
// Keeping S_i and N_i per cluster makes the energy change of moving one face O(1).
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "limn/simplify/surface.hpp"

namespace limn {

/// Label of a face that belongs to no cluster yet.
inline constexpr uint32_t kUnassigned = kNone;

struct Partition {
  std::vector<uint32_t> label;     ///< cluster per face, or kUnassigned
  std::vector<double> S;           ///< per cluster: area
  std::vector<double> N;           ///< 3 per cluster: sum of face vector areas
  std::vector<uint32_t> size;      ///< per cluster: number of faces
  std::vector<uint32_t> any_face;  ///< per cluster: one of its faces (kNone when empty)

  size_t cluster_count() const { return S.size(); }
  /// |N_k|. O(1).
  double norm(uint32_t k) const {
    const double* n = &N[3 * size_t(k)];
    return std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  /// 2 (S_k - |N_k|), in squared model units; never negative. O(1).
  double cluster_energy(uint32_t k) const { return std::max(0.0, 2.0 * (S[k] - norm(k))); }
  /// Sum of cluster energies. O(clusters).
  double energy() const;
  /// Unit proxy normal N_k/|N_k| (zero for a cluster of zero area). O(1).
  void proxy_normal(uint32_t k, double out[3]) const;

  /// Appends an empty cluster; returns its id. Amortised O(1).
  uint32_t add_cluster();
  /// Puts unassigned face f into cluster k. O(1).
  void assign(const VsaSurface& s, uint32_t f, uint32_t k);
  /// Moves face f from its cluster to cluster k, updating both clusters' sums. Precondition: f's
  /// cluster keeps another face edge-adjacent to f or becomes empty. O(arity).
  void move(const VsaSurface& s, uint32_t f, uint32_t k);
  /// Recomputes every sum from the labels (drops accumulated round-off). O(faces + clusters).
  void recompute(const VsaSurface& s);
};

/// A partition with `clusters` clusters (labels in [0, clusters) or kUnassigned) and its sums.
/// O(faces + clusters).
Partition partition_from_labels(const VsaSurface& s, std::span<const uint32_t> labels,
                                size_t clusters);

}  // namespace limn
