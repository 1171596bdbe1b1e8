// Lazy refinement: a leaf is split only where the region needs more resolution and only into the
// cells its box shares with the surface (exact box-triangle tests on triangles the Embree BVH
// returns for the box), so memory follows the painted detail and nothing else. This file visits
// the tree; the tests are CellBoxes', the writes NodeWrites'.
#include "refine.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace limn::detail {

using namespace paint_detail;

Refiner::Refiner(OctreeTexture& t, const PaintSurface& s) : boxes_(t, s), writes_(t), s_(s) {}

std::span<const uint32_t> Refiner::start_list(uint32_t x, uint32_t y, uint32_t z) const {
  if (!start_) throw std::logic_error("octree refiner: start lists not prepared");
  return start_->list(x, y, z);
}

GeneralNode Refiner::refine_leaf(Ctx& w, const CellBox& cb, const LeafCell& leaf,
                                 const std::vector<uint32_t>* full_list) {
  GeneralNode g;
  Split& parts = w.scratch[size_t(cb.level)].full_parts;
  CellBox kids[8];
  boxes_.children(cb, kids);
  bool off_region[8] = {};
  LeafCell off_leaf[8];
  if (!full_list) {
    // Each child's list from the BVH (at once on the threads with a log): the lists splitting
    // the cell's own would give, without querying it first. A child off the region
    // (visit_general will not visit it) needs only its leaf, found from the query's candidates.
    auto query = [&](int c) {
      const float kc[3] = {kids[c].c.x, kids[c].c.y, kids[c].c.z};
      std::vector<uint32_t>& out = parts[size_t(c)];
      out.clear();
      if (CellBoxes::meets(region_, kids[c])) {
        s_.triangles_in_box(kc, kids[c].h, boxes_.slack(), out);
        return;
      }
      s_.box_candidates(kc, kids[c].h, boxes_.slack(), out);
      off_region[c] = boxes_.leaf_from_candidates(out, kids[c], &leaf, off_leaf[c]);
      out.clear();
    };
    if (w.out.log)
      tbb::parallel_for(0, 8, query);
    else
      for (int c = 0; c < 8; ++c) query(c);
  } else {
    boxes_.split_maybe_parallel(w.out.log != nullptr, *full_list, cb, kids, parts);
  }
  for (int c = 0; c < 8; ++c) {
    const std::vector<uint32_t>& fc = parts[size_t(c)];
    if (fc.empty() && !off_region[c]) continue;
    g.kind[c] = CellKind::leaf;
    g.leaf[c] = off_region[c] ? off_leaf[c] : boxes_.make_leaf(fc, &leaf);
    ++w.stats.leaves_created;
  }
  ++w.stats.generals_created;
  return g;
}

namespace {

// The elements of sorted `a` that sorted `b` holds, in order.
void intersect_sorted(std::span<const uint32_t> a, std::span<const uint32_t> b,
                      std::vector<uint32_t>& out) {
  out.clear();
  size_t j = 0;
  for (uint32_t v : a) {
    while (j < b.size() && b[j] < v) ++j;
    if (j == b.size()) break;
    if (b[j] == v) out.push_back(v);
  }
}

}  // namespace

