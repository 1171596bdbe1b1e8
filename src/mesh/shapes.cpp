// limn procedural shapes: cube, tori and terrains with placed extraordinary vertices, and a tagged
// crease cage. Everything is built on flat arrays in one pass so the ~800k-quad shapes take tens
// of milliseconds, and everything is deterministic: the only randomness is a seeded splitmix64.
#include "limn/mesh/shapes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace limn {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTorusMajor = 1.0, kTorusMinor = 0.4;

// splitmix64 (Steele, Lea, Flood 2014). std::uniform_int_distribution and friends may produce
// different sequences on different standard libraries; this is bit-identical everywhere.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, n) for n > 0 (the modulo bias is below 2^-50 for the small n used here).
  int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
  /// Uniform in [0, 1) with 53 random bits.
  double unit() { return static_cast<double>(next() >> 11) * 0x1p-53; }

 private:
  uint64_t state_;
};

/// A rectangle of a x b grid cells starting at cell (i0, j0), to be replaced by a fan of a + b
/// quads around a new centre vertex of valence a + b.
struct Block {
  int i0 = 0, j0 = 0, a = 0, b = 0;
};

/// Block size for valence n as used by the torus and terrain: a + b = n with a and b both even
/// when n is even (then every rectangle corner falls on a spoke-free ring position, see
/// build_grid) and as square as possible otherwise.
std::pair<int, int> even_block_shape(int n) {
  if (n % 2 != 0) return {(n - 1) / 2, (n + 1) / 2};
  const int a = (n / 2) % 2 == 0 ? n / 2 : n / 2 - 1;
  return {a, n - a};
}

