// Lazy refinement of the octree over a region of the surface, calling a painter on the leaves it
// reaches. Internal header of the paint layer.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <unordered_map>
#include <vector>

#include <tbb/concurrent_vector.h>

#include "geometry.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
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

/// A cell of the octree: its level, integer coordinates at that level, centre and half size.
struct CellBox {
  int level = 0;
  uint32_t x = 0, y = 0, z = 0;
  paint_detail::V3 c;
  float h = 0;
};

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

/// The bounds of a list's triangles' corners.
struct ListBox {
  float lo[3], hi[3];
};

/// Where to refine and paint: everywhere, or cells meeting a ball.
struct Region {
  bool everything = true;
  paint_detail::V3 c;
  float r = 0;
};

struct RefineStats {
  size_t leaves_created = 0, bricks_created = 0, generals_created = 0, bricks_exploded = 0,
         bricks_compacted = 0, leaves_painted = 0;
  size_t tasks = 0, tasks_threaded = 0;  ///< task cells visited; of them, in parallel joins
};

class Refiner {
 public:
  Refiner(OctreeTexture& t, const PaintSurface& s);
  ~Refiner() { give_back_logs(); }
  Refiner(const Refiner&) = delete;
  Refiner& operator=(const Refiner&) = delete;

  /// Refines every cell meeting `region` and touched by the surface down to level `depth`, then
  /// calls `painter` (may be null) on every leaf at level >= depth there. `tris`: a sorted list
  /// holding at least every triangle meeting a cell of the region at level >= depth - 2.
  /// With no painter or one that has shards (LeafPainter::shard), and depth > kTaskDepth, each
  /// cell of level depth - kTaskDepth is painted through its own shard, and on several threads
  /// the cells meeting the region are visited as tasks, siblings at once at every level down to
  /// those; their pool writes are replayed in the order one thread makes them, so the texture
  /// comes out the same bit for bit on any number of threads (a whole-surface run holds its
  /// writes, about the pool's size again, until then). Precondition: 1 <= depth <=
  /// kMaxDepth.
  void run(const Region& region, std::span<const uint32_t> tris, int depth, LeafPainter* painter);

