// Undo/redo per stroke by replaying the pool journal backwards or forwards.
#include "limn/paint/undo.hpp"

#include <stdexcept>

#include "octree_blocks.hpp"

namespace limn {

using detail::OctreeEditor;
using Op = OctreeTexture::JournalOp;

PaintHistory::PaintHistory(size_t max_strokes, size_t max_bytes)
    : max_strokes_(max_strokes ? max_strokes : 1), max_bytes_(max_bytes) {}

void PaintHistory::begin(OctreeTexture& t) {
  if (OctreeEditor::recording(t)) throw std::logic_error("PaintHistory::begin: already recording");
  OctreeEditor::journal(t).clear();
  OctreeEditor::recording(t) = true;
}

size_t PaintHistory::end(OctreeTexture& t) {
  if (!OctreeEditor::recording(t)) throw std::logic_error("PaintHistory::end: not recording");
  OctreeEditor::recording(t) = false;
  std::vector<Op>& j = OctreeEditor::journal(t);
  if (j.empty()) return 0;
  Record r;
  r.ops = std::move(j);
  j = {};
  const size_t bytes = r.ops.size() * sizeof(Op);
  done_.push_back(std::move(r));
  undone_.clear();
  while (done_.size() > 1 && (done_.size() > max_strokes_ || this->bytes() > max_bytes_))
    done_.erase(done_.begin());
  return bytes;
}

bool PaintHistory::undo(OctreeTexture& t) {
  if (done_.empty()) return false;
  OctreeEditor::undo_ops(t, done_.back().ops);
  undone_.push_back(std::move(done_.back()));
  done_.pop_back();
  return true;
}

bool PaintHistory::redo(OctreeTexture& t) {
  if (undone_.empty()) return false;
  OctreeEditor::redo_ops(t, undone_.back().ops);
  done_.push_back(std::move(undone_.back()));
  undone_.pop_back();
  return true;
}

void PaintHistory::clear() {
  done_.clear();
  undone_.clear();
}

size_t PaintHistory::bytes() const {
  size_t n = 0;
  for (const Record& r : done_) n += r.ops.size() * sizeof(Op);
  for (const Record& r : undone_) n += r.ops.size() * sizeof(Op);
  return n;
}

}  // namespace limn
