// limn paint: undo and redo per stroke. A stroke's record is the journal of every pool word it
// changed (old and new value), the pool's growth and the free-list pushes and pops, so undo gives
// back the exact bytes, however the stroke refined, relocated or recycled blocks.
#pragma once

#include <cstddef>
#include <vector>

#include "limn/paint/texture.hpp"

namespace limn {

struct MaterialTexture;

class PaintHistory {
 public:
  /// Keeps at most `max_strokes` undoable strokes and about `max_bytes` of records (the oldest
  /// go first; the newest stroke is always kept).
  explicit PaintHistory(size_t max_strokes = 256, size_t max_bytes = size_t(1) << 30);

  /// Starts recording a stroke on `t`. Precondition: not already recording on t. O(1).
  void begin(OctreeTexture& t);
  /// Ends the stroke: it becomes the newest undoable one and the redo list is cleared. A stroke
  /// that changed nothing is dropped. Returns the record's size in bytes. O(1).
  size_t end(OctreeTexture& t);
  /// Undoes the newest stroke; false when there is none. O(words the stroke changed).
  /// Precondition: `t` is the texture the strokes were recorded on, unchanged since but for
  /// undo/redo through this history.
  bool undo(OctreeTexture& t);
  /// Redoes the most recently undone stroke; false when there is none.
  bool redo(OctreeTexture& t);

  /// The same for a material: one record per stroke holds the writes to its colour and RMH
  /// textures. Precondition: an RMH texture a stroke will paint exists before begin().
  void begin(MaterialTexture& m);
  size_t end(MaterialTexture& m);
  bool undo(MaterialTexture& m);
  bool redo(MaterialTexture& m);
  /// Forgets every record (after the texture was replaced or edited outside the history).
  void clear();

  size_t undo_count() const { return done_.size(); }
  size_t redo_count() const { return undone_.size(); }
  /// Bytes held by the records.
  size_t bytes() const;

 private:
  struct Record {
    std::vector<OctreeTexture::JournalOp> ops, rmh_ops;
  };
  void start(OctreeTexture& t);
  size_t keep(Record r);
  std::vector<Record> done_, undone_;
  size_t max_strokes_, max_bytes_;
};

}  // namespace limn
