// Triangle lists the refiner keeps across runs instead of finding again: the start cells' lists
// of a texture cube (made once per cube and surface, shared by every refiner of the surface), and
// the leaves' lists of the bricks a stroke's dabs visit. Internal header of the paint layer.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <vector>

#include "cell_boxes.hpp"

namespace limn::detail {

/// The triangles meeting each start cell (level octree::kStartDepth) of a texture cube, sorted:
/// exactly what triangles_in_box gives for the cell's box.
class StartLists {
 public:
  /// The table for `boxes`' cube over its surface: the one kept with the surface when it is for
  /// the same cube, else made (O(T), on TBB's threads) and kept there in its place.
  static std::shared_ptr<const StartLists> of(const CellBoxes& cells);
  /// Start cell (x, y, z)'s list.
  std::span<const uint32_t> list(uint32_t x, uint32_t y, uint32_t z) const;

 private:
  double origin_[3], size_;
  std::vector<uint32_t> start_;  // per cell (x + n (y + n z)), its list's first index in tris_
  std::vector<uint32_t> tris_;
};

/// Per brick (by level and Morton code), which of its leaves' lists are known and the lists,
/// kept across the runs of a stroke (Refiner::keep_brick_lists).
struct KeptBricks {
  struct Brick {
    uint64_t known = 0;         ///< leaves whose lists are known (len 0: none meets it)
    uint32_t off[64], len[64];  ///< leaf m's list: tris[off[m], off[m] + len[m])
  };
  std::unordered_map<uint64_t, uint32_t> index;
  std::vector<Brick> bricks;
  std::vector<uint32_t> tris;

  /// The brick `key`'s entry (made empty on first use) and its index.
  Brick& find(uint64_t key, uint32_t& i) {
    const auto [it, added] = index.try_emplace(key, uint32_t(bricks.size()));
    if (added) bricks.emplace_back();
    i = it->second;
    return bricks[i];
  }
  /// Leaf m's kept list.
  std::span<const uint32_t> list(const Brick& b, int m) const {
    return std::span<const uint32_t>(tris.data() + b.off[m], b.len[m]);
  }
  /// Keeps `list` as leaf m's.
  void keep(Brick& b, int m, std::span<const uint32_t> list) {
    b.off[m] = uint32_t(tris.size()), b.len[m] = uint32_t(list.size());
    tris.insert(tris.end(), list.begin(), list.end());
  }
};

}  // namespace limn::detail