/// Builds a W x H grid of quads with the given blocks replaced by fans. Vertex (i, j) of the grid
/// sits at pos(i, j, out); block centres at pos of the block's mean grid coordinate. With
/// `periodic` both directions wrap (a torus, W x H vertices); otherwise there are (W+1) x (H+1)
/// vertices and one boundary loop. Quad (i, j) is counter-clockwise in (i, j), so the caller picks
/// the outward side through the parametrisation. Blocks must not wrap and must not share a vertex
/// with each other (nor, without `periodic`, with the boundary): callers guarantee that, and a
/// violation throws std::logic_error rather than producing a non-manifold mesh.
template <class Pos>
Mesh build_grid(int W, int H, bool periodic, const std::vector<Block>& blocks, Pos&& pos) {
  const int vw = periodic ? W : W + 1, vh = periodic ? H : H + 1;
  if (size_t(vw) * size_t(vh) + blocks.size() > UINT32_MAX ||
      size_t(W) * size_t(H) * 4 > UINT32_MAX)
    throw std::invalid_argument(fmt::format("shapes: a {} x {} grid exceeds 32-bit indices", W, H));
  // Grid coordinates never exceed W (resp. H), so one conditional subtraction wraps them.
  auto vid = [&](int i, int j) -> size_t {
    if (periodic) {
      if (i >= W) i -= W;
      if (j >= H) j -= H;
    }
    return size_t(j) * size_t(vw) + size_t(i);
  };

  // 0: plain grid vertex, 1: on a block's rectangle (kept, becomes ring), 2: strictly inside a
  // block (dropped). Marking the whole closed rectangle catches blocks that touch each other.
  std::vector<uint8_t> vstate(size_t(vw) * size_t(vh), 0);
  std::vector<uint8_t> cell_gone(size_t(W) * size_t(H), 0);
  size_t gone_cells = 0, fan_quads = 0;
  const int lo = periodic ? 0 : 1;  // open grids keep blocks off the boundary
  for (const Block& k : blocks) {
    if (k.a < 1 || k.b < 1 || k.i0 < lo || k.j0 < lo || k.i0 + k.a > W - lo || k.j0 + k.b > H - lo)
      throw std::logic_error("shapes: block outside the grid");
    for (int j = k.j0; j <= k.j0 + k.b; ++j)
      for (int i = k.i0; i <= k.i0 + k.a; ++i) {
        uint8_t& s = vstate[vid(i, j)];
        if (s != 0) throw std::logic_error("shapes: blocks touch");
        const bool inside = i > k.i0 && i < k.i0 + k.a && j > k.j0 && j < k.j0 + k.b;
        s = inside ? 2 : 1;
      }
    for (int j = k.j0; j < k.j0 + k.b; ++j)
      for (int i = k.i0; i < k.i0 + k.a; ++i) cell_gone[size_t(j) * size_t(W) + size_t(i)] = 1;
    gone_cells += size_t(k.a) * size_t(k.b);
    fan_quads += size_t(k.a + k.b);
  }

  // Dropped interior vertices would be unreferenced, so kept vertices are renumbered densely in
  // grid order and the block centres appended after them.
  Mesh m;
  std::vector<uint32_t> remap(vstate.size(), 0);
  const size_t kept = vstate.size() - size_t(std::count(vstate.begin(), vstate.end(), 2));
  m.positions.resize(3 * (kept + blocks.size()));
  uint32_t next = 0;
  for (int j = 0; j < vh; ++j)
    for (int i = 0; i < vw; ++i) {
      const size_t v = vid(i, j);
      if (vstate[v] == 2) continue;
      remap[v] = next;
      pos(double(i), double(j), &m.positions[3 * size_t(next)]);
      ++next;
    }
  const uint32_t first_centre = next;
  for (const Block& k : blocks) {
    pos(k.i0 + 0.5 * k.a, k.j0 + 0.5 * k.b, &m.positions[3 * size_t(next)]);
    ++next;
  }

  const size_t nfaces = size_t(W) * size_t(H) - gone_cells + fan_quads;
  m.face_offsets.resize(nfaces + 1);
  m.face_vertices.resize(4 * nfaces);
  for (size_t f = 0; f <= nfaces; ++f) m.face_offsets[f] = static_cast<uint32_t>(4 * f);
  uint32_t* out = m.face_vertices.data();
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      if (cell_gone[size_t(j) * size_t(W) + size_t(i)]) continue;
      *out++ = remap[vid(i, j)];
      *out++ = remap[vid(i + 1, j)];
      *out++ = remap[vid(i + 1, j + 1)];
      *out++ = remap[vid(i, j + 1)];
    }

  std::vector<uint32_t> ring;
  for (size_t bi = 0; bi < blocks.size(); ++bi) {
    const Block& k = blocks[bi];
    // Walk the rectangle counter-clockwise in (i, j), the same sense as the grid quads, so each
    // ring edge is used once by a fan quad and once, reversed, by the grid quad outside it.
    ring.clear();
    for (int i = k.i0; i < k.i0 + k.a; ++i) ring.push_back(remap[vid(i, k.j0)]);
    for (int j = k.j0; j < k.j0 + k.b; ++j) ring.push_back(remap[vid(k.i0 + k.a, j)]);
    for (int i = k.i0 + k.a; i > k.i0; --i) ring.push_back(remap[vid(i, k.j0 + k.b)]);
    for (int j = k.j0 + k.b; j > k.j0; --j) ring.push_back(remap[vid(k.i0, j)]);
    const size_t rn = ring.size(), n = rn / 2;
    // Fan quad t is (centre, r[2t+s], r[2t+s+1], r[2t+s+2]): ring positions of parity s get a
    // spoke. A rectangle corner has 3 outside quads, so a spoke there makes it valence 5; a side
    // vertex without a spoke drops to valence 3. The corners sit at positions 0, a, a+b, 2a+b;
    // pick the parity that spokes the fewest of them (none when a and b are both even).
    const int even_corners =
        1 + (k.a % 2 == 0) + ((k.a + k.b) % 2 == 0) + ((2 * k.a + k.b) % 2 == 0);
    const size_t s = even_corners > 4 - even_corners ? 1 : 0;
    const uint32_t c = first_centre + static_cast<uint32_t>(bi);
    for (size_t t = 0; t < n; ++t) {
      *out++ = c;
      *out++ = ring[(2 * t + s) % rn];
      *out++ = ring[(2 * t + s + 1) % rn];
      *out++ = ring[(2 * t + s + 2) % rn];
    }
  }
  return m;
}

/// Torus point at grid coordinate (gi, gj) of a W x H grid: u = 2 pi gi / W around the major
/// circle, v = 2 pi gj / H around the tube. du x dv points away from the tube's core circle, so
/// the grid's counter-clockwise quads face outward.
void torus_point(double gi, double gj, int W, int H, float* out) {
  const double u = 2.0 * kPi * gi / W, v = 2.0 * kPi * gj / H;
  const double rr = kTorusMajor + kTorusMinor * std::cos(v);
  out[0] = static_cast<float>(rr * std::cos(u));
  out[1] = static_cast<float>(rr * std::sin(u));
  out[2] = static_cast<float>(kTorusMinor * std::sin(v));
}

void check_torus_size(int major, int minor, const char* fn) {
  // Below 3 a wrapped grid repeats edges (two quads would share both of their long sides).
  if (major < 3 || minor < 3)
    throw std::invalid_argument(
        fmt::format("{}: grid {} x {} is too small (at least 3 x 3)", fn, major, minor));
}

}  // namespace