bool Refiner::build_brick(Ctx& w, const CellBox& cb, const LeafCell& leaf,
                          std::span<const uint32_t> full, std::span<const uint32_t> tris,
                          Brick& b) {
  b = Brick{};
  std::vector<uint64_t>& masks = w.masks;
  const CellBoxes::BrickLeaves l = boxes_.brick_leaves(cb);
  boxes_.leaf_masks(full, cb, l, ~uint64_t(0), masks);
  // Each leaf's first triangle and first on side 1 of that one's tag: what make_leaf reads of
  // its list, found in one pass over the list.
  uint32_t first[64], back[64];
  uint64_t any = 0, open = 0;  // open: leaves with a first triangle and no back one yet
  for (size_t i = 0; i < full.size(); ++i) {
    const uint32_t t = full[i];
    const uint64_t fresh = masks[i] & ~any;
    for (uint64_t m = fresh; m; m &= m - 1) first[std::countr_zero(m)] = t;
    for (uint64_t m = masks[i] & open; m; m &= m - 1) {
      const int k = std::countr_zero(m);
      if (s_.side(s_.tag(first[k]), t) == 1) back[k] = t, open &= ~(uint64_t(1) << k);
    }
    any |= fresh, open |= fresh;
  }
  for (uint64_t left = any; left; left &= left - 1) {
    const int m = std::countr_zero(left);
    b.cell[m] = boxes_.leaf_of(first[m], open >> m & 1 ? ~0u : back[m], &leaf);
    ++w.stats.leaves_created;
  }
  b.mask = any;
  ++w.stats.bricks_created;  // counted as before, even when no sub-cell meets the surface
  if (b.mask == 0) return false;
  if (w.painter) {
    // tris is a subset of full (both sorted): a leaf's region list is its full list less the
    // triangles outside tris.
    const uint64_t want =
        any &
        (CellBoxes::within(region_, cb) ? ~uint64_t(0) : boxes_.meeting_leaves(region_, cb, l));
    size_t j = 0;
    for (size_t i = 0; i < full.size(); ++i) {
      while (j < tris.size() && tris[j] < full[i]) ++j;
      masks[i] &= j < tris.size() && tris[j] == full[i] ? want : 0;
    }
    LeafLists& ll = w.lists;
    CellBoxes::leaf_lists(full, masks, ll);
    for (uint64_t left = want; left; left &= left - 1) {
      const int m = std::countr_zero(left);
      if (ll.start[m] == ll.start[m + 1]) continue;
      w.painter->paint(CellBoxes::leaf_box(l, m), b.cell[m], ll.list(m), LeafPainter::kNoMemo),
          ++w.stats.leaves_painted;
    }
  }
  return true;
}

GeneralNode Refiner::explode(Ctx& w, const Brick& b) {
  GeneralNode g;
  for (int c1 = 0; c1 < 8; ++c1) {
    const uint32_t byte = uint32_t(b.mask >> (8 * c1)) & 255u;
    if (!byte) continue;
    GeneralNode child;
    for (int c2 = 0; c2 < 8; ++c2)
      if (byte >> c2 & 1) child.kind[c2] = CellKind::leaf, child.leaf[c2] = b.cell[8 * c1 + c2];
    child.avg = writes_.general_avg(w.out, child);
    writes_.store_general(w.out, child, 0, 0, g.ptr[c1], g.info[c1]);
    g.kind[c1] = CellKind::general;
  }
  g.avg = b.avg;
  ++w.stats.bricks_exploded;
  return g;
}

bool Refiner::try_compact(const Ctx& w, const GeneralNode& n, Brick& out) const {
  bool any = false;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::empty) continue;
    if (n.kind[c] != CellKind::general) return false;
    if (octree::leaves(n.info[c]) != octree::occupied(n.info[c])) return false;
    any = true;
  }
  if (!any) return false;
  out = Brick{};
  for (int c1 = 0; c1 < 8; ++c1) {
    if (n.kind[c1] != CellKind::general) continue;
    uint32_t at = 0;
    const std::span<const uint32_t> words = writes_.block(w.out, n.ptr[c1], at);
    const GeneralNode child = decode_general(words, at, n.info[c1]);
    for (int c2 = 0; c2 < 8; ++c2)
      if (child.kind[c2] == CellKind::leaf) {
        out.mask |= uint64_t(1) << (8 * c1 + c2);
        out.cell[8 * c1 + c2] = child.leaf[c2];
      }
  }
  out.avg = brick_average(out);
  return true;
}

namespace {

// Whether two bricks hold the same cells (what encode_brick stores, less the average).
bool same_cells(const Brick& a, const Brick& b) {
  if (a.mask != b.mask || a.dbl != b.dbl) return false;
  for (uint64_t m = a.mask; m; m &= m - 1) {
    const LeafCell &x = a.cell[std::countr_zero(m)], &y = b.cell[std::countr_zero(m)];
    if (x.tag != y.tag || x.dbl != y.dbl || x.s[0] != y.s[0] || x.s[1] != y.s[1]) return false;
  }
  return true;
}

}  // namespace

