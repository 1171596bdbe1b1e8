// Lazy refinement of the octree over a region of the surface, calling a painter on the leaves it
// reaches: the visit of the tree. The cells' boxes and lists are in cell_boxes.hpp, the node
// writes (straight or logged for a run on several threads) in node_writes.hpp, the lists kept
// across runs in kept_lists.hpp. Internal header of the paint layer.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <unordered_map>
#include <vector>

#include "cell_boxes.hpp"
#include "kept_lists.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "node_writes.hpp"
#include "octree_blocks.hpp"

namespace limn::detail {

/// What happens to a leaf cell at or below the target depth inside the region.
class LeafPainter {
 public:
  virtual ~LeafPainter() = default;
  static constexpr uint32_t kNoMemo = ~0u;
  /// `tris`: every triangle (sorted) meeting the cell; may change `cell` (samples, or add the
  /// back sample). `memo`: with Refiner::keep_brick_lists, a number the refiner gives a brick's
  /// leaf it visits (not one it builds), the same for that cell, with the same `tris`, in every
  /// run of that refiner and no other cell's painted through this painter; kNoMemo for other
  /// cells.
  virtual void paint(const CellBox& box, LeafCell& cell, std::span<const uint32_t> tris,
                     uint32_t memo) = 0;
  /// Finishes what `paint` left pending (cells painted since the last flush stay where they are
  /// until then). Called before a node's cells are stored or averaged.
  virtual void flush() {}
  /// Whether this painter paints through shards (below); false: the run stays on the calling
  /// thread and paints through this painter.
  virtual bool sharded() const { return false; }
  /// The painter of every cell inside the task cell `key` (level << 48 | Morton code, the same
  /// cells for the same key in every run at one depth; ~0: every cell, for runs too shallow for
  /// tasks), the same object for the same key for this painter's life, used by one thread at a
  /// time; the refiner asks on its calling thread. What paint() writes must not be shared
  /// between shards. Called only when sharded().
  virtual LeafPainter* shard(uint64_t /*key*/) { return this; }
};

struct RefineStats {
  size_t leaves_created = 0, bricks_created = 0, generals_created = 0, bricks_exploded = 0,
         bricks_compacted = 0, leaves_painted = 0;
  size_t tasks = 0, tasks_threaded = 0;  ///< task cells visited; of them, in parallel joins
};

class Refiner {
 public:
  Refiner(OctreeTexture& t, const PaintSurface& s);
  Refiner(const Refiner&) = delete;
  Refiner& operator=(const Refiner&) = delete;

  /// Refines every cell meeting `region` and touched by the surface down to level `depth`, then
  /// calls `painter` (may be null) on every leaf at level >= depth there. `tris`: a sorted list
  /// holding at least every triangle meeting a cell of the region at level >= depth - 2.
  /// With no painter or one that has shards (LeafPainter::shard), and depth > kTaskDepth, each
  /// cell of level depth - kTaskDepth is painted through its own shard, and on several threads
  /// the cells meeting the region are visited as tasks, siblings at once at every level down to
  /// those; their pool writes are replayed in the order one thread makes them (NodeWrites), so
  /// the texture comes out the same bit for bit on any number of threads (a whole-surface run
  /// holds its writes, about the pool's size again, until then). Precondition: 1 <= depth <=
  /// kMaxDepth.
  void run(const Region& region, std::span<const uint32_t> tris, int depth, LeafPainter* painter);

  /// The texture's cells as boxes against the surface.
  const CellBoxes& boxes() const { return boxes_; }

  /// Keeps, across runs (the dabs of a stroke), the triangle lists of the leaves of each brick
  /// run() visits (not those it builds), and uses them instead of splitting the brick's lists
  /// again when a later run wants no leaf of it the earlier ones did not. A leaf a run paints
  /// meets the region, so every triangle meeting it is in the run's list (see run()): its list,
  /// the triangles passing the same box tests from the root down, is the same in every run, so
  /// the results are the same bit for bit. Only for runs with the same depth over an unchanged
  /// mesh; off by default.
  void keep_brick_lists(bool on) { keep_ = on; }

  /// The triangles meeting the start cell (x, y, z) (level octree::kStartDepth) of this
  /// refiner's texture, sorted (StartLists), so that refining a start cell splits its list
  /// instead of querying the BVH for each child: the serial head of a dab on fresh surface.
  /// Precondition: prepare_start_lists() was called.
  std::span<const uint32_t> start_list(uint32_t x, uint32_t y, uint32_t z) const;
  /// Makes (or finds) that table now: run() does before a visit that may need it (its
  /// threads then only read it); OctreeTexture::create does, so a first dab does not.
  void prepare_start_lists() {
    if (!start_) start_ = StartLists::of(boxes_);
  }

  /// Levels from a task's cell to the leaves: a task cell holds 4 x 4 x 4 bricks' cells (16^3
  /// leaves), few enough tasks that a dab's per-task parts stay small, enough for two threads
  /// on a radius-16 dab (measured against 2 and 3 levels: both slower, 3 by 10-20% once the
  /// per-task work shrank).
  static constexpr int kTaskDepth = 4;

  RefineStats stats;

