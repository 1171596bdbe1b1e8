// How the refiner reads and writes the octree's nodes during a run, so that a run on several
// threads leaves the pool exactly as one thread would: on one thread, nodes are encoded
// (octree_blocks.hpp) and stored in the pool at once; on several, each task records its stores
// and releases in a log of its own, a stored block named by a temporary address until the end of
// the run, when the logs are replayed in the order one thread makes the writes. Internal header
// of the paint layer.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <tbb/concurrent_vector.h>

#include "octree_blocks.hpp"

namespace limn::detail {

/// Objects kept for reuse, taken and given back from any thread.
template <class T>
struct SharedPool {
  std::mutex m;
  std::vector<std::unique_ptr<T>> all;
  std::vector<T*> free;
  T& take() {
    std::lock_guard<std::mutex> lock(m);
    if (free.empty()) return *all.emplace_back(std::make_unique<T>());
    T* x = free.back();
    free.pop_back();
    return *x;
  }
  void put(T& x) {
    std::lock_guard<std::mutex> lock(m);
    free.push_back(&x);
  }
};

/// One task's pool writes in order, a child task's log hung into its parent's at the join in
/// child order.
struct WriteLog {
  enum Kind : uint8_t { kStore, kRelease, kChild };
  struct Op {
    Kind kind;
    bool brick;
    uint8_t generals, bricks;  ///< a general node's child pointer words (pairs, then bricks)
    uint32_t ptr, old_n;       ///< the block replaced or released (0: none), its size
    uint32_t off, n;           ///< the new block's words in `words`; kChild: children[off]
    uint32_t temp;             ///< the new block's temporary address
  };
  std::vector<Op> ops;
  std::vector<uint32_t> words;
  std::vector<WriteLog*> children;
  /// The log's share of temporary addresses not used yet: slots [next, end) of the run's
  /// table, taken a chunk at a time (one atomic step per chunk, not per store).
  uint32_t next = 0, end = 0;
  void clear() { ops.clear(), words.clear(), children.clear(), next = end = 0; }
};

/// One task's side of the writes: its log (null: straight to the pool) and its encoder's words.
struct TaskWrites {
  WriteLog* log = nullptr;
  std::vector<uint32_t> words;
};

/// A run's node reads and writes on one texture. Reads see the pool as it was at the run's start
/// plus what the reading task's log (and those it has joined) stored.
class NodeWrites {
 public:
  explicit NodeWrites(OctreeTexture& t) : ed_(t) {}
  ~NodeWrites() { give_back(); }
  NodeWrites(const NodeWrites&) = delete;
  NodeWrites& operator=(const NodeWrites&) = delete;

  OctreeEditor& editor() { return ed_; }
  const OctreeEditor& editor() const { return ed_; }

  /// Starts a run: with `logged`, the run's writes go to logs (the first: main_log()) until
  /// finish(). Gives back the logs of a run a throw cut short.
  void begin(bool logged);
  /// Whether temporary addresses have room above the pool (a logged run needs it).
  bool room_for_log() const { return ed_.pool().size() < octree::kMaxPoolWords / 2; }
  WriteLog* main_log() { return &main_log_; }
  /// Replays a logged run's writes in order into the pool; returns `root_ptr`'s real address.
  /// Unlogged: returns root_ptr.
  uint32_t finish(uint32_t root_ptr);
  /// The run's logs back to the shared pool (once replayed, or after a throw).
  void give_back();

  /// `count` fresh logs for child tasks (any thread).
  void take_logs(int count, WriteLog* out[]);
  /// Hangs child tasks' logs into their parent's, after what the parent wrote so far.
  static void join(WriteLog& parent, WriteLog* const children[], int count);

  /// Encodes and stores a node; returns (ptr, info). `old_ptr` 0: new.
  void store_general(TaskWrites& w, const GeneralNode& n, uint32_t old_ptr, uint32_t old_info,
                     uint32_t& ptr, uint32_t& info);
  /// Encodes and stores a brick in place of `old_word`'s block (0: new), `old` its cells as
  /// decoded (their size; null with old_word 0); returns the brick's word.
  uint32_t store_brick(TaskWrites& w, const Brick& b, uint32_t old_word, const Brick* old);
  /// Frees a block (logged: at the replay).
  void release(TaskWrites& w, uint32_t ptr, uint32_t n, bool brick);
  /// The words holding block `ptr` (pool or log) and the block's position in them.
  std::span<const uint32_t> block(const TaskWrites& w, uint32_t ptr, uint32_t& at) const;
  /// The average colour of n's cell c (a general node's or a brick's stored average; 0 else).
  Rgba8 child_avg(const TaskWrites& w, const GeneralNode& n, int c) const;
  /// The average colour of a node from its cells'.
  Rgba8 general_avg(const TaskWrites& w, const GeneralNode& n) const;

 private:
  /// ed_.replace_block with w's words, or its record in w's log (a temporary address).
  uint32_t put_block(TaskWrites& w, uint32_t old_ptr, uint32_t old_n, bool brick, int generals,
                     int bricks);
  /// Makes the log's writes in order, its children's where they hang.
  void replay(WriteLog& log);
  /// A temporary address's real one once replayed (real ones as they are).
  uint32_t resolve(uint32_t p) const { return p >= temp0_ ? real_[p - temp0_] : p; }
  uint32_t resolve_brick(uint32_t word) const {
    return resolve(word & ~octree::kBrickDoubleFlag) | (word & octree::kBrickDoubleFlag);
  }
  /// Where a temporary address's block is: its log and op.
  struct Where {
    const WriteLog* log = nullptr;
    uint32_t op = 0;
  };
  static constexpr uint32_t kTempChunk = 32;

  OctreeEditor ed_;
  bool logged_ = false;
  WriteLog main_log_;
  uint32_t temp0_ = 0;  // the pool's size at the run's start: temporary addresses start there
  tbb::concurrent_vector<Where> where_;  // per temporary address
  std::mutex logs_mutex_;
  std::vector<WriteLog*> taken_logs_;  // the run's task logs, given back after the replay
  std::vector<uint32_t> real_;         // per temporary address, its block's address once replayed
};

}  // namespace limn::detail