void Refiner::visit_brick(Ctx& w, Brick& b, const CellBox& bb, std::span<const uint32_t> tris) {
  // Only leaves meeting the region are visited: only they are tested. Most bricks of a dab lie
  // inside its ball: then all their cells meet it.
  const CellBoxes::BrickLeaves l = boxes_.brick_leaves(bb);
  const uint64_t want =
      CellBoxes::within(region_, bb) ? ~uint64_t(0) : boxes_.meeting_leaves(region_, bb, l);
  KeptBricks::Brick* kept = nullptr;
  uint32_t memo0 = LeafPainter::kNoMemo;  // memo of leaf m: memo0 + m
  auto visit_leaf = [&](int m, std::span<const uint32_t> t2) {
    if (!(b.mask >> m & 1)) {
      // A surface cell the brick lacks: the texture was made for another mesh.
      b.mask |= uint64_t(1) << m;
      b.cell[m] = boxes_.make_leaf(t2, nullptr);
      ++w.stats.leaves_created;
    }
    const uint32_t memo = memo0 == LeafPainter::kNoMemo ? memo0 : memo0 + uint32_t(m);
    if (w.painter)
      w.painter->paint(CellBoxes::leaf_box(l, m), b.cell[m], t2, memo), ++w.stats.leaves_painted;
  };
  if (keep_) {
    const uint64_t key = morton3(bb.x, bb.y, bb.z) | uint64_t(bb.level) << 48;
    uint32_t index = 0;
    kept = &w.kept->find(key, index);
    if (index < (1u << 25)) memo0 = 64 * index;
    if (!(want & ~kept->known)) {
      // Every leaf wanted has its list from an earlier run: the same visits, no tests.
      for (uint64_t left = want; left; left &= left - 1) {
        const int m = std::countr_zero(left);
        if (kept->len[m]) visit_leaf(m, w.kept->list(*kept, m));
      }
      return;
    }
  }
  std::vector<uint64_t>& masks = w.masks;
  boxes_.leaf_masks(tris, bb, l, want, masks);
  uint64_t any = 0;
  for (uint64_t m : masks) any |= m;
  if (kept) {
    for (uint64_t left = want & ~any; left; left &= left - 1) kept->len[std::countr_zero(left)] = 0;
    kept->known |= want;
  }
  LeafLists& ll = w.lists;
  CellBoxes::leaf_lists(tris, masks, ll);
  for (uint64_t left = any; left; left &= left - 1) {
    const int m = std::countr_zero(left);
    const std::span<const uint32_t> list = ll.list(m);
    if (kept) w.kept->keep(*kept, m, list);
    visit_leaf(m, list);
  }
}

void Refiner::visit_general(Ctx& w, GeneralNode& n, const CellBox& nb,
                            std::span<const uint32_t> tris,
                            const std::vector<uint32_t>* parent_full, const ListBox* box) {
  CellBox kids[8];
  boxes_.children(nb, kids);
  const uint32_t want = CellBoxes::meeting(region_, kids);
  Scratch& sc = w.scratch[size_t(nb.level)];
  Split &parts = sc.parts, &full_parts = sc.full_parts;
  // Just refined: full_parts holds parent_full split by child, and tris (a subset of
  // parent_full, both sorted) splits into the same lists less the triangles it lacks.
  const bool full_split = parent_full != nullptr;
  const bool same = full_split && tris.size() == parent_full->size();
  // Near the root a dab's list often lies in one child whole: it goes there untested, with its
  // bounds (the lists split() would make).
  int only = -1;
  const bool whole = !full_split && box && boxes_.whole_list_in_one(*box, nb, want, only);
  if (whole) {
    for (int c = 0; c < 8; ++c) parts[size_t(c)].clear();
    if (only >= 0) parts[size_t(only)].assign(tris.begin(), tris.end());
  } else if (!full_split) {
    boxes_.split_maybe_parallel(w.out.log != nullptr, tris, nb, kids, parts, want);
  } else if (!same) {
    for (int c = 0; c < 8; ++c) intersect_sorted(full_parts[size_t(c)], tris, parts[size_t(c)]);
  }
  const Split& tparts = same ? full_parts : parts;
  uint32_t todo = 0;
  for (int c = 0; c < 8; ++c)
    if (!tparts[size_t(c)].empty() && (want >> c & 1)) todo |= 1u << c;
  if (tasks_ && nb.level <= depth_ - kTaskDepth - 1) {
    visit_parts(w, n, kids, todo, tparts, full_split ? &full_parts : nullptr,
                nb.level == depth_ - kTaskDepth - 1, whole ? box : nullptr);
  } else {
    for (int c = 0; c < 8; ++c)
      if (todo >> c & 1)
        visit_child(w, n, c, kids[c], tparts[size_t(c)],
                    full_split ? &full_parts[size_t(c)] : nullptr, whole ? box : nullptr);
  }
  finish_bricks(w);
  if (w.painter) w.painter->flush();
  n.avg = writes_.general_avg(w.out, n);
}

