#include "atlas/pack.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>
#include <numeric>

namespace limn::atlas {

ChartExtent orient_chart(Chart& ch) {
  const size_t n = ch.uv.size() / 2;
  // Convex hull (Andrew's monotone chain) of the UV points.
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto x = [&](uint32_t i) { return ch.uv[2 * size_t(i)]; };
  auto y = [&](uint32_t i) { return ch.uv[2 * size_t(i) + 1]; };
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return x(a) < x(b) || (x(a) == x(b) && y(a) < y(b)); });
  auto cross = [&](uint32_t o, uint32_t a, uint32_t b) {
    return (x(a) - x(o)) * (y(b) - y(o)) - (y(a) - y(o)) * (x(b) - x(o));
  };
  std::vector<uint32_t> hull(2 * n);
  size_t k = 0;
  for (size_t i = 0; i < n; ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], order[i]) <= 0) --k;
    hull[k++] = order[i];
  }
  for (size_t i = n - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], order[i]) <= 0) --k;
    hull[k++] = order[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  double hull_area = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    const uint32_t a = hull[i], b = hull[(i + 1) % hull.size()];
    hull_area += 0.5 * (x(a) * y(b) - x(b) * y(a));
  }

  // The smallest bounding rectangle has a side along a hull edge.
  double best_area = INFINITY, best_c = 1, best_s = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    const uint32_t a = hull[i], b = hull[(i + 1) % hull.size()];
    const double dx = x(b) - x(a), dy = y(b) - y(a), len = std::hypot(dx, dy);
    if (!(len > 0)) continue;
    const double c = dx / len, s = dy / len;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t h : hull) {
      const double p = x(h) * c + y(h) * s, q = -x(h) * s + y(h) * c;
      lo[0] = std::min(lo[0], p), hi[0] = std::max(hi[0], p);
      lo[1] = std::min(lo[1], q), hi[1] = std::max(hi[1], q);
    }
    const double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    if (area < best_area) best_area = area, best_c = c, best_s = s;
  }
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < n; ++i) {
    const double p = x(uint32_t(i)) * best_c + y(uint32_t(i)) * best_s;
    const double q = -x(uint32_t(i)) * best_s + y(uint32_t(i)) * best_c;
    ch.uv[2 * i] = p, ch.uv[2 * i + 1] = q;
    lo[0] = std::min(lo[0], p), hi[0] = std::max(hi[0], p);
    lo[1] = std::min(lo[1], q), hi[1] = std::max(hi[1], q);
  }
  ChartExtent e{hi[0] - lo[0], hi[1] - lo[1], hull_area};
  const bool turn = e.height > e.width;
  for (size_t i = 0; i < n; ++i) {
    const double p = ch.uv[2 * i] - lo[0], q = ch.uv[2 * i + 1] - lo[1];
    // A quarter turn counter-clockwise (no mirror), back into the positive quadrant.
    ch.uv[2 * i] = turn ? e.height - q : p;
    ch.uv[2 * i + 1] = turn ? p : q;
  }
  if (turn) std::swap(e.width, e.height);
  return e;
}