  /// How far every box test grows a cell's box (model units): see the constructor.
  float slack() const { return slack_; }
  /// The box of a cell.
  CellBox box(int level, uint32_t x, uint32_t y, uint32_t z) const {
    CellBox b;
    b.level = level, b.x = x, b.y = y, b.z = z;
    const double s = cell_size(level);
    b.c = {centre(0, x, s), centre(1, y, s), centre(2, z, s)};
    b.h = float(0.5 * s);
    return b;
  }
  /// The triangles of `in` meeting the box (order kept).
  void filter(std::span<const uint32_t> in, const CellBox& b, std::vector<uint32_t>& out) const;
  /// The same for each of b's 8 children at once, for a list of triangles meeting b (as
  /// filter() decides; every list the refiner splits is one): a triangle whose bounding box
  /// lies on one child's side of b's three mid-planes (within the slack) goes to that child
  /// untested, as it meets the part of b's grown box on that side; one reaching several is
  /// tested against those (separating axes, 8 at once). out[c] is filter()'s list for child c
  /// but for triangles within rounding of its grown faces, kept.
  using Split = std::array<std::vector<uint32_t>, 8>;
  /// Only the children in `want` (bit c: child c) are tested; the others' lists come out empty.
  void split(std::span<const uint32_t> in, const CellBox& b, Split& out,
             uint32_t want = 0xffu) const;
  /// The same with b's children already at hand (`kids`, as children() gives them).
  void split(std::span<const uint32_t> in, const CellBox& b, const CellBox kids[8], Split& out,
             uint32_t want = 0xffu) const;
  /// A brick's two levels at once: masks[i], the leaves (bit 8 * c1 + c2: leaf c2 of child c1,
  /// Brick's numbering) among `want` that in[i] meets, for the brick cell `bb` (level depth - 2).
  /// Each leaf is tested once, from the triangle's axes taken from the brick's centre
  /// (TriAxes): the lists of a brick's leaves are the same whichever list of the brick's
  /// triangles they come from.
  void leaf_masks(std::span<const uint32_t> in, const CellBox& bb, uint64_t want,
                  std::vector<uint64_t>& masks) const {
    leaf_masks(in, bb, brick_leaves(bb), want, masks);
  }
  /// A brick's leaves (cells two levels below a cell): per axis the centres of the 4 leaves
  /// along it, as box() computes them; leaf m (8 * c1 + c2) has index (c1 >> a & 1) * 2 +
  /// (c2 >> a & 1) along axis a.
  struct BrickLeaves {
    float c[3][4];
    float h;
    int level;
    uint32_t base[3];
  };
  BrickLeaves brick_leaves(const CellBox& bb) const {
    BrickLeaves l;
    l.level = bb.level + 2;
    const double s = cell_size(l.level);
    l.base[0] = 4 * bb.x, l.base[1] = 4 * bb.y, l.base[2] = 4 * bb.z;
    for (int a = 0; a < 3; ++a)
      for (uint32_t k = 0; k < 4; ++k) l.c[a][k] = centre(a, l.base[a] + k, s);
    l.h = float(0.5 * s);
    return l;
  }
  static constexpr int leaf_index(int m, int a) { return (m >> (3 + a) & 1) * 2 + (m >> a & 1); }
  /// The box of leaf m: what child(child(bb, m >> 3), m & 7) gives.
  static CellBox leaf_box(const BrickLeaves& l, int m) {
    CellBox b;
    const int i = leaf_index(m, 0), j = leaf_index(m, 1), k = leaf_index(m, 2);
    b.level = l.level, b.x = l.base[0] + uint32_t(i), b.y = l.base[1] + uint32_t(j),
    b.z = l.base[2] + uint32_t(k);
    b.c = {l.c[0][i], l.c[1][j], l.c[2][k]};
    b.h = l.h;
    return b;
  }
  /// Whether split(tris, nb, kids, out, want) would give every triangle of a list whose
  /// corners' bounds are `box` to one child, keeping all of them: then `only` is that child
  /// (-1: one not in want, every list empty). Decided from the bounds alone (the split's
  /// bounding-box sides, which only grow with them): exact.
  bool whole_list_in_one(const ListBox& box, const CellBox& nb, uint32_t want, int& only) const;
  /// Whether every triangle of a list whose corners' bounds are `box` passes tri_inside_box(b).
  bool all_inside(const ListBox& box, const CellBox& b) const;
  /// The 8 children of a box: child(b, c) for each c, with each of the 6 distinct coordinates
  /// computed once (box()'s formula) instead of 24 times.
  void children(const CellBox& b, CellBox kids[8]) const {
    const int level = b.level + 1;
    const double s = cell_size(level);
    const uint32_t x = 2 * b.x, y = 2 * b.y, z = 2 * b.z;
    float cx[2], cy[2], cz[2];
    for (uint32_t i = 0; i < 2; ++i)
      cx[i] = centre(0, x + i, s), cy[i] = centre(1, y + i, s), cz[i] = centre(2, z + i, s);
    const float h = float(0.5 * s);
    for (int c = 0; c < 8; ++c) {
      const uint32_t i = uint32_t(c & 1), j = uint32_t(c >> 1 & 1), k = uint32_t(c >> 2 & 1);
      CellBox& o = kids[c];
      o.level = level, o.x = x + i, o.y = y + j, o.z = z + k;
      o.c = {cx[i], cy[j], cz[k]};
      o.h = h;
    }
  }
  /// Child c of a box.
  CellBox child(const CellBox& b, int c) const {
    return box(b.level + 1, 2 * b.x + uint32_t(c & 1), 2 * b.y + uint32_t(c >> 1 & 1),
               2 * b.z + uint32_t(c >> 2 & 1));
  }
  /// A new leaf for a cell whose triangles are `tris` (non-empty), with colours inherited from
  /// `parent` (null: background).
  LeafCell make_leaf(std::span<const uint32_t> tris, const LeafCell* parent) const;
  /// The leaf of a list whose first triangle is `first` and whose first on side 1 of that one's
  /// tag is `back` (~0: none): what make_leaf makes of it.
  LeafCell leaf_of(uint32_t first, uint32_t back, const LeafCell* parent) const;
  /// The leaf make_leaf gives the cell `cb` (its list: the triangles of `candidates` meeting it,
  /// sorted), found from candidates in any order, repeats allowed, with box tests only on
  /// those that could change it (a lower index than the one kept): false when none meets the
  /// cell. For a cell only its leaf is wanted of (no list to split further).
  bool leaf_from_candidates(std::span<const uint32_t> candidates, const CellBox& cb,
                            const LeafCell* parent, LeafCell& out) const;

  /// Keeps, across runs (the dabs of a stroke), the triangle lists of the leaves of each brick
  /// run() visits (not those it builds), and uses them instead of splitting the brick's lists
  /// again when a later run wants no leaf of it the earlier ones did not. A leaf a run paints
  /// meets the region, so every triangle meeting it is in the run's list (see run()): its list,
  /// the triangles passing the same box tests from the root down, is the same in every run, so
  /// the results are the same bit for bit. Only for runs with the same depth over an unchanged
  /// mesh; off by default.
  void keep_brick_lists(bool on) { keep_ = on; }