void Refiner::finish_bricks(Ctx& w) {
  if (!w.pending) return;
  if (w.painter) w.painter->flush();
  for (int i = 0; i < w.pending; ++i) {
    PendingBrick& p = w.bricks[size_t(i)];
    GeneralNode& n = *p.n;
    if (p.fresh) {
      p.b.avg = brick_average(p.b);
      n.kind[p.c] = CellKind::brick;
      n.ptr[p.c] = writes_.store_brick(w.out, p.b, 0, nullptr);
    } else if (!same_cells(p.before, p.b)) {
      // A brick the visit left as it was (its texels already as strong from an earlier dab of
      // the stroke, or out of the brush's reach) is not averaged, encoded and written again:
      // the same words would come out.
      p.b.avg = brick_average(p.b);
      n.ptr[p.c] = writes_.store_brick(w.out, p.b, n.ptr[p.c], &p.before);
    }
  }
  w.pending = 0;
}

Refiner::Shard& Refiner::shard(uint64_t key) {
  std::lock_guard<std::mutex> lock(shard_mutex_);
  std::unique_ptr<Shard>& s = shards_[key];
  if (!s) s = std::make_unique<Shard>(), s->painter = painter_->shard(key);
  return *s;
}

namespace {

void add(RefineStats& to, const RefineStats& a) {
  to.leaves_created += a.leaves_created, to.bricks_created += a.bricks_created;
  to.generals_created += a.generals_created, to.bricks_exploded += a.bricks_exploded;
  to.bricks_compacted += a.bricks_compacted, to.leaves_painted += a.leaves_painted;
  to.tasks += a.tasks, to.tasks_threaded += a.tasks_threaded;
}

}  // namespace

// Never destroyed: a refiner that outlives main() (a painter in a static) still gives back.
SharedPool<Refiner::Ctx>& Refiner::ctx_pool() {
  static SharedPool<Ctx>& pool = *new SharedPool<Ctx>;
  return pool;
}

Refiner::Ctx& Refiner::take_ctx() {
  return ctx_pool().take();
}

void Refiner::put_ctx(Ctx& w) {
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    add(task_stats_, w.stats);
  }
  w.stats = {}, w.out.log = nullptr, w.painter = nullptr, w.kept = nullptr;
  ctx_pool().put(w);
}

void Refiner::visit_parts(Ctx& w, GeneralNode& n, const CellBox kids[8], uint32_t todo,
                          const Split& tparts, const Split* full_parts, bool task_cells,
                          const ListBox* box) {
  int cs[8], count = 0;
  Shard* sh[8] = {};
  for (int c = 0; c < 8; ++c) {
    if (!(todo >> c & 1)) continue;
    if (task_cells && painter_) {
      const CellBox& cb = kids[c];
      sh[count] = &shard(morton3(cb.x, cb.y, cb.z) | uint64_t(cb.level) << 48);
    }
    cs[count++] = c;
  }
  if (task_cells) w.stats.tasks += size_t(count);
  auto visit = [&](Ctx& x, int i) {
    const int c = cs[i];
    visit_child(x, n, c, kids[c], tparts[size_t(c)],
                full_parts ? &(*full_parts)[size_t(c)] : nullptr, box);
  };
  if (!w.out.log || count < 2) {
    // One thread: the same visits in order, each task cell through its shard.
    LeafPainter* const painter = w.painter;
    KeptBricks* const kept = w.kept;
    for (int i = 0; i < count; ++i) {
      if (sh[i]) w.painter = sh[i]->painter, w.kept = &sh[i]->kept;
      visit(w, i);
      finish_bricks(w);  // through this child's painter
    }
    w.painter = painter, w.kept = kept;
    return;
  }
  if (task_cells) w.stats.tasks_threaded += size_t(count);
  // Each child with a context and log of its own (a thread waiting for its children may run
  // other tasks meanwhile, so contexts are not per thread); logs merged in child order, so
  // the writes come out in the order one thread makes them.
  WriteLog* logs[8];
  writes_.take_logs(count, logs);
  tbb::parallel_for(
      tbb::blocked_range<int>(0, count, 1),
      [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i < r.end(); ++i) {
          Ctx& x = take_ctx();
          x.out.log = logs[i];
          x.painter = sh[i] ? sh[i]->painter : nullptr;
          x.kept = sh[i] ? &sh[i]->kept : &kept_;
          visit(x, i);
          finish_bricks(x);
          put_ctx(x);
        }
      },
      tbb::simple_partitioner());
  // Each child's writes where one thread would make them: after what w wrote before the join.
  NodeWrites::join(*w.out.log, logs, count);
}