namespace {

// A chart rasterised at one density and turn: its padded box and its runs of texels (gutter
// included), row by row.
struct Raster {
  int w = 0, h = 0;
  std::vector<uint32_t> row_runs{0};      ///< row y's runs are runs[row_runs[y] .. row_runs[y+1])
  std::vector<std::pair<int, int>> runs;  ///< (first column, length)
  size_t covered = 0;                     ///< texels the triangles touch, before padding
  size_t taken = 0;                       ///< texels of the runs (padding included)
};

// Marks every texel of the w x h grid that the triangle touches (closed texel squares).
void cover_triangle(const double px[3], const double py[3], int w, int h,
                    std::vector<uint8_t>& grid) {
  const double ylo = std::min({py[0], py[1], py[2]}), yhi = std::max({py[0], py[1], py[2]});
  const int r0 = std::max(0, int(std::floor(ylo)));
  const int r1 = std::min(h - 1, std::max(r0, int(std::ceil(yhi)) - 1));
  for (int r = r0; r <= r1; ++r) {
    const double lo = r, hi = r + 1;
    double xmin = INFINITY, xmax = -INFINITY;
    for (int i = 0; i < 3; ++i) {
      if (py[i] >= lo && py[i] <= hi) xmin = std::min(xmin, px[i]), xmax = std::max(xmax, px[i]);
      const int j = (i + 1) % 3;
      for (double line : {lo, hi})
        if ((py[i] - line) * (py[j] - line) < 0) {
          const double xi = px[i] + (px[j] - px[i]) * (line - py[i]) / (py[j] - py[i]);
          xmin = std::min(xmin, xi), xmax = std::max(xmax, xi);
        }
    }
    if (!(xmin <= xmax)) continue;
    const int c0 = std::max(0, int(std::floor(xmin)));
    const int c1 = std::min(w - 1, std::max(c0, int(std::ceil(xmax)) - 1));
    std::fill(grid.begin() + size_t(r) * w + c0, grid.begin() + size_t(r) * w + c1 + 1, 1);
  }
}

Raster rasterise(const Chart& ch, const Pose& pose, double density, int pad) {
  Raster r;
  const double cw = pose.width * density, chh = pose.height * density;
  r.w = int(std::ceil(cw)) + 2 * pad + 1;
  r.h = int(std::ceil(chh)) + 2 * pad + 1;
  std::vector<uint8_t> grid(size_t(r.w) * r.h, 0);
  const Placement at{};
  for (size_t t = 0; t < ch.triangles.size(); t += 3) {
    double px[3], py[3];
    for (int i = 0; i < 3; ++i) {
      const uint32_t v = ch.triangles[t + i];
      double texel[2];
      placed_texel(ch.uv[2 * size_t(v)], ch.uv[2 * size_t(v) + 1], pose, at, density, pad, texel);
      px[i] = texel[0], py[i] = texel[1];
    }
    cover_triangle(px, py, r.w, r.h, grid);
  }
  for (uint8_t g : grid) r.covered += g;
  // Grow by the padding (a square window): rows, then columns.
  if (pad > 0) {
    std::vector<uint8_t> rows(grid.size(), 0);
    for (int y = 0; y < r.h; ++y)
      for (int x = 0; x < r.w; ++x)
        if (grid[size_t(y) * r.w + x])
          std::fill(rows.begin() + size_t(y) * r.w + std::max(0, x - pad),
                    rows.begin() + size_t(y) * r.w + std::min(r.w - 1, x + pad) + 1, 1);
    std::fill(grid.begin(), grid.end(), 0);
    for (int y = 0; y < r.h; ++y)
      for (int x = 0; x < r.w; ++x)
        if (rows[size_t(y) * r.w + x])
          for (int yy = std::max(0, y - pad); yy <= std::min(r.h - 1, y + pad); ++yy)
            grid[size_t(yy) * r.w + x] = 1;
  }
  for (int y = 0; y < r.h; ++y) {
    const uint8_t* row = &grid[size_t(y) * r.w];
    for (int x = 0; x < r.w;) {
      if (!row[x]) {
        ++x;
        continue;
      }
      const int x0 = x;
      while (x < r.w && row[x]) ++x;
      r.runs.emplace_back(x0, x - x0);
      r.taken += size_t(x - x0);
    }
    r.row_runs.push_back(uint32_t(r.runs.size()));
  }
  while (r.h > 0 && r.row_runs[r.h] == r.row_runs[r.h - 1]) r.row_runs.pop_back(), --r.h;
  return r;
}

// One tile: which texels are taken, and per texel the free run to its right.
class Tile {
 public:
  explicit Tile(int size) : size_(size), run_(size_t(size) * size), longest_(size, size) {
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) run_[size_t(y) * size + x] = int16_t(size - x);
  }
  // The lowest row under `y_end` (then the leftmost column) where the chart fits; false when
  // it fits nowhere below.
  bool lowest_fit(const Raster& r, int y_end, int& best_x, int& best_y) const {
    if (r.w > size_ || r.h > size_) return false;
    // The chart's longest run rules out every row whose longest free run is shorter.
    int key_row = 0, key_length = 0;
    for (int row = 0; row < r.h; ++row)
      for (uint32_t i = r.row_runs[row]; i < r.row_runs[row + 1]; ++i)
        if (r.runs[i].second > key_length) key_length = r.runs[i].second, key_row = row;
    int blocking_row = key_row;  // tried first: the row that failed last fails again most often
    y_end = std::min(y_end, size_ - r.h + 1);
    for (int y = 0; y < y_end; ++y) {
      if (longest_[y + key_row] < key_length) continue;
      for (int x = 0; x + r.w <= size_;) {
        int skip = 0;
        for (int k = 0; k < r.h && !skip; ++k) {
          const int row = k == 0 ? blocking_row : (k <= blocking_row ? k - 1 : k);
          const int16_t* line = &run_[size_t(y + row) * size_ + x];
          for (uint32_t i = r.row_runs[row]; i < r.row_runs[row + 1] && !skip; ++i) {
            const auto [first, length] = r.runs[i];
            const int here = line[first];
            if (here >= length) continue;
            // Every start that puts this run over the taken texels ahead fails: jump past them.
            const int free = std::max(here, 0);
            const int taken = x + first + free < size_ ? -line[first + free] : 1;
            skip = free + taken, blocking_row = row;
          }
        }
        if (!skip) {
          best_x = x, best_y = y;
          return true;
        }
        x += skip;
      }
    }
    return false;
  }
  void take(const Raster& r, int x0, int y0) {
    for (int row = 0; row < r.h; ++row) {
      int16_t* run = &run_[size_t(y0 + row) * size_];
      for (uint32_t i = r.row_runs[row]; i < r.row_runs[row + 1]; ++i) {
        const auto [first, length] = r.runs[i];
        const int a = x0 + first, b = a + length;
        for (int x = b - 1; x >= a; --x)
          run[x] = int16_t(x + 1 < size_ && run[x + 1] < 0 ? run[x + 1] - 1 : -1);
        // The runs left of it now end at it (free ones) or go on through it (taken ones).
        if (a > 0 && run[a - 1] < 0)
          for (int x = a - 1; x >= 0 && run[x] < 0; --x) run[x] = int16_t(run[x + 1] - 1);
        else
          for (int x = a - 1; x >= 0 && run[x] > 0; --x)
            run[x] = int16_t(run[x + 1] > 0 ? run[x + 1] + 1 : 1);
      }
      int longest = 0;
      for (int x = 0; x < size_; x += std::abs(run[x])) longest = std::max(longest, int(run[x]));
      longest_[y0 + row] = longest;
    }
  }