Mesh make_cube() {
  Mesh m;
  // Vertex x + 2y + 4z sits at the cube corner with those coordinates.
  for (int v = 0; v < 8; ++v)
    m.add_vertex((v & 1) ? 0.5f : -0.5f, (v & 2) ? 0.5f : -0.5f, (v & 4) ? 0.5f : -0.5f);
  // Each face is (o, o+U, o+U+V, o+V) with U x V the outward normal.
  m.add_face({0, 2, 3, 1});  // -z
  m.add_face({4, 5, 7, 6});  // +z
  m.add_face({0, 4, 6, 2});  // -x
  m.add_face({1, 3, 7, 5});  // +x
  m.add_face({0, 1, 5, 4});  // -y
  m.add_face({2, 6, 7, 3});  // +y
  return m;
}

Mesh make_torus(int major, int minor, std::span<const int> valences) {
  check_torus_size(major, minor, "make_torus");
  for (int n : valences)
    if (n < 3 || n > 12)
      throw std::invalid_argument(fmt::format("make_torus: valence {} outside 3..12", n));

  // Shelf packing: blocks left to right in rows, each followed by one free column (the last one
  // wraps to column 0), rows stacked with one free row between them and before the wrap. Then the
  // slack is spread evenly so the vertices are scattered around the torus, not bunched at (0, 0).
  std::vector<Block> blocks;
  std::vector<size_t> row_start;  // first block of each row
  std::vector<int> row_height, row_used;
  int cursor = 0;
  for (int n : valences) {
    const auto [a, b] = even_block_shape(n);
    if (a + 1 > major || b + 1 > minor)
      throw std::invalid_argument(
          fmt::format("make_torus: a valence-{} block ({} x {} quads) does not fit a {} x {} grid",
                      n, a, b, major, minor));
    if (row_start.empty() || cursor + a + 1 > major) {
      row_start.push_back(blocks.size());
      row_height.push_back(0);
      row_used.push_back(0);
      cursor = 0;
    }
    blocks.push_back({cursor, 0, a, b});
    cursor += a + 1;
    row_used.back() = cursor;
    row_height.back() = std::max(row_height.back(), b);
  }
  const int rows = static_cast<int>(row_start.size());
  int height = 0;
  for (int h : row_height) height += h + 1;
  if (height > minor)
    throw std::invalid_argument(fmt::format(
        "make_torus: {} extraordinary vertices do not fit a {} x {} grid with one quad between "
        "them",
        valences.size(), major, minor));
  row_start.push_back(blocks.size());
  for (int r = 0, j = 0; r < rows; ++r) {
    const int jr = j + r * (minor - height) / rows;
    const size_t first = row_start[size_t(r)], count = row_start[size_t(r) + 1] - first;
    const int slack = major - row_used[size_t(r)];
    for (size_t q = 0; q < count; ++q) {
      Block& k = blocks[first + q];
      k.i0 += static_cast<int>(q) * slack / static_cast<int>(count);
      k.j0 = jr;
    }
    j += row_height[size_t(r)] + 1;
  }

  return build_grid(major, minor, true, blocks, [&](double gi, double gj, float* out) {
    torus_point(gi, gj, major, minor, out);
  });
}