 private:
  /// Per node level, the lists a visit keeps while it recurses below.
  struct Scratch {
    std::vector<uint32_t> full;
    Split parts, full_parts;
  };
  /// A brick visited (or built) and painted whose rays may be in flight: averaged and stored
  /// by finish_bricks, so that the rays of a node's bricks go out together.
  struct PendingBrick {
    GeneralNode* n;  ///< its parent, slot c
    int c;
    bool fresh;  ///< built from a leaf (else `before` is the brick as it was)
    Brick b, before;
  };
  /// What one task's visit writes (a task runs on one thread at a time): its pending bricks,
  /// per level its lists, the brick builder's masks and lists, its node writes, counts; and the
  /// painter and kept lists of the task.
  struct Ctx {
    std::array<PendingBrick, 8> bricks;  // a node's children at most
    int pending = 0;
    std::array<Scratch, octree::kMaxDepth + 1> scratch;
    std::vector<uint64_t> masks;  // a brick's list's leaf masks (leaf_masks)
    LeafLists lists;              // a brick's leaves' lists
    TaskWrites out;               // out.log null: writes go to the pool
    RefineStats stats;
    LeafPainter* painter = nullptr;
    KeptBricks* kept = nullptr;
  };
  /// A task cell's own state across runs: its painter and kept lists.
  struct Shard {
    LeafPainter* painter = nullptr;
    KeptBricks kept;
  };

  /// `full` (may be null): every triangle meeting the node's box, when known (a node just made
  /// by refining): its children's lists are filtered from it instead of queried; then the
  /// node's scratch already holds full split by child (`full_parts`), as refine_leaf left it.
  /// `box` (may be null): the bounds of tris's corners, when known.
  void visit_general(Ctx& w, GeneralNode& n, const CellBox& nb, std::span<const uint32_t> tris,
                     const std::vector<uint32_t>* full = nullptr, const ListBox* box = nullptr);
  /// visit_general's work on child c (box cb, region list tc) of n: makes, refines, visits and
  /// stores it, writing only n's slot c. full_c: the child's full list when n was just refined;
  /// box_c: the bounds of tc's corners, when known.
  void visit_child(Ctx& w, GeneralNode& n, int c, const CellBox& cb, std::span<const uint32_t> tc,
                   const std::vector<uint32_t>* full_c, const ListBox* box_c);
  /// visit_child on the children in `todo` (bit c) of a node above the task cells (with
  /// `task_cells`, its children are task cells: each visited through its shard): at once on
  /// TBB's threads when writes are logged (a run on several threads) and there are several.
  /// `box`: the bounds of the children's lists when one child holds its parent's whole list.
  void visit_parts(Ctx& w, GeneralNode& n, const CellBox kids[8], uint32_t todo,
                   const Split& tparts, const Split* full_parts, bool task_cells,
                   const ListBox* box);
  /// Contexts of tasks, from a pool every refiner shares (kept warm across strokes: a click is a
  /// stroke of its own).
  static SharedPool<Ctx>& ctx_pool();
  static Ctx& take_ctx();
  /// Adds w's counts to the run's and gives it back.
  void put_ctx(Ctx& w);
  /// The task cell `key`'s shard (made on first use; any thread).
  Shard& shard(uint64_t key);
  /// Flushes the painter and averages and stores the pending bricks, in the order visited.
  void finish_bricks(Ctx& w);
  /// Paints b's leaves in the region, leaving the painter unflushed (see finish_bricks); b.avg
  /// is left for the caller (stale if a cell changed).
  void visit_brick(Ctx& w, Brick& b, const CellBox& bb, std::span<const uint32_t> tris);
  /// A new general node for the leaf cell `cb` (refined one level); leaves its full list split
  /// by child in cb's scratch (`full_parts`). `full` null: the children's lists come from the
  /// BVH instead (the same lists), at once on the threads with a log.
  GeneralNode refine_leaf(Ctx& w, const CellBox& cb, const LeafCell& leaf,
                          const std::vector<uint32_t>* full);
  /// A new brick for the leaf cell `cb` (two levels), visited at once: what make-then-visit
  /// did, with the region's lists taken from the full ones (`tris`, the region's list for cb,
  /// is a subset of `full`) instead of split again, the painter left unflushed and b.avg unset
  /// (see finish_bricks). False (b.mask 0) when no sub-cell meets the surface.
  bool build_brick(Ctx& w, const CellBox& cb, const LeafCell& leaf, std::span<const uint32_t> full,
                   std::span<const uint32_t> tris, Brick& b);
  GeneralNode explode(Ctx& w, const Brick& b);
  /// A general node whose cells are all leaf-only general nodes becomes a brick.
  bool try_compact(const Ctx& w, const GeneralNode& n, Brick& out) const;

  CellBoxes boxes_;
  NodeWrites writes_;
  const PaintSurface& s_;
  std::shared_ptr<const StartLists> start_;
  Region region_;
  int depth_ = 0;
  LeafPainter* painter_ = nullptr;
  bool keep_ = false;
  bool tasks_ = false;  // this run visits task cells (no painter or a sharded one; deep enough)
  std::mutex shard_mutex_, stats_mutex_;
  RefineStats task_stats_;  // every context's counts, added as each goes back
  KeptBricks kept_;         // without shards
  std::unordered_map<uint64_t, std::unique_ptr<Shard>> shards_;
};

}  // namespace limn::detail