 private:
  int size_;
  /// Per texel: the free texels from it to the right (> 0), or minus the taken ones (< 0).
  std::vector<int16_t> run_;
  std::vector<int> longest_;  ///< per row: its longest free run
};

// Places the rasterised charts in `order`, each at the turn and lowest row (then leftmost
// column) where it fits with its top lowest. Returns the position in `order` of the first chart
// that fits in no tile allowed, or order.size() when all fit.
size_t place_all(const std::vector<std::vector<Raster>>& raster,
                 const std::vector<std::vector<Pose>>& poses, const std::vector<uint32_t>& order,
                 const PackOptions& o, Packing& out) {
  const size_t n = order.size();
  std::vector<Tile> tiles;
  out.placements.assign(n, {});
  out.poses.assign(n, {});
  out.covered = 0;
  out.taken = 0;
  for (size_t at = 0; at < n; ++at) {
    const uint32_t i = order[at];
    bool placed = false;
    for (int t = 0; t < o.tiles && !placed; ++t) {
      if (size_t(t) == tiles.size()) tiles.emplace_back(o.size);
      int best_top = INT_MAX, best_x = 0, best_y = 0, best_turn = 0;
      for (int turn = 0; turn < o.turns; ++turn) {
        int x = 0, y = 0;
        const Raster& r = raster[turn][i];
        const int y_end = best_top == INT_MAX ? INT_MAX : best_top - r.h;
        if (tiles[t].lowest_fit(r, y_end, x, y) && y + r.h < best_top)
          best_top = y + r.h, best_x = x, best_y = y, best_turn = turn;
      }
      if (best_top == INT_MAX) continue;
      const Raster& r = raster[best_turn][i];
      tiles[t].take(r, best_x, best_y);
      out.placements[i] = {uint32_t(t), best_turn, best_x, best_y};
      out.poses[i] = poses[i][best_turn];
      out.covered += r.covered;
      out.taken += r.taken;
      placed = true;
    }
    if (!placed) return at;
  }
  out.tiles = tiles.size();
  return n;
}

