// The refiner's node reads and writes, straight or logged: see node_writes.hpp.
#include "node_writes.hpp"

#include <stdexcept>

namespace limn::detail {

namespace {

// Never destroyed: a refiner that outlives main() (a painter in a static) still gives back.
// Kept warm across strokes: a click is a stroke of its own.
SharedPool<WriteLog>& log_pool() {
  static SharedPool<WriteLog>& pool = *new SharedPool<WriteLog>;
  return pool;
}

}  // namespace

void NodeWrites::begin(bool logged) {
  give_back();
  temp0_ = uint32_t(ed_.pool().size());
  logged_ = logged;
  main_log_.clear();
}

uint32_t NodeWrites::finish(uint32_t root_ptr) {
  if (!logged_) return root_ptr;
  real_.assign(where_.size(), 0);
  replay(main_log_);
  return resolve(root_ptr);
}

void NodeWrites::give_back() {
  for (WriteLog* l : taken_logs_) l->clear(), log_pool().put(*l);
  taken_logs_.clear();
  where_.clear();
}

void NodeWrites::take_logs(int count, WriteLog* out[]) {
  std::lock_guard<std::mutex> lock(logs_mutex_);
  for (int i = 0; i < count; ++i)
    out[i] = &log_pool().take(), out[i]->clear(), taken_logs_.push_back(out[i]);
}

void NodeWrites::join(WriteLog& parent, WriteLog* const children[], int count) {
  for (int i = 0; i < count; ++i) {
    WriteLog::Op op{};
    op.kind = WriteLog::kChild, op.off = uint32_t(parent.children.size());
    parent.children.push_back(children[i]);
    parent.ops.push_back(op);
  }
}

std::span<const uint32_t> NodeWrites::block(const TaskWrites& w, uint32_t ptr, uint32_t& at) const {
  if (w.log && ptr >= temp0_) {
    // Stored earlier by this task or one it waits for or has joined: ordered before this read.
    const Where& at_log = where_[ptr - temp0_];
    if (!at_log.log) throw std::logic_error("octree refiner: a temporary address not logged");
    const WriteLog::Op& op = at_log.log->ops[at_log.op];
    at = 0;
    return std::span<const uint32_t>(at_log.log->words).subspan(op.off, op.n);
  }
  at = ptr;
  return ed_.pool();
}

Rgba8 NodeWrites::child_avg(const TaskWrites& w, const GeneralNode& n, int c) const {
  uint32_t at = 0;
  if (n.kind[c] == CellKind::general)
    return block(w, n.ptr[c], at)[at + 2 * uint32_t(popc(octree::generals(n.info[c]))) +
                                  uint32_t(popc(octree::bricks(n.info[c])))];
  if (n.kind[c] == CellKind::brick) {
    const uint32_t word = n.ptr[c];
    return block(w, word & ~octree::kBrickDoubleFlag,
                 at)[at + 2 + ((word & octree::kBrickDoubleFlag) ? 2 : 0)];
  }
  return 0;
}

Rgba8 NodeWrites::general_avg(const TaskWrites& w, const GeneralNode& n) const {
  ColorMean m;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::leaf) add_leaf(m, n.leaf[c]);
    if (n.kind[c] == CellKind::general || n.kind[c] == CellKind::brick) m.add(child_avg(w, n, c));
  }
  return m.mean();
}

uint32_t NodeWrites::put_block(TaskWrites& w, uint32_t old_ptr, uint32_t old_n, bool brick,
                               int generals, int bricks) {
  if (!w.log) return ed_.replace_block(old_ptr, old_n, w.words, brick);
  WriteLog& log = *w.log;
  WriteLog::Op op;
  op.kind = WriteLog::kStore, op.brick = brick;
  op.generals = uint8_t(generals), op.bricks = uint8_t(bricks);
  op.ptr = old_ptr, op.old_n = old_n;
  op.off = uint32_t(log.words.size()), op.n = uint32_t(w.words.size());
  log.words.insert(log.words.end(), w.words.begin(), w.words.end());
  // The slot's index is the address: each slot written once, whole, by the thread whose log
  // took it.
  if (log.next == log.end) {
    const auto first = where_.grow_by(kTempChunk);
    log.next = uint32_t(first - where_.begin()), log.end = log.next + kTempChunk;
  }
  const uint32_t slot = log.next++;
  where_[slot] = {&log, uint32_t(log.ops.size())};
  op.temp = temp0_ + slot;
  log.ops.push_back(op);
  return op.temp;
}

void NodeWrites::release(TaskWrites& w, uint32_t ptr, uint32_t n, bool brick) {
  if (!w.log) return ed_.release(ptr, n, brick);
  WriteLog::Op op{};
  op.kind = WriteLog::kRelease, op.brick = brick, op.ptr = ptr, op.old_n = n;
  w.log->ops.push_back(op);
}

void NodeWrites::replay(WriteLog& log) {
  for (const WriteLog::Op& op : log.ops) {
    if (op.kind == WriteLog::kChild) {
      replay(*log.children[op.off]);
      continue;
    }
    if (op.kind == WriteLog::kRelease) {
      ed_.release(resolve(op.ptr), op.old_n, op.brick);
      continue;
    }
    const std::span<uint32_t> words = std::span<uint32_t>(log.words).subspan(op.off, op.n);
    for (uint32_t k = 0; k < op.generals; ++k) words[2 * k] = resolve(words[2 * k]);
    for (uint32_t k = 0; k < op.bricks; ++k)
      words[2 * op.generals + k] = resolve_brick(words[2 * op.generals + k]);
    real_[op.temp - temp0_] = ed_.replace_block(resolve(op.ptr), op.old_n, words, op.brick);
  }
}

void NodeWrites::store_general(TaskWrites& w, const GeneralNode& n, uint32_t old_ptr,
                               uint32_t old_info, uint32_t& ptr, uint32_t& info) {
  info = encode_general(n, w.words);
  const uint32_t old_n = old_ptr ? general_block_words(old_info) : 0;
  ptr =
      put_block(w, old_ptr, old_n, false, popc(octree::generals(info)), popc(octree::bricks(info)));
}

uint32_t NodeWrites::store_brick(TaskWrites& w, const Brick& b, uint32_t old_word,
                                 const Brick* old) {
  const uint32_t flag = encode_brick(b, w.words);
  const uint32_t old_ptr = old_word & ~octree::kBrickDoubleFlag;
  const uint32_t old_n = old ? brick_block_words(old->mask, old->dbl) : 0;
  return put_block(w, old_ptr, old_n, true, 0, 0) | flag;
}

}  // namespace limn::detail