  /// The triangles meeting the start cell (x, y, z) (level octree::kStartDepth) of this
  /// refiner's texture, sorted: exactly what triangles_in_box gives for its box. From a table
  /// of every start cell, made on the first call for the texture's cube (O(T); shared by
  /// every refiner of the surface until another cube is asked about), so that refining a
  /// start cell splits its list instead of querying the BVH for each child: the serial head of
  /// a dab on fresh surface.
  std::span<const uint32_t> start_list(uint32_t x, uint32_t y, uint32_t z) const;
  /// Makes (or finds) that table now: run() does before a visit that may need it (its
  /// threads then only read it); OctreeTexture::create does, so a first dab does not.
  void prepare_start_lists() { start_ = start_lists(); }

  /// Levels from a task's cell to the leaves: a task cell holds 4 x 4 x 4 bricks' cells (16^3
  /// leaves), few enough tasks that a dab's per-task parts stay small, enough for two threads
  /// on a radius-16 dab (measured against 2 and 3 levels: both slower, 3 by 10-20% once the
  /// per-task work shrank).
  static constexpr int kTaskDepth = 4;

  RefineStats stats;

 private:
  /// Per brick (by level and Morton code) with keep_brick_lists: which leaves' lists are known
  /// and where they are in `tris`.
  struct KeptBrick {
    uint64_t known = 0;
    uint32_t off[64], len[64];
  };
  struct Kept {
    std::unordered_map<uint64_t, uint32_t> index;
    std::vector<KeptBrick> bricks;
    std::vector<uint32_t> tris;
  };
  /// The pool writes of a run on several threads: recorded per task in order, a child task's
  /// log hung into its parent's at the join in child order, the tree replayed once at the end
  /// of the run, so the pool comes out as one thread writes it. A block stored meanwhile is
  /// named by a temporary address (temp0_ and up, above every address in the pool, one per
  /// store of the run), which reads of it before the replay (averages, compaction, visits)
  /// find through `where_`.
  struct Log {
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
    std::vector<Log*> children;
    /// The log's share of temporary addresses not used yet: slots [next, end) of where_, taken
    /// kTempChunk at a time (one atomic step per chunk, not per store).
    uint32_t next = 0, end = 0;
    void clear() { ops.clear(), words.clear(), children.clear(), next = end = 0; }
  };
  /// Where a temporary address's block is: its log and op.
  struct Where {
    const Log* log = nullptr;
    uint32_t op = 0;
  };
  /// A brick's leaves' lists, one after another: leaf m's in tris[start[m], start[m + 1]).
  struct LeafLists {
    uint32_t start[65];
    std::vector<uint32_t> tris;
    std::span<const uint32_t> list(int m) const {
      return std::span<const uint32_t>(tris).subspan(start[m], start[m + 1] - start[m]);
    }
  };
  /// The lists of the leaves of a brick from leaf_masks' masks of `in`: leaf m's, the in[i]
  /// with bit m of masks[i], in order.
  static void leaf_lists(std::span<const uint32_t> in, std::span<const uint64_t> masks,
                         LeafLists& out);
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
  /// per level its lists, the brick builder's masks and lists, the encoder's words, counts;
  /// and the painter, kept lists and log of the task.
  struct Ctx {
    std::array<PendingBrick, 8> bricks;  // a node's children at most
    int pending = 0;
    std::array<Scratch, octree::kMaxDepth + 1> scratch;
    std::vector<uint64_t> masks;  // a brick's list's leaf masks (leaf_masks)
    LeafLists lists;              // a brick's leaves' lists
    std::vector<uint32_t> words;
    RefineStats stats;
    LeafPainter* painter = nullptr;
    Kept* kept = nullptr;
    Log* log = nullptr;  ///< null: writes go to the pool
  };
  /// A task cell's own state across runs: its painter and kept lists.
  struct Shard {
    LeafPainter* painter = nullptr;
    Kept kept;
  };