// One packing at `density`; false when the charts do not fit in the tiles allowed. Greedy
// placement depends much on the order, so three orders are tried (largest area, tallest, longest
// outline first) and the first that fits is kept.
bool pack_at(const std::vector<Chart>& charts, const std::vector<std::vector<Pose>>& poses,
             double density, const PackOptions& o, Packing& out) {
  const size_t n = charts.size();
  auto raster = std::vector<std::vector<Raster>>(size_t(o.turns), std::vector<Raster>(n));
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    for (int t = 0; t < o.turns; ++t)
      raster[t][i] = rasterise(charts[i], poses[i][t], density, o.padding);
  });
  std::vector<uint32_t> order(n);
  for (int by = 0; by < 3; ++by) {
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      const Raster &ra = raster[0][a], &rb = raster[0][b];
      const size_t ka = by == 0 ? ra.covered : by == 1 ? size_t(ra.h) : size_t(ra.w + ra.h);
      const size_t kb = by == 0 ? rb.covered : by == 1 ? size_t(rb.h) : size_t(rb.w + rb.h);
      return ka > kb;
    });
    if (place_all(raster, poses, order, o, out) == n) {
      out.texels_per_unit = density;
      return true;
    }
  }
  return false;
}

}  // namespace

Pose chart_pose(const Chart& ch, int turn, int turns) {
  const double angle = 2 * std::numbers::pi * turn / turns;
  Pose p;
  p.c = std::cos(angle), p.s = std::sin(angle);
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t v = 0; v < ch.uv.size(); v += 2) {
    const double x = p.c * ch.uv[v] - p.s * ch.uv[v + 1], y = p.s * ch.uv[v] + p.c * ch.uv[v + 1];
    lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
    lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
  }
  p.ox = -lo[0], p.oy = -lo[1], p.width = hi[0] - lo[0], p.height = hi[1] - lo[1];
  return p;
}

Packing pack_charts(const std::vector<Chart>& charts, const PackOptions& o) {
  std::vector<std::vector<Pose>> poses(charts.size());
  tbb::parallel_for(size_t(0), charts.size(), [&](size_t i) {
    for (int t = 0; t < o.turns; ++t) poses[i].push_back(chart_pose(charts[i], t, o.turns));
  });
  Packing best;
  if (o.texels_per_unit > 0) {
    best.fits = pack_at(charts, poses, o.texels_per_unit, o, best);
    return best;
  }
  double area = 0;
  for (const Chart& ch : charts) area += ch.area;
  if (!(area > 0)) return best;
  // Densities in steps of 3% from a first guess (charts and padding filling 3/4 of the tiles),
  // up while the charts fit or down until they do, then the last step halved a few times. Greedy
  // packing is not monotonic in the density (a denser try can succeed where a sparser one
  // failed), so a plain bisection would stop early.
  const double ceiling = o.size * std::sqrt(o.tiles / area);  // charts covering every texel
  double lo = ceiling * std::sqrt(0.75);
  best.fits = pack_at(charts, poses, lo, o, best);
  if (best.fits) {
    Packing denser;
    while (lo / 0.97 <= ceiling && pack_at(charts, poses, lo / 0.97, o, denser)) {
      lo /= 0.97;
      std::swap(best, denser);
    }
    best.fits = true;
  }
  while (!best.fits) {
    lo *= 0.97;
    if (lo < ceiling * 1e-6) return best;  // too many charts for the tiles at any density
    best.fits = pack_at(charts, poses, lo, o, best);
  }
  Packing trial;
  const double first_fit = lo;
  double hi = std::min(ceiling, lo / 0.97);
  for (int step = 0; step < 4; ++step) {
    const double mid = std::sqrt(lo * hi);
    if (pack_at(charts, poses, mid, o, trial)) {
      lo = mid;
      std::swap(best, trial);
      best.fits = true;
    } else {
      hi = mid;
    }
  }
  // Greedy packing is chaotic in the density: a few denser tries past the first failure, in 1%
  // steps, often find one that fits; the densest that does is kept.
  for (int step = 1; step <= 8; ++step) {
    const double d = first_fit * (1 + 0.01 * step);
    if (d > ceiling) break;
    if (d <= best.texels_per_unit) continue;
    if (pack_at(charts, poses, d, o, trial)) std::swap(best, trial), best.fits = true;
  }
  return best;
}

}  // namespace limn::atlas