Mesh make_crease_cage() {
  // A 4x4x4 lattice (3 quads per box edge) of which the surface points are used, except the
  // inside of the missing lid. Lattice coordinates 0..3 map to [-1, 1].
  constexpr int kN = 3;
  Mesh m;
  std::array<uint32_t, (kN + 1) * (kN + 1) * (kN + 1)> id{};
  auto at = [](int x, int y, int z) { return size_t((z * (kN + 1) + y) * (kN + 1) + x); };
  for (int z = 0; z <= kN; ++z)
    for (int y = 0; y <= kN; ++y)
      for (int x = 0; x <= kN; ++x) {
        const bool side = x == 0 || x == kN || y == 0 || y == kN;
        if (!side && z != 0) continue;
        id[at(x, y, z)] = m.add_vertex(-1.0f + 2.0f * float(x) / kN, -1.0f + 2.0f * float(y) / kN,
                                       -1.0f + 2.0f * float(z) / kN);
      }

  // Each side is an origin and two lattice directions U, V with U x V pointing outward, so the
  // quads (p, p+U, p+U+V, p+V) are counter-clockwise seen from outside.
  struct Side {
    int o[3], u[3], v[3];
  };
  constexpr Side kSides[] = {
      {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}},   // bottom, -z
      {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},   // -x
      {{kN, 0, 0}, {0, 1, 0}, {0, 0, 1}},  // +x
      {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}},   // -y (front; its centre quad becomes the hole)
      {{0, kN, 0}, {0, 0, 1}, {1, 0, 0}},  // +y
  };
  for (size_t s = 0; s < std::size(kSides); ++s) {
    const Side& sd = kSides[s];
    auto p = [&](int i, int j) {
      return id[at(sd.o[0] + i * sd.u[0] + j * sd.v[0], sd.o[1] + i * sd.u[1] + j * sd.v[1],
                   sd.o[2] + i * sd.u[2] + j * sd.v[2])];
    };
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const uint32_t f = m.add_face({p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)});
        if (s == 3 && i == 1 && j == 1) m.hole_faces.push_back(f);
      }
  }

  auto crease = [&](int x0, int y0, int z0, int x1, int y1, int z1, float sharpness) {
    m.crease_edges.insert(m.crease_edges.end(), {id[at(x0, y0, z0)], id[at(x1, y1, z1)]});
    m.crease_sharpness.push_back(sharpness);
  };
  for (int t = 0; t < kN; ++t) {
    // The bottom rim, a closed square of infinitely sharp edges.
    crease(t, 0, 0, t + 1, 0, 0, kInfiniteSharpness);
    crease(kN, t, 0, kN, t + 1, 0, kInfiniteSharpness);
    crease(t + 1, kN, 0, t, kN, 0, kInfiniteSharpness);
    crease(0, t + 1, 0, 0, t, 0, kInfiniteSharpness);
  }
  for (int t = 0; t < kN; ++t) {
    // Two diagonally opposite vertical box edges, semi-sharp: they soften after 2-3 levels.
    crease(0, 0, t, 0, 0, t + 1, 2.5f);
    crease(kN, kN, t, kN, kN, t + 1, 2.5f);
  }
  // The two bottom corners whose vertical edges are not creased.
  for (auto [x, y] : {std::pair{kN, 0}, std::pair{0, kN}}) {
    m.corner_vertices.push_back(id[at(x, y, 0)]);
    m.corner_sharpness.push_back(kInfiniteSharpness);
  }
  m.tags.boundary = BoundaryInterpolation::edge_and_corner;
  m.tags.crease_method = CreaseMethod::uniform;
  return m;
}

Mesh make_terrain(int n, uint64_t seed, int spacing) {
  if (n < 1) throw std::invalid_argument(fmt::format("make_terrain: size {} < 1", n));
  // The largest block (2 x 4, valence 6) plus a free cell on either side must fit one site.
  if (spacing < 6)
    throw std::invalid_argument(fmt::format("make_terrain: spacing {} < 6 cells", spacing));
  Rng rng(seed);

  // Height: a few plane waves with random direction, frequency (1 to 3 periods across the
  // square) and phase, weighted 1/k and normalised so the amplitude is at most 0.15.
  struct Wave {
    double kx, ky, phase, amp;
  };
  std::array<Wave, 4> waves{};
  double amp_sum = 0;
  for (size_t w = 0; w < waves.size(); ++w) {
    const double dir = 2.0 * kPi * rng.unit(), freq = kPi * (1.0 + 2.0 * rng.unit());
    waves[w] = {freq * std::cos(dir), freq * std::sin(dir), 2.0 * kPi * rng.unit(),
                1.0 / double(w + 1)};
    amp_sum += waves[w].amp;
  }
  for (Wave& w : waves) w.amp *= 0.15 / amp_sum;

  // Sites on a jittered lattice: each lattice cell of spacing x spacing grid cells gets one block,
  // kept one cell inside its lattice cell so blocks of neighbouring sites never touch, and the
  // lattice is centred so no block touches the terrain's boundary.
  constexpr int kValences[] = {3, 5, 6};
  const int sites = n / spacing, off = (n - sites * spacing) / 2;
  std::vector<Block> blocks;
  blocks.reserve(size_t(sites) * size_t(sites));
  for (int q = 0; q < sites; ++q)
    for (int p = 0; p < sites; ++p) {
      auto [a, b] = even_block_shape(kValences[rng.below(3)]);
      if (rng.next() & 1) std::swap(a, b);
      const int i0 = off + p * spacing + 1 + rng.below(spacing - 1 - a);
      const int j0 = off + q * spacing + 1 + rng.below(spacing - 1 - b);
      blocks.push_back({i0, j0, a, b});
    }

  const double h = 2.0 / n;
  return build_grid(n, n, false, blocks, [&](double gi, double gj, float* out) {
    const double x = -1.0 + h * gi, y = -1.0 + h * gj;
    double z = 0;
    for (const Wave& w : waves) z += w.amp * std::sin(w.kx * x + w.ky * y + w.phase);
    out[0] = static_cast<float>(x);
    out[1] = static_cast<float>(y);
    out[2] = static_cast<float>(z);
  });
}

