// limn simplify: the local greedy optimiser of Jin, Wu, Liu (sec. 3.2-3.3).
//
// For a cluster-boundary edge between T_m in C_k and T_n in C_l there are three states: as is,
// T_n moved into C_k, or T_m moved into C_l. S_k + S_l is the same in all three, so the best is
// the one with the largest |N_k| + |N_l|; a move is taken only when it lowers E. A move that would
// empty or disconnect the face's cluster is refused. Work is driven by a queue of edges: a move
// queues the edges around the moved face, and when the queue runs dry only the boundary edges of
// clusters whose sums changed since the edge was last looked at are queued again, so quiet
// regions are never swept. It stops when no boundary edge has a move that lowers E: a local
// minimum of E over single-face boundary moves.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "limn/simplify/vsa.hpp"

namespace limn {

/// Greedy optimiser state over a partition: the boundary-edge list, the queue and the
/// per-edge and per-cluster stamps that tell which edges are stale. The partition is referenced,
/// not copied; callers may relabel faces between runs and report them with `touch`.
class GreedyOptimizer {
 public:
  /// Precondition: every face is assigned and every cluster edge-connected. Queues every
  /// boundary edge. O(corners).
  GreedyOptimizer(const VsaSurface& s, Partition& p, GreedyOptions options = {});

  /// Runs until no boundary move lowers E. Time about O(boundary edges x rounds + moves).
  GreedyStats run();

  /// The pair of edge-adjacent clusters, neither of them `exclude`, whose merge would raise E
  /// least (merge_cost); {kNone, kNone} when there is none. O(boundary edges).
  std::pair<uint32_t, uint32_t> cheapest_merge(uint32_t exclude, double* cost);

  /// Starts recording accepted moves, so that `rollback` can undo them. O(1).
  void begin_journal();
  /// Undoes every move recorded since begin_journal and stops recording. Cluster sums take the
  /// reverse moves (round-off aside, they return to their old values). O(moves recorded).
  void rollback();
  /// Stops recording and keeps the moves. O(1).
  void end_journal();

  /// Tells the optimiser that these faces changed cluster outside it (e.g. a split): queues their
  /// edges and marks their clusters changed. O(faces given).
  void touch(std::span<const uint32_t> faces);

 private:
  bool boundary(uint32_t c) const;
  void push(uint32_t c);
  void evaluate(uint32_t c);
  double gain(uint32_t f, uint32_t to) const;
  bool removable(uint32_t f);
  bool fan_in_cluster(uint32_t from_corner, uint32_t to_corner, uint32_t l) const;
  bool search_connected(uint32_t f, uint32_t l, std::span<const uint32_t> targets);
  void apply(uint32_t f, uint32_t to, double drop);
  void grow_clusters();
  void refresh_norms();

  const VsaSurface& s_;
  Partition& p_;
  GreedyOptions o_;
  GreedyStats st_;
  std::vector<uint32_t> queue_;  // corners; FIFO from head_
  size_t head_ = 0;
  std::vector<uint32_t> list_;            // corners of (once) boundary edges, compacted per round
  std::vector<uint8_t> queued_, listed_;  // per edge
  std::vector<uint32_t> edge_stamp_;      // per edge: clock when last scored
  std::vector<uint32_t> cluster_stamp_;   // per cluster: clock of its last change
  std::vector<uint32_t> checked_at_;      // per cluster: clock when its boundary was last queued
  std::vector<double> checked_normal_;    // 3 per cluster: its proxy normal then
  std::vector<uint8_t> stale_;
  std::vector<double> norm_;  // per cluster: |N|, kept with every move
  uint32_t clock_ = 1;
  std::vector<uint32_t> visit_;  // per face: search generation
  std::vector<uint8_t> owner_;   // per face: the search wave that reached it
  uint32_t generation_ = 0;
  std::vector<std::vector<uint32_t>> waves_;
  std::vector<size_t> heads_;
  std::vector<uint8_t> parent_;
  bool journaling_ = false;
  std::vector<std::pair<uint32_t, uint32_t>> journal_;  // (face, cluster it left)
};

/// Convenience: builds an optimiser and runs it once.
GreedyStats greedy_optimize(const VsaSurface& s, Partition& p, const GreedyOptions& options = {});

}  // namespace limn
