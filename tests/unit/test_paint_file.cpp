// Undo/redo give back the exact bytes; the .lot file round-trips exactly; corrupt, truncated,
// foreign and structurally broken files are refused with one line naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "limn/paint/brush.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/undo.hpp"
#include "paint/octree_blocks.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kData = LIMN_TEST_DATA;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A stroke recorded in `h`.
StrokeStats stroke(OctreeTexture& t, const PaintSurface& s, PaintHistory& h, int depth,
                   float radius, BlendMode mode, std::vector<float> line, float r = 1) {
  Brush b;
  b.depth = depth, b.radius = radius, b.blend = mode, b.hardness = 0.7f;
  b.color[0] = r, b.color[1] = 0.5f, b.color[2] = 0.25f, b.color[3] = 1;
  StrokePainter p(t, s, &h);
  p.begin(b);
  p.stroke_world(line);
  return p.end();
}

TEST(PaintUndo, UndoAndRedoRestoreTheExactBytes) {
  const Mesh m = test::uv_sphere(1.0, 20, 40);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  PaintHistory h;
  EXPECT_FALSE(h.undo(t));
  std::vector<std::string> states = {serialize_lot(t)};
  const std::vector<float> line = {0, 0, 1, 0.3f, 0.2f, 0.95f, 0.5f, 0.5f, 0.7f};
  stroke(t, s, h, 6, 0.2f, BlendMode::mix, line);  // refines from the start tree
  states.push_back(serialize_lot(t));
  stroke(t, s, h, 9, 0.15f, BlendMode::add, line);  // deeper: bricks explode, blocks recycle
  states.push_back(serialize_lot(t));
  stroke(t, s, h, 9, 0.1f, BlendMode::erase, line);
  states.push_back(serialize_lot(t));
  h.begin(t);  // a fill is one undoable step too
  const float blue[4] = {0, 0, 1, 0.5f};
  fill(t, s, blue, BlendMode::multiply, 1.0f);
  h.end(t);
  states.push_back(serialize_lot(t));
  const std::vector<float> spot = {-0.6f, 0, -0.8f};
  stroke(t, s, h, 12, 0.01f, BlendMode::mix, spot);
  states.push_back(serialize_lot(t));
  ASSERT_EQ(h.undo_count(), 5u);
  for (size_t i = 1; i < states.size(); ++i) ASSERT_NE(states[i], states[i - 1]) << i;
  for (size_t i = states.size() - 1; i > 0; --i) {
    ASSERT_TRUE(h.undo(t));
    ASSERT_EQ(serialize_lot(t), states[i - 1]) << "undo to state " << i - 1;
    ASSERT_EQ(t.check(), "");
  }
  EXPECT_FALSE(h.undo(t));
  for (size_t i = 1; i < states.size(); ++i) {
    ASSERT_TRUE(h.redo(t));
    ASSERT_EQ(serialize_lot(t), states[i]) << "redo to state " << i;
  }
  EXPECT_FALSE(h.redo(t));
  // A new stroke after undos drops the redo list.
  ASSERT_TRUE(h.undo(t));
  ASSERT_TRUE(h.undo(t));
  stroke(t, s, h, 8, 0.2f, BlendMode::mix, {0, 1, 0});
  EXPECT_EQ(h.redo_count(), 0u);
  ASSERT_TRUE(h.undo(t));
  EXPECT_EQ(serialize_lot(t), states[3]);
  EXPECT_GT(h.bytes(), 0u);
}

TEST(PaintUndo, HistoryKeepsAtMostItsLimit) {
  const Mesh m = test::uv_sphere(1.0, 8, 16);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  PaintHistory h(2);
  for (int i = 0; i < 4; ++i) stroke(t, s, h, 6, 0.3f, BlendMode::mix, {0, 0, 1}, float(i) / 4.0f);
  EXPECT_EQ(h.undo_count(), 2u);
  EXPECT_TRUE(h.undo(t));
  EXPECT_TRUE(h.undo(t));
  EXPECT_FALSE(h.undo(t));
  EXPECT_EQ(t.check(), "");
}

