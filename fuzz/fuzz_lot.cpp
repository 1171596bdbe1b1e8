// libFuzzer target: the .lot reader must either refuse a file (InputError) or return a texture
// that passes its own structural check, reads without fault at any point, survives a dab, and
// writes back to a file that reads as the same texture. Checksums are skipped so mutations reach
// the structural checks behind them.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "limn/mesh/mesh.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/lookup.hpp"

namespace {

// A sheet over [-1,1]^2 at z = 0 (where the seed textures live), built once.
const limn::PaintSurface& sheet() {
  static const limn::PaintSurface s([] {
    limn::Mesh m;
    const int n = 8;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        m.add_vertex(-1.0f + 2.0f * float(i) / n, -1.0f + 2.0f * float(j) / n, 0.0f);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 2,
                       d = a + uint32_t(n) + 1;
        m.add_face({a, b, c, d});
      }
    return m;
  }());
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::MaterialTexture m;
  try {
    m = limn::parse_lot(in, "fuzz.lot", false);
  } catch (const limn::InputError&) {
    return 0;
  }
  const limn::OctreeTexture& t = m.color;
  if (!t.check().empty()) __builtin_trap();
  if (m.rmh) {
    if (!m.rmh->check().empty()) __builtin_trap();
    // The material's lookups: RMH values over its defaults.
    limn::OctreeSampler rs(*m.rmh);
    for (size_t i = 0; i + 3 <= size && i < 3 * 32; i += 3) {
      float p[3], rgba[4] = {0, 0, 0, 0};
      for (int k = 0; k < 3; ++k)
        p[k] = m.rmh->origin()[k] + float(data[i + size_t(k)]) / 255.0f * m.rmh->size();
      rs.filtered(p, nullptr, 0.0f, rgba);
      (void)limn::material_value(rgba, m.rmh->background());
    }
  }
  (void)t.stats();
  size_t samples = 0;
  t.for_each_sample([&](const limn::OctreeSample&) { ++samples; });

  // Lookups at points spread over the cube (and a little outside), from the input's bytes.
  limn::OctreeSampler s(t);
  for (size_t i = 0; i + 6 <= size && i < 6 * 64; i += 6) {
    float p[3], n[3];
    for (int k = 0; k < 3; ++k) {
      const float u = float(data[i + size_t(k)]) / 255.0f * 1.2f - 0.1f;
      p[k] = t.origin()[k] + u * t.size();
      n[k] = float(int(data[i + 3 + size_t(k)]) - 128);
    }
    limn::Rgba8 c;
    float rgba[4];
    s.nearest(p, n, c);
    s.nearest(p, nullptr, c);
    s.filtered(p, n, 0.0f, rgba);
    s.filtered(p, n, t.size() * float(data[i]) / 1024.0f, rgba);
    for (int level = 0; level <= limn::octree::kMaxDepth; level += 3)
      s.cell_value(uint32_t(data[i]) << 8, uint32_t(data[i + 1]) << 8, uint32_t(data[i + 2]) << 8,
                   level, n, c);
  }

  // A dab edits whatever structure the file holds; the result must stay valid.
  if (t.words().size() < 200000 && size > 0) {
    limn::OctreeTexture u = t;
    limn::Brush b;
    b.radius = 0.3f;
    b.depth = 2 + data[0] % 9;
    limn::StrokePainter painter(u, sheet());
    painter.begin(b);
    const float centre[3] = {0.1f, -0.2f, 0.0f};
    painter.dab_world(centre);
    painter.end();
    if (!u.check().empty()) __builtin_trap();
  }

  const std::string again = limn::serialize_lot(m);
  const limn::MaterialTexture r = limn::parse_lot(again, "roundtrip.lot");  // must not throw
  if (!(r == m)) __builtin_trap();
  return 0;
}
