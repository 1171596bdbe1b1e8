// The refiner's kept triangle lists: see kept_lists.hpp.
#include "kept_lists.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <tbb/parallel_for.h>

#include "surface_impl.hpp"

namespace limn::detail {

using namespace paint_detail;

std::shared_ptr<const StartLists> StartLists::of(const CellBoxes& cells) {
  const PaintSurface& surf = cells.surface();
  const double* origin = cells.origin();
  const float slack = cells.slack();
  const double size = cells.cell_size(0);
  {
    std::lock_guard<std::mutex> lock(surf.impl().derived_mutex);
    auto kept = std::static_pointer_cast<const StartLists>(surf.impl().derived);
    if (kept && kept->size_ == size && kept->origin_[0] == origin[0] &&
        kept->origin_[1] == origin[1] && kept->origin_[2] == origin[2])
      return kept;
  }
  // Each triangle against the start cells its bounds reach (grown by the slack and by the
  // rounding of the boxes' float centres), with the test triangles_in_box makes on the boxes
  // box() gives: the same lists.
  const int level = octree::kStartDepth;
  const uint32_t n = 1u << level;
  const double s = cells.cell_size(level);
  auto lists = std::make_shared<StartLists>();
  for (int a = 0; a < 3; ++a) lists->origin_[a] = origin[a];
  lists->size_ = size;
  double grow[3];
  for (int a = 0; a < 3; ++a)
    grow[a] = 2 * double(slack) +
              8 * double(std::numeric_limits<float>::epsilon()) * (std::fabs(origin[a]) + size);
  std::vector<CellBox> boxes(size_t(n) * n * n);
  for (uint32_t z = 0; z < n; ++z)
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) boxes[x + n * (y + n * z)] = cells.box(level, x, y, z);
  // In chunks of triangles on TBB's threads, each chunk's (cell, triangle) pairs in index order.
  constexpr uint32_t kTris = 8192;
  const uint32_t count = uint32_t(surf.triangle_count());
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> parts((count + kTris - 1) / kTris);
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t part) {
    std::vector<std::pair<uint32_t, uint32_t>>& hits = parts[part];
    for (uint32_t t = uint32_t(part) * kTris; t < std::min(count, uint32_t(part + 1) * kTris);
         ++t) {
      if (surf.degenerate(t)) continue;
      uint32_t lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        double mn = INFINITY, mx = -INFINITY;
        for (int k = 0; k < 3; ++k)
          mn = std::min(mn, double(surf.corner(t, k)[a])),
          mx = std::max(mx, double(surf.corner(t, k)[a]));
        const double l = std::floor((mn - grow[a] - origin[a]) / s),
                     h = std::floor((mx + grow[a] - origin[a]) / s);
        lo[a] = uint32_t(std::clamp(l, 0.0, double(n - 1)));
        hi[a] = uint32_t(std::clamp(h, 0.0, double(n - 1)));
      }
      const V3 p0 = v3(surf.corner(t, 0)), p1 = v3(surf.corner(t, 1)), p2 = v3(surf.corner(t, 2));
      for (uint32_t z = lo[2]; z <= hi[2]; ++z)
        for (uint32_t y = lo[1]; y <= hi[1]; ++y)
          for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
            const uint32_t cell = x + n * (y + n * z);
            const CellBox& b = boxes[cell];
            if (tri_meets_box(b.c, b.h, p0, p1, p2, slack)) hits.push_back({cell, t});
          }
    }
  });
  // Counted, then placed: each cell's triangles in index order.
  lists->start_.assign(size_t(n) * n * n + 1, 0);
  for (const auto& hits : parts)
    for (const auto& h : hits) ++lists->start_[h.first + 1];
  for (size_t i = 1; i < lists->start_.size(); ++i) lists->start_[i] += lists->start_[i - 1];
  lists->tris_.resize(lists->start_.back());
  std::vector<uint32_t> pos(lists->start_.begin(), lists->start_.end() - 1);
  for (const auto& hits : parts)
    for (const auto& h : hits) lists->tris_[pos[h.first]++] = h.second;
  {
    std::lock_guard<std::mutex> lock(surf.impl().derived_mutex);
    surf.impl().derived = lists;
  }
  return lists;
}

std::span<const uint32_t> StartLists::list(uint32_t x, uint32_t y, uint32_t z) const {
  const uint32_t n = 1u << octree::kStartDepth;
  const size_t i = x + n * (y + size_t(n) * z);
  return std::span<const uint32_t>(tris_).subspan(start_[i], start_[i + 1] - start_[i]);
}

}  // namespace limn::detail