// A texture with every kind of block: general nodes, bricks, two-sided cells, free blocks.
OctreeTexture varied(const PaintSurface& s) {
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(1, 2, 3, 4));
  PaintHistory h;
  stroke(t, s, h, 5, 0.4f, BlendMode::mix, {0, 0, 0.005f});
  stroke(t, s, h, 8, 0.2f, BlendMode::mix, {0, 0, 0.005f, 0.3f, 0, 0.005f});
  stroke(t, s, h, 11, 0.02f, BlendMode::add, {-0.5f, 0.5f, -0.005f}, 0.2f);
  return t;
}

Mesh two_sheets() {
  const double gap = 0.3 * 2.04 / 256.0;
  return test::merge({test::sheet(-1, 1, -1, 1, gap, 16, true),
                      test::sheet(-1, 1, -1, 1, 0.0, 16, false),
                      test::sheet(0.9, 1, 0.9, 1, 0.5, 1, true)});
}

TEST(PaintFile, SaveLoadRoundTripsExactly) {
  const Mesh m = two_sheets();
  const PaintSurface s(m);
  OctreeTexture t = varied(s);
  const OctreeTextureStats st = t.stats();
  ASSERT_GT(st.double_cells, 0u);
  ASSERT_GT(st.bricks, 0u);
  ASSERT_GT(st.free_words, 0u);
  const fs::path dir = fs::temp_directory_path() / ("limn-lot-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path f = dir / "t.lot";
  save_lot(t, f);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temp
  OctreeTexture u = load_lot(f).color;
  EXPECT_TRUE(u == t);
  EXPECT_EQ(serialize_lot(u), slurp(f));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> d(-1.1f, 1.1f);
  OctreeSampler a(t), b(u);
  for (int i = 0; i < 5000; ++i) {
    const float p[3] = {d(rng), d(rng), d(rng) * 0.01f}, n[3] = {0, 0, i % 2 ? 1.0f : -1.0f};
    Rgba8 ca, cb;
    ASSERT_EQ(a.nearest(p, n, ca), b.nearest(p, n, cb));
    ASSERT_EQ(ca, cb);
  }
  // The loaded texture carries on exactly as the original (free lists included).
  PaintHistory h;
  stroke(t, s, h, 9, 0.3f, BlendMode::mix, {0.2f, -0.2f, 0.005f});
  stroke(u, s, h, 9, 0.3f, BlendMode::mix, {0.2f, -0.2f, 0.005f});
  EXPECT_EQ(serialize_lot(t), serialize_lot(u));
  // A failed save (a folder stands where the file would go) leaves the folder and no temp file.
  fs::create_directories(dir / "busy.lot" / "x");
  EXPECT_THROW(save_lot(t, dir / "busy.lot"), std::runtime_error);
  EXPECT_TRUE(fs::is_directory(dir / "busy.lot" / "x"));
  EXPECT_THROW(save_lot(t, dir / "missing" / "t.lot"), std::runtime_error);
  EXPECT_EQ(slurp(f), serialize_lot(varied(s)));  // the good file is as it was
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  fs::remove_all(dir);
}

// A pool past 2 MiB lives in 2 MiB-aligned storage (huge pages where the system has them, see
// OctreeTexture::Words): a copy, a save/load round trip, a stroke's undo and compaction keep
// every word.
TEST(PaintFile, PoolsPastTwoMiBKeepEveryWord) {
  const Mesh m = test::uv_sphere(1.0, 30, 60);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  refine_surface(t, s, 9);
  ASSERT_GT(t.words().size() * sizeof(uint32_t), octree::kHugeBytes);
  auto aligned = [](const OctreeTexture& x) {
    return reinterpret_cast<uintptr_t>(x.words().data()) % octree::kHugeBytes == 0;
  };
  EXPECT_TRUE(aligned(t));
  const OctreeTexture copy = t;
  EXPECT_TRUE(aligned(copy));
  EXPECT_TRUE(copy == t);
  const std::string bytes = serialize_lot(t);
  const OctreeTexture loaded = parse_lot(bytes, "memory").color;
  EXPECT_TRUE(aligned(loaded));
  EXPECT_TRUE(loaded == t);
  PaintHistory h;
  stroke(t, s, h, 10, 0.3f, BlendMode::mix, {0, 0, 1, 0.3f, 0, 0.95f});
  EXPECT_NE(serialize_lot(t), bytes);
  ASSERT_TRUE(h.undo(t));
  EXPECT_EQ(serialize_lot(t), bytes);
  // Compaction moves every block into a new pool: the same samples where they were.
  OctreeTexture packed = t;
  packed.compact();
  EXPECT_TRUE(aligned(packed));
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> d(-1, 1);
  OctreeSampler a(t), b(packed);
  for (int i = 0; i < 5000; ++i) {
    float p[3] = {d(rng), d(rng), d(rng)};
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (float& x : p) x /= len;  // on the sphere
    Rgba8 ca, cb;
    ASSERT_EQ(a.nearest(p, p, ca), b.nearest(p, p, cb));
    ASSERT_EQ(ca, cb);
  }
}

TEST(PaintFile, EveryStateOfAPaintingRoundTrips) {
  // Every step of a painting, with free blocks and compacted (pools of odd length, ending in a
  // brick without a pad word, among them: a loader once refused those).
  const Mesh m = test::uv_sphere(1.0, 12, 24);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  PaintHistory h;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-1, 1);
  size_t odd = 0;
  for (int i = 0; i < 24; ++i) {
    stroke(t, s, h, 4 + i % 8, 0.05f + 0.2f * std::fabs(u(rng)), BlendMode(i % 4),
           {u(rng), u(rng), u(rng)}, std::fabs(u(rng)));
    OctreeTexture compacted = t;
    compacted.compact();
    ASSERT_EQ(compacted.check(), "");
    odd += compacted.words().size() % 2;
    for (const OctreeTexture* x : {&t, &compacted}) {
      const std::string f = serialize_lot(*x);
      const OctreeTexture back = parse_lot(f, "state.lot").color;
      ASSERT_TRUE(back == *x) << i;
      ASSERT_EQ(serialize_lot(back), f) << i;
    }
  }
  EXPECT_GT(odd, 0u);
}