  /// A cell's size at a level: the quotient divided out once per level.
  double cell_size(int level) const {
    return level >= 0 && level <= octree::kMaxDepth
               ? scale_[size_t(level)]
               : double(ed_.texture().size()) / double(1u << level);
  }
  /// The centre coordinate along `axis` of cell i of size s.
  float centre(int axis, uint32_t i, double s) const {
    return float(origin_[axis] + (double(i) + 0.5) * s);
  }
  bool meets(const CellBox& b) const;
  /// b lies inside the region (with a margin): meets() holds for every cell inside b.
  bool within(const CellBox& b) const;
  /// Which of b's children (`kids`) meet the region (bit c: child c).
  uint32_t meeting(const CellBox kids[8]) const;
  /// Which leaves of the brick `bb` (bit m, leaf_box(l, m)) meet the region and lie in a
  /// child of bb that does: meets() on each, from per-axis terms (the same float operations).
  uint64_t meeting_leaves(const CellBox& bb, const BrickLeaves& l) const;
  /// leaf_masks with the brick's leaves at hand.
  void leaf_masks(std::span<const uint32_t> in, const CellBox& bb, const BrickLeaves& l,
                  uint64_t want, std::vector<uint64_t>& masks) const;
  void full_tris(const CellBox& b, std::span<const uint32_t> region_tris,
                 std::vector<uint32_t>& out) const;
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
  /// split() of a list on TBB's threads in chunks when it is long and writes are logged (a run
  /// on several threads), each chunk's parts appended in chunk order: the same lists.
  void split_maybe_parallel(const Ctx& w, std::span<const uint32_t> in, const CellBox& b,
                            const CellBox kids[8], Split& out, uint32_t want = 0xffu) const;
  /// Makes the log's writes in order, its children's where they hang.
  void replay(Log& log);
  /// A temporary address's real one once replayed (real ones as they are).
  uint32_t resolve(uint32_t p) const { return p >= temp0_ ? real_[p - temp0_] : p; }
  uint32_t resolve_brick(uint32_t word) const {
    return resolve(word & ~octree::kBrickDoubleFlag) | (word & octree::kBrickDoubleFlag);
  }
  /// Contexts and logs of tasks, from pools every refiner shares (kept warm across strokes:
  /// a click is a stroke of its own).
  static SharedPool<Ctx>& ctx_pool();
  static SharedPool<Log>& log_pool();
  static Ctx& take_ctx();
  static void put_ctx(Ctx& w);
  static Log& take_log();
  static void put_log(Log& l);
  /// The run's task logs back to the pool, once replayed.
  void give_back_logs();
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
  GeneralNode explode(Ctx& w, const Brick& b, const CellBox& bb);
  /// Encodes and stores a node; returns (ptr, info). `old_ptr` 0: new.
  void store_general(Ctx& w, const GeneralNode& n, uint32_t old_ptr, uint32_t old_info,
                     uint32_t& ptr, uint32_t& info);
  /// Encodes and stores a brick in place of `old_word`'s block (0: new), `old` its cells as
  /// decoded (their size; null with old_word 0); returns the brick's word.
  uint32_t store_brick(Ctx& w, const Brick& b, uint32_t old_word, const Brick* old);
  /// ed_.replace_block, or its record in w's log (a temporary address).
  uint32_t put_block(Ctx& w, uint32_t old_ptr, uint32_t old_n, bool brick, int generals,
                     int bricks);
  void release(Ctx& w, uint32_t ptr, uint32_t n, bool brick);
  /// The words holding block `ptr` (pool or log) and the block's position in them.
  std::span<const uint32_t> block(const Ctx& w, uint32_t ptr, uint32_t& at) const;
  Rgba8 child_avg(const Ctx& w, const GeneralNode& n, int c) const;
  Rgba8 general_avg(const Ctx& w, const GeneralNode& n) const;
  static Rgba8 brick_avg(const Brick& b);
  /// A general node whose cells are all leaf-only general nodes becomes a brick.
  bool try_compact(const Ctx& w, const GeneralNode& n, Brick& out) const;

  struct StartLists;
  std::shared_ptr<const StartLists> start_lists() const;
  std::shared_ptr<const StartLists> start_;

  OctreeEditor ed_;
  const PaintSurface& s_;
  std::array<double, octree::kMaxDepth + 1> scale_;  // cell size by level
  double origin_[3];
  Region region_;
  int depth_ = 0;
  LeafPainter* painter_ = nullptr;
  float slack_ = 0;
  bool keep_ = false;
  bool tasks_ = false;  // this run visits task cells (no painter or a sharded one; deep enough)
  Log main_log_;
  std::mutex shard_mutex_, stats_mutex_;
  RefineStats task_stats_;  // every context's counts, added as each goes back
  Kept kept_;               // without shards
  std::unordered_map<uint64_t, std::unique_ptr<Shard>> shards_;
  uint32_t temp0_ = 0;  // the pool's size at the run's start: temporary addresses start there
  tbb::concurrent_vector<Where> where_;  // per temporary address
  static constexpr uint32_t kTempChunk = 32;
  std::mutex logs_mutex_;
  std::vector<Log*> taken_logs_;  // the run's task logs, given back after the replay
  std::vector<uint32_t> real_;    // per temporary address, its block's address once replayed
};

}  // namespace limn::detail