void Refiner::visit_child(Ctx& w, GeneralNode& n, int c, const CellBox& cb,
                          std::span<const uint32_t> tc, const std::vector<uint32_t>* full_c,
                          const ListBox* box_c) {
  const int level = cb.level;
  std::vector<uint32_t>& full = w.scratch[size_t(level - 1)].full;
  // The child's full list, from its parent's when known (no BVH query, and no triangles from
  // outside the parent's box to test).
  auto child_full = [&] {
    if (full_c) {
      full = *full_c;
    } else {
      boxes_.full_tris(region_, cb, tc, full);
    }
  };
  if (n.kind[c] == CellKind::empty) {
    child_full();
    if (full.empty()) return;
    n.kind[c] = CellKind::leaf;
    n.leaf[c] = boxes_.make_leaf(full, nullptr);
    ++w.stats.leaves_created;
  }
  switch (n.kind[c]) {
    case CellKind::leaf: {
      if (level >= depth_) {
        if (w.painter)
          w.painter->paint(cb, n.leaf[c], tc, LeafPainter::kNoMemo), ++w.stats.leaves_painted;
        break;
      }
      // A leaf with no list at hand (made by an earlier run) that becomes a general node takes
      // its children's lists straight from the BVH, instead of its own list queried and then
      // split; its own list then stays empty, so visit_general sees it as not `same`. A start
      // cell's list is at hand in the surface's table.
      bool queried = !full_c && level < depth_ - 2 && !region_.everything;
      if (queried && level == octree::kStartDepth) {
        const std::span<const uint32_t> kept = start_list(cb.x, cb.y, cb.z);
        full.assign(kept.begin(), kept.end());
        queried = false;
      } else if (queried) {
        full.clear();
      } else {
        child_full();
      }
      // A cell the surface only grazes within the boxes' slack may have no sub-cell the surface
      // meets once rounded: it stays a leaf.
      if (level == depth_ - 2) {
        PendingBrick& p = w.bricks[w.pending];
        if (!build_brick(w, cb, n.leaf[c], full, tc, p.b)) break;
        p.n = &n, p.c = c, p.fresh = true;
        ++w.pending;
      } else {
        GeneralNode g = refine_leaf(w, cb, n.leaf[c], queried ? nullptr : &full);
        bool any = false;
        for (int k = 0; k < 8; ++k) any |= g.kind[k] != CellKind::empty;
        if (!any) break;
        visit_general(w, g, cb, tc, &full);
        n.kind[c] = CellKind::general;
        writes_.store_general(w.out, g, 0, 0, n.ptr[c], n.info[c]);
      }
      break;
    }
    case CellKind::general: {
      finish_bricks(w);  // their stores first, in child order
      // From the log when just stored by this task (an exploded brick's children).
      uint32_t at = 0;
      const std::span<const uint32_t> words = writes_.block(w.out, n.ptr[c], at);
      GeneralNode g = decode_general(words, at, n.info[c]);
      visit_general(w, g, cb, tc, nullptr, box_c);
      Brick b;
      if (try_compact(w, g, b)) {
        for (int k = 0; k < 8; ++k)
          if (g.kind[k] == CellKind::general)
            writes_.release(w.out, g.ptr[k], general_block_words(g.info[k]), false);
        writes_.release(w.out, n.ptr[c], general_block_words(n.info[c]), false);
        n.kind[c] = CellKind::brick;
        n.ptr[c] = writes_.store_brick(w.out, b, 0, nullptr);
        ++w.stats.bricks_compacted;
      } else {
        writes_.store_general(w.out, g, n.ptr[c], n.info[c], n.ptr[c], n.info[c]);
      }
      break;
    }
    case CellKind::brick: {
      uint32_t at = 0;
      const std::span<const uint32_t> words =
          writes_.block(w.out, n.ptr[c] & ~octree::kBrickDoubleFlag, at);
      Brick b = decode_brick(words, at | (n.ptr[c] & octree::kBrickDoubleFlag));
      if (level + 2 < depth_) {
        finish_bricks(w);  // their stores first, in child order
        const uint32_t old_ptr = n.ptr[c] & ~octree::kBrickDoubleFlag;
        GeneralNode g = explode(w, b);
        writes_.release(w.out, old_ptr, brick_block_words(b.mask, b.dbl), true);
        visit_general(w, g, cb, tc);
        n.kind[c] = CellKind::general;
        writes_.store_general(w.out, g, 0, 0, n.ptr[c], n.info[c]);
      } else {
        PendingBrick& p = w.bricks[w.pending++];
        p.n = &n, p.c = c, p.fresh = false;
        p.b = b, p.before = b;
        visit_brick(w, p.b, cb, tc);
      }
      break;
    }
    case CellKind::empty:
      break;
  }
}