void expect_rejected(std::string_view bytes, const std::string& name, bool checksums = true) {
  try {
    parse_lot(bytes, name, checksums);
    ADD_FAILURE() << "accepted a bad file (" << bytes.size() << " bytes)";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(name + ": ", 0), 0u) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST(PaintFile, CorruptTruncatedAndForeignFilesAreRejected) {
  const Mesh m = test::uv_sphere(1.0, 8, 16);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  PaintHistory h;
  stroke(t, s, h, 6, 0.3f, BlendMode::mix, {0, 0, 1});
  const std::string f = serialize_lot(t);
  ASSERT_LT(f.size(), 20000u);
  ASSERT_NO_THROW(parse_lot(f, "good.lot"));
  for (size_t n = 0; n < f.size(); n += (n < 128 ? 1 : 37))
    expect_rejected(f.substr(0, n), "cut.lot");
  for (size_t i = 0; i < f.size(); i += (i < 128 ? 1 : 13))
    for (int bit : {0, 5}) {
      std::string g = f;
      g[i] = char(g[i] ^ (1 << bit));
      expect_rejected(g, "flip.lot");
    }
  expect_rejected(f + '\0', "long.lot");
  expect_rejected("", "empty.lot");
  expect_rejected("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "mesh.lot");
  expect_rejected(std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'), "image.lot");
}

// Reseals a file's checksums after an edit, so only the structural checks stand in the way.
std::string reseal(std::string f) {
  auto put = [&](size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) f[at + size_t(k)] = char(v >> (8 * k) & 255u);
  };
  put(56, crc32(std::string_view(f).substr(96)));  // a colour-only file: the colour payload
  put(92, crc32(std::string_view(f).substr(0, 92)));
  return f;
}
uint32_t word_at(const std::string& f, size_t i) {
  uint32_t v = 0;
  for (int k = 0; k < 4; ++k)
    v |= uint32_t(static_cast<unsigned char>(f[96 + 4 * i + size_t(k)])) << (8 * k);
  return v;
}
std::string with_word(std::string f, size_t i, uint32_t v) {
  for (int k = 0; k < 4; ++k) f[96 + 4 * i + size_t(k)] = char(v >> (8 * k) & 255u);
  return reseal(f);
}

TEST(PaintFile, StructurallyBrokenFilesAreRejectedEvenWithValidChecksums) {
  const Mesh m = two_sheets();
  const PaintSurface s(m);
  const OctreeTexture t = varied(s);
  const std::string f = serialize_lot(t);
  const size_t words = t.words().size();
  ASSERT_NO_THROW(parse_lot(reseal(f), "same.lot"));
  const uint32_t root = word_at(f, 0);
  expect_rejected(with_word(f, 0, uint32_t(words + 10)), "root-outside.lot");
  expect_rejected(with_word(f, 0, root + 1), "root-odd.lot");
  expect_rejected(with_word(f, 0, 0), "root-on-itself.lot");
  expect_rejected(with_word(f, 1, word_at(f, 1) | 0xff00ffu), "root-masks.lot");
  // The root's first child descriptor pointing back at the root's block: a cycle.
  expect_rejected(with_word(f, root, root), "cycle.lot");
  // Header fields.
  std::string g = f;
  g[32] = g[33] = g[34] = g[35] = '\xff';  // size = NaN
  expect_rejected(reseal(g), "nan.lot");
  g = f;
  g[47] = '\x01';  // 2^56 pool words
  expect_rejected(reseal(g), "huge.lot");
  g = f;
  g[8] = 3;  // version 3
  expect_rejected(reseal(g), "version.lot");
  g = f;
  g[16] = 1;  // an RMH texture promised, none there
  expect_rejected(reseal(g), "no-rmh.lot");
  // Random single-word damage to the structure (not to colours, not to free blocks): every
  // outcome is a refusal or a texture that passes the check and reads without fault (ASan
  // watches).
  std::vector<uint8_t> structure(words, 1);
  t.for_each_sample([&](const OctreeSample& x) { structure[x.word] = 0; });
  for (const auto& [cls, ptr] : t.free_blocks())
    for (uint32_t k = 0; k < cls / 2; ++k) structure[ptr + k] = 0;
  std::vector<size_t> targets;
  for (size_t i = 0; i < words; ++i)
    if (structure[i]) targets.push_back(i);
  ASSERT_GT(targets.size(), 100u);
  std::mt19937 rng(2);
  size_t refused = 0;
  const int trials = 1500;
  for (int i = 0; i < trials; ++i) {
    std::string h = f;
    const size_t w = targets[rng() % targets.size()];
    uint32_t v = word_at(h, w);
    switch (i % 4) {
      case 0:
        v ^= 1u << (rng() % 32);
        break;
      case 1:
        v = uint32_t(rng());
        break;
      case 2:
        v += uint32_t(rng() % 16) - 8u;
        break;
      case 3:
        v = uint32_t(rng() % (words + 8));
        break;
    }
    h = with_word(h, w, v);
    try {
      const OctreeTexture u = parse_lot(h, "damaged.lot").color;
      ASSERT_EQ(u.check(), "");
      OctreeSampler smp(u);
      for (int k = 0; k < 50; ++k) {
        const float p[3] = {float(rng() % 2000) / 1000.0f - 1, float(rng() % 2000) / 1000.0f - 1,
                            0.001f};
        Rgba8 c;
        float rgba[4];
        smp.nearest(p, nullptr, c);
        smp.filtered(p, nullptr, 0.05f, rgba);
      }
      (void)u.stats();
    } catch (const InputError& e) {
      ++refused;
      EXPECT_EQ(std::string(e.what()).rfind("damaged.lot: ", 0), 0u);
    }
  }
  EXPECT_GT(refused, size_t(trials) / 2);
}

TEST(PaintFile, EveryBadFileInTheCorpusIsRefusedNamingIt) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(kData / "bad")) {
    if (e.path().extension() != ".lot") continue;
    SCOPED_TRACE(e.path().string());
    try {
      load_lot(e.path());
      ADD_FAILURE() << "accepted";
    } catch (const InputError& x) {
      EXPECT_NE(std::string(x.what()).find(e.path().filename().string()), std::string::npos);
    }
    ++n;
  }
  EXPECT_GE(n, 10u);
  EXPECT_THROW(load_lot(kData / "bad" / "no-such-file.lot"), InputError);
}

}  // namespace
}  // namespace limn