Mesh make_dense_torus(int major, int minor, uint64_t seed) {
  check_torus_size(major, minor, "make_dense_torus");
  Rng rng(seed);
  // On a closed quad mesh V = F (Euler: V - 2F + F = 0), and a block changes both by
  // 1 - (a-1)(b-1): the new centre minus the dropped interior vertices. The torus's even shapes
  // (2x4, 4x4, ...) lose 2..8 quads each, which at one block per tile would shrink 1600 x 500 to
  // ~760k quads. These shapes add one quad each for valences 3, 5, 6 and the valence-8 2 x 6
  // block loses 4, so on average the face count stays within ~0.5% of major x minor. The thin
  // odd-parity blocks spoke two rectangle corners (valence 5), which only adds to the density.
  struct Shape {
    int a, b;
  };
  constexpr Shape kShapes[] = {{1, 2}, {1, 4}, {1, 5}, {2, 6}};  // valences 3, 5, 6, 8
  // Tiles of about 7 x 8 cells, one block each with a free cell on every side (so blocks in
  // neighbouring tiles never touch): 1600 x 500 gets 228 x 62 tiles, ~5.5 extraordinary
  // vertices per tile, about one vertex in ten.
  const int tiles_i = std::max(1, major / 7), tiles_j = std::max(1, minor / 8);
  std::vector<Block> blocks;
  blocks.reserve(size_t(tiles_i) * size_t(tiles_j));
  for (int tj = 0; tj < tiles_j; ++tj)
    for (int ti = 0; ti < tiles_i; ++ti) {
      // Integer division spreads the remainder cells over the tiles instead of leaving a seam.
      auto split = [](int t, int size, int tiles) { return int(int64_t(t) * size / tiles); };
      const int ci = split(ti, major, tiles_i), cw = split(ti + 1, major, tiles_i) - ci;
      const int cj = split(tj, minor, tiles_j), ch = split(tj + 1, minor, tiles_j) - cj;
      const int fw = cw - 2, fh = ch - 2;  // room inside the one-cell margin
      auto fits = [&](int a, int b) { return a <= fw && b <= fh; };
      std::array<int, std::size(kShapes)> fit{};
      int nf = 0;
      for (int s = 0; s < int(std::size(kShapes)); ++s)
        if (fits(kShapes[s].a, kShapes[s].b) || fits(kShapes[s].b, kShapes[s].a))
          fit[size_t(nf++)] = s;
      if (nf == 0) continue;  // a tile too small for any block stays regular
      // The valence first, uniformly among those that fit, then an orientation that fits, so
      // shapes fitting both ways are not favoured.
      Shape sh = kShapes[fit[size_t(rng.below(nf))]];
      const bool both = fits(sh.a, sh.b) && fits(sh.b, sh.a);
      if (both ? (rng.next() & 1) != 0 : !fits(sh.a, sh.b)) std::swap(sh.a, sh.b);
      blocks.push_back(
          {ci + 1 + rng.below(fw - sh.a + 1), cj + 1 + rng.below(fh - sh.b + 1), sh.a, sh.b});
    }
  return build_grid(major, minor, true, blocks, [&](double gi, double gj, float* out) {
    torus_point(gi, gj, major, minor, out);
  });
}

std::vector<std::string> shape_names() {
  return {"cube", "torus", "cage", "terrain", "torus-dense", "terrain-small", "torus-dense-small"};
}

Mesh make_shape(std::string_view name, uint64_t seed) {
  if (name == "cube") return make_cube();
  if (name == "torus") {
    constexpr int kValences[] = {3, 5, 6, 8};
    return make_torus(48, 24, kValences);
  }
  if (name == "cage") return make_crease_cage();
  if (name == "terrain") return make_terrain(895, seed);
  if (name == "torus-dense") return make_dense_torus(1600, 500, seed);
  if (name == "terrain-small") return make_terrain(64, seed, 12);
  if (name == "torus-dense-small") return make_dense_torus(96, 40, seed);
  std::string known;
  for (const std::string& s : shape_names()) known += (known.empty() ? "" : ", ") + s;
  throw InputError(fmt::format("unknown shape '{}' (known: {})", name, known));
}

}  // namespace limn