void Refiner::run(const Region& region, std::span<const uint32_t> tris, int depth,
                  LeafPainter* painter) {
  region_ = region, depth_ = depth, painter_ = painter;
  // Start cells may be refined below (see visit_child): their lists at hand before any thread
  // asks.
  if (!region.everything && depth - 2 > octree::kStartDepth) prepare_start_lists();
  {
    // The calling thread's context, from the shared pool too: a click's refiner is made and
    // dropped per dab, and a warm context saves its lists' allocations.
    struct Taken {
      Refiner& r;
      Ctx& w;
      ~Taken() { r.put_ctx(w); }
    } taken{*this, take_ctx()};
    Ctx& main = taken.w;
    main.painter = painter, main.kept = &kept_;
    tasks_ = false;
    if (!painter) {
      tasks_ = depth - kTaskDepth - 1 >= 0;  // refining only: no shards to keep apart
    } else if (painter->sharded()) {
      tasks_ = depth - kTaskDepth - 1 >= 0;
      if (tasks_) {
        main.painter = nullptr;  // every cell painted lies under a task cell
      } else {
        // Too shallow for tasks: one shard for everything.
        Shard& s = shard(~uint64_t(0));
        main.painter = s.painter, main.kept = &s.kept;
      }
    }
    OctreeEditor& ed = writes_.editor();
    const uint32_t ptr = ed.word(0), info = ed.word(1);
    GeneralNode root =
        octree::occupied(info) ? decode_general(ed.pool(), ptr, info) : GeneralNode{};
    const CellBox rb = boxes_.box(0, 0, 0, 0);
    // The triangles meeting the root's box: all of them when their corners' bounds lie inside
    // it (the texture was made for this mesh), and those bounds let the visit skip splits.
    ListBox tbox = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (uint32_t t : tris)
      for (int v = 0; v < 3; ++v)
        for (int a = 0; a < 3; ++a) {
          const float x = s_.corner(t, v)[a];
          tbox.lo[a] = std::min(tbox.lo[a], x), tbox.hi[a] = std::max(tbox.hi[a], x);
        }
    const bool known = !tris.empty() && boxes_.all_inside(tbox, rb);
    std::vector<uint32_t> filtered;
    if (!known) boxes_.filter(tris, rb, filtered);
    const std::span<const uint32_t> t0 = known ? tris : std::span<const uint32_t>(filtered);
    // On several threads every write waits in a log, replayed once the visit is over (reads of
    // the pool meanwhile see it as it was); temporary addresses need room above the pool.
    const bool threads =
        tasks_ && writes_.room_for_log() && tbb::this_task_arena::max_concurrency() > 1 &&
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
    writes_.begin(threads);
    main.out.log = threads ? writes_.main_log() : nullptr;
    if (!t0.empty()) {
      visit_general(main, root, rb, t0, nullptr, known ? &tbox : nullptr);
      bool any = false;
      for (int c = 0; c < 8; ++c) any |= root.kind[c] != CellKind::empty;
      if (any) {
        uint32_t nptr = 0, ninfo = 0;
        writes_.store_general(main.out, root, ptr, info, nptr, ninfo);
        nptr = writes_.finish(nptr);
        ed.set(0, nptr);
        ed.set(1, ninfo);
      }
    }
  }
  writes_.give_back();
  stats = task_stats_;
}

}  // namespace limn::detail
