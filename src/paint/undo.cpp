// Undo/redo per stroke by replaying the pool journal backwards or forwards.
#include "limn/paint/undo.hpp"

#include <stdexcept>

#include "limn/paint/material.hpp"
#include "octree_blocks.hpp"

namespace limn {

using detail::OctreeEditor;
using Op = OctreeTexture::JournalOp;

PaintHistory::PaintHistory(size_t max_strokes, size_t max_bytes)
    : max_strokes_(max_strokes ? max_strokes : 1), max_bytes_(max_bytes) {}

void PaintHistory::start(OctreeTexture& t) {
  if (OctreeEditor::recording(t)) throw std::logic_error("PaintHistory::begin: already recording");
  OctreeEditor::journal(t).clear();
  OctreeEditor::recording(t) = true;
}

namespace {

std::vector<Op> stop(OctreeTexture& t) {
  if (!OctreeEditor::recording(t)) throw std::logic_error("PaintHistory::end: not recording");
  OctreeEditor::recording(t) = false;
  std::vector<Op> ops = std::move(OctreeEditor::journal(t));
  OctreeEditor::journal(t) = {};
  return ops;
}

}  // namespace

size_t PaintHistory::keep(Record r) {
  if (r.ops.empty() && r.rmh_ops.empty()) return 0;
  const size_t bytes = (r.ops.size() + r.rmh_ops.size()) * sizeof(Op);
  done_.push_back(std::move(r));
  undone_.clear();
  while (done_.size() > 1 && (done_.size() > max_strokes_ || this->bytes() > max_bytes_))
    done_.erase(done_.begin());
  return bytes;
}

void PaintHistory::begin(OctreeTexture& t) {
  start(t);
}

size_t PaintHistory::end(OctreeTexture& t) {
  Record r;
  r.ops = stop(t);
  return keep(std::move(r));
}

bool PaintHistory::undo(OctreeTexture& t) {
  if (done_.empty()) return false;
  if (!done_.back().rmh_ops.empty())
    throw std::logic_error("PaintHistory::undo: the stroke painted a material");
  OctreeEditor::undo_ops(t, done_.back().ops);
  undone_.push_back(std::move(done_.back()));
  done_.pop_back();
  return true;
}

bool PaintHistory::redo(OctreeTexture& t) {
  if (undone_.empty()) return false;
  if (!undone_.back().rmh_ops.empty())
    throw std::logic_error("PaintHistory::redo: the stroke painted a material");
  OctreeEditor::redo_ops(t, undone_.back().ops);
  done_.push_back(std::move(undone_.back()));
  undone_.pop_back();
  return true;
}

void PaintHistory::begin(MaterialTexture& m) {
  start(m.color);
  if (m.rmh) start(*m.rmh);
}

size_t PaintHistory::end(MaterialTexture& m) {
  Record r;
  r.ops = stop(m.color);
  if (m.rmh) r.rmh_ops = stop(*m.rmh);
  return keep(std::move(r));
}

bool PaintHistory::undo(MaterialTexture& m) {
  if (done_.empty()) return false;
  const Record& r = done_.back();
  if (!r.rmh_ops.empty() && !m.rmh)
    throw std::logic_error("PaintHistory::undo: the material has no RMH texture");
  OctreeEditor::undo_ops(m.color, r.ops);
  if (!r.rmh_ops.empty()) OctreeEditor::undo_ops(*m.rmh, r.rmh_ops);
  undone_.push_back(std::move(done_.back()));
  done_.pop_back();
  return true;
}

bool PaintHistory::redo(MaterialTexture& m) {
  if (undone_.empty()) return false;
  const Record& r = undone_.back();
  if (!r.rmh_ops.empty() && !m.rmh)
    throw std::logic_error("PaintHistory::redo: the material has no RMH texture");
  OctreeEditor::redo_ops(m.color, r.ops);
  if (!r.rmh_ops.empty()) OctreeEditor::redo_ops(*m.rmh, r.rmh_ops);
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
  for (const Record& r : done_) n += (r.ops.size() + r.rmh_ops.size()) * sizeof(Op);
  for (const Record& r : undone_) n += (r.ops.size() + r.rmh_ops.size()) * sizeof(Op);
  return n;
}

}  // namespace limn
