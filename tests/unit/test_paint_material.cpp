// Material channels: a colour-only painting is what it was (no RMH texture, the same bytes);
// a brush carrying a material writes each channel with its own blend and opacity, texel for
// texel where its colour goes (the colour's coverage is the oracle of the weight); undo covers
// both textures; .lot version 2 round-trips them and version 1 still reads.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "limn/paint/brush.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/strokes.hpp"
#include "limn/paint/undo.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

using Key = std::tuple<int, uint32_t, uint32_t, uint32_t, int>;

std::map<Key, Rgba8> samples_of(const OctreeTexture& t) {
  std::map<Key, Rgba8> m;
  t.for_each_sample([&](const OctreeSample& s) { m[{s.level, s.x, s.y, s.z, s.side}] = s.color; });
  return m;
}

Brush base_brush() {
  Brush b;
  b.depth = 7, b.radius = 0.45f, b.hardness = 0.3f;
  return b;
}

const std::vector<float> kLine = {0, 0, 1, 0.6f, 0.2f, 0.77f, 0.95f, 0.3f, 0};

TEST(MaterialPaint, ColourOnlyPaintingIsTheTextureItWasBefore) {
  const Mesh m = test::uv_sphere(1.0, 20, 40);
  const PaintSurface s(m);
  OctreeTexture plain = OctreeTexture::create(s);
  MaterialTexture mat = MaterialTexture::from_color(plain);
  const Brush b = base_brush();
  StrokePainter p(plain, s);
  p.begin(b);
  p.stroke_world(kLine);
  p.end();
  MaterialPainter mp(mat, s);
  mp.begin(b);
  mp.stroke_world(kLine);
  mp.end();
  EXPECT_TRUE(mat.color == plain);
  EXPECT_FALSE(mat.rmh.has_value());
  EXPECT_EQ(mat.bytes(), plain.words().size() * 4);
  EXPECT_EQ(serialize_lot(mat), serialize_lot(plain));
}

TEST(MaterialPaint, ChannelsFollowTheBrushTexelForTexel) {
  const Mesh m = test::uv_sphere(1.0, 20, 40);
  const PaintSurface s(m);
  // The colour texture starts transparent and is painted opaque white at opacity 1 by a mix:
  // a texel's alpha is then the stroke's weight there, the oracle for every channel.
  MaterialTexture mat = MaterialTexture::from_color(OctreeTexture::create(s, 0));
  const MaterialDefaults defaults{0.2f, 0.1f, 0.5f};
  Brush b = base_brush();
  for (float& c : b.color) c = 1;
  const auto rough = MaterialChannel::roughness, metal = MaterialChannel::metallic;
  b.material[int(rough)] = {true, 1.0f, BlendMode::mix, 0.5f};
  b.material[int(metal)] = {true, 0.4f, BlendMode::add, 1.0f};
  MaterialPainter p(mat, s, nullptr, defaults);
  p.begin(b);
  p.stroke_world(kLine);
  const StrokeStats st = p.end();
  ASSERT_TRUE(mat.rmh.has_value());
  EXPECT_EQ(mat.rmh->check(), "");
  EXPECT_GT(st.samples_changed, 1000u);

  const Rgba8 bg = mat.rmh->background();
  const double def[3] = {channel(bg, 0) / 255.0, channel(bg, 1) / 255.0, channel(bg, 2) / 255.0};
  const auto color = samples_of(mat.color), rmh = samples_of(*mat.rmh);
  EXPECT_EQ(color.size(), rmh.size());  // the same cells, split by the same dabs
  size_t painted = 0;
  for (const auto& [key, c] : color) {
    const auto it = rmh.find(key);
    ASSERT_NE(it, rmh.end());
    const Rgba8 v = it->second;
    const double w = channel(c, 3) / 255.0;
    if (channel(c, 3) == 0) {
      // Untouched (or touched too lightly to show in 8 bits): still the defaults.
      if (channel(v, 3) != 0) {
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(double(channel(v, k)), 255 * def[k], 1.01);
      }
      continue;
    }
    ++painted;
    ASSERT_EQ(channel(v, 3), 255u);
    const double want[3] = {def[0] + (1 - def[0]) * w * 0.5, std::min(1.0, def[1] + 0.4 * w),
                            def[2]};
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(channel(v, k) / 255.0, want[k], 1.01 / 255) << "channel " << k;
  }
  EXPECT_GT(painted, 1000u);

  // A second stroke on roughness alone leaves metallic and height, and the colour, as they are.
  const MaterialTexture before = mat;
  Brush r = base_brush();
  r.paint_color = false;
  r.material[int(rough)] = {true, 0.0f, BlendMode::mix, 1.0f};
  MaterialPainter q(mat, s);
  q.begin(r);
  q.stroke_world(kLine);
  q.end();
  EXPECT_TRUE(mat.color == before.color);
  const auto after = samples_of(*mat.rmh), was = samples_of(*before.rmh);
  size_t lowered = 0;
  for (const auto& [key, v] : after) {
    const Rgba8 o = was.at(key);
    if (channel(o, 3) == 0) continue;
    EXPECT_NEAR(double(channel(v, 1)), double(channel(o, 1)), 1.0);
    EXPECT_NEAR(double(channel(v, 2)), double(channel(o, 2)), 1.0);
    EXPECT_LE(channel(v, 0), channel(o, 0));
    lowered += channel(v, 0) < channel(o, 0);
  }
  EXPECT_GT(lowered, 500u);
}

TEST(MaterialPaint, EraseReturnsAChannelToItsDefault) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  MaterialTexture mat = MaterialTexture::from_color(OctreeTexture::create(s));
  Brush b = base_brush();
  b.paint_color = false, b.hardness = 1;
  b.material[int(MaterialChannel::height)] = {true, 1.0f, BlendMode::mix, 1.0f};
  for (BlendMode mode : {BlendMode::mix, BlendMode::erase}) {
    b.material[int(MaterialChannel::height)].blend = mode;
    MaterialPainter p(mat, s);
    p.begin(b);
    p.stroke_world(kLine);
    p.end();
  }
  // Every texel the dabs reached at full strength is back at the default height.
  const float p0[3] = {0, 0, 1};
  MaterialPick pick = pick_world(mat, s, p0, 0.1f);
  EXPECT_NEAR(pick.channels[2], mat.defaults().height, 1.0 / 255);
  size_t full = 0;
  mat.rmh->for_each_sample([&](const OctreeSample& x) {
    if (channel(x.color, 3) == 255) {
      EXPECT_NEAR(double(channel(x.color, 2)), double(channel(mat.rmh->background(), 2)), 1.0);
      ++full;
    }
  });
  EXPECT_GT(full, 100u);
}

TEST(MaterialPaint, UndoAndRedoCoverBothTextures) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  MaterialTexture mat = MaterialTexture::from_color(OctreeTexture::create(s));
  PaintHistory h;
  Brush b = base_brush();
  b.material[int(MaterialChannel::metallic)] = {true, 1.0f, BlendMode::mix, 1.0f};
  // The first material stroke makes the RMH texture; an unpainted one stays after its undo.
  MaterialPainter(mat, s, &h).begin(b);  // a stroke with no dab: nothing to record
  const std::string start = serialize_lot(mat);
  std::vector<std::string> states = {start};
  for (int i = 0; i < 3; ++i) {
    b.material[int(MaterialChannel::metallic)].value = 0.3f * float(i);
    b.color[1] = 0.2f * float(i);
    MaterialPainter p(mat, s, &h);
    p.begin(b);
    p.stroke_world({kLine.begin() + 3 * i, kLine.begin() + 3 * i + 3});
    p.end();
    states.push_back(serialize_lot(mat));
  }
  EXPECT_EQ(h.undo_count(), 3u);
  for (int i = 3; i > 0; --i) {
    ASSERT_TRUE(h.undo(mat));
    ASSERT_EQ(serialize_lot(mat), states[size_t(i) - 1]) << i;
  }
  for (int i = 1; i <= 3; ++i) {
    ASSERT_TRUE(h.redo(mat));
    ASSERT_EQ(serialize_lot(mat), states[size_t(i)]) << i;
  }
  // A record with RMH writes does not undo onto a colour texture alone.
  EXPECT_THROW(h.undo(mat.color), std::logic_error);
  // A brush that paints neither colour nor a channel paints nothing and records nothing.
  Brush none = base_brush();
  none.paint_color = false;
  MaterialPainter idle(mat, s, &h);
  idle.begin(none);
  EXPECT_FALSE(idle.dab_world(kLine.data()));
  idle.end();
  EXPECT_EQ(serialize_lot(mat), states[3]);
  EXPECT_EQ(h.undo_count(), 3u);
}

// Writes a version-1 file of a colour texture from the version-2 bytes, by the layout in
// include/limn/paint/file.hpp: header bytes 0-59 with version 1, header size 64 and flags 0,
// the CRC of them, then the same payload.
std::string as_version_1(const std::string& v2) {
  std::string out = v2.substr(0, 60);
  auto put = [](std::string& s, size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) s[at + size_t(k)] = char(v >> (8 * k) & 255u);
  };
  put(out, 8, 1);
  put(out, 12, 64);
  put(out, 16, 0);
  out += std::string(4, '\0');
  put(out, 60, crc32(std::string_view(out).substr(0, 60)));
  return out + v2.substr(96);
}

TEST(MaterialFile, ChannelsRoundTripAndVersion1StillReads) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  MaterialTexture mat = MaterialTexture::from_color(OctreeTexture::create(s));
  mat.height_scale = 0.0375f;
  Brush b = base_brush();
  b.material[int(MaterialChannel::roughness)] = {true, 0.9f, BlendMode::mix, 0.7f};
  MaterialPainter p(mat, s, nullptr, {0.3f, 0.6f, 0.4f});
  p.begin(b);
  p.stroke_world(kLine);
  p.end();
  const std::string f = serialize_lot(mat);
  const MaterialTexture back = parse_lot(f, "m.lot");
  EXPECT_TRUE(back == mat);
  EXPECT_EQ(serialize_lot(back), f);
  EXPECT_FLOAT_EQ(back.height_scale, 0.0375f);
  EXPECT_NEAR(back.defaults().metallic, 0.6f, 0.5f / 255);

  // Version 1: the colour texture, the default height scale, no channels.
  const std::string colour_only = serialize_lot(mat.color);
  const MaterialTexture v1 = parse_lot(as_version_1(colour_only), "old.lot");
  EXPECT_TRUE(v1.color == mat.color);
  EXPECT_FALSE(v1.rmh.has_value());
  EXPECT_FLOAT_EQ(v1.height_scale, kDefaultHeightScale * mat.color.size());
  EXPECT_EQ(serialize_lot(v1), colour_only);

  // Damage in the RMH payload: the checksum catches it; resealed, the structural check does.
  const size_t rmh_at = f.size() - 4 * mat.rmh->words().size() - 8 * mat.rmh->free_blocks().size();
  std::string g = f;
  g[rmh_at + 1] = char(g[rmh_at + 1] ^ 0x40);
  try {
    parse_lot(g, "bad.lot");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.lot: corrupt: RMH"), std::string::npos) << e.what();
  }
  auto put = [](std::string& x, size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) x[at + size_t(k)] = char(v >> (8 * k) & 255u);
  };
  put(g, 88, crc32(std::string_view(g).substr(rmh_at)));
  put(g, 92, crc32(std::string_view(g).substr(0, 92)));
  try {
    parse_lot(g, "bad.lot");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.lot: corrupt: RMH texture: "), std::string::npos)
        << e.what();
  }
  // A height scale that is not a positive number.
  g = f;
  put(g, 60, 0xbf800000u);  // -1.0f
  put(g, 92, crc32(std::string_view(g).substr(0, 92)));
  EXPECT_THROW(parse_lot(g, "bad.lot"), InputError);
}

TEST(MaterialStrokes, ScriptsPaintChannelsAndRefuseBadOnes) {
  const StrokeScript sc = parse_strokes(
      R"({"strokes": [{"points": [[0, 0, 1]], "radius": 0.3, "roughness": 0.25,
                       "metallic": {"value": 1, "blend": "add", "opacity": 0.5}},
                      {"points": [[0, 0, 1]], "radius": 0.3, "height": {"blend": "erase"},
                       "color": [0, 1, 0]},
                      {"type": "fill", "metallic": 0.5}]})",
      "s.json", 8);
  ASSERT_EQ(sc.commands.size(), 3u);
  const Brush& a = sc.commands[0].brush;
  EXPECT_FALSE(a.paint_color);  // a material entry paints colour only when it gives one
  EXPECT_TRUE(a.material[0].on && a.material[1].on && !a.material[2].on);
  EXPECT_FLOAT_EQ(a.material[0].value, 0.25f);
  EXPECT_EQ(a.material[1].blend, BlendMode::add);
  EXPECT_FLOAT_EQ(a.material[1].opacity, 0.5f);
  EXPECT_TRUE(sc.commands[1].brush.paint_color);
  EXPECT_EQ(sc.commands[1].brush.material[2].blend, BlendMode::erase);
  EXPECT_FALSE(sc.commands[2].brush.paint_color);
  for (
      const char* bad :
      {R"({"strokes": [{"points": [[0, 0, 1]], "radius": 0.3, "roughness": 1.5}]})",
       R"({"strokes": [{"points": [[0, 0, 1]], "radius": 0.3, "height": {"blend": "mix"}}]})",
       R"({"strokes": [{"points": [[0, 0, 1]], "radius": 0.3, "metallic": {"value": 1, "x": 0}}]})",
       R"({"strokes": [{"points": [[0, 0, 1]], "radius": 0.3, "metallic": "shiny"}]})",
       R"({"strokes": [{"type": "fill", "roughness": {"value": 0.5, "opacity": -1}}]})"}) {
    try {
      parse_strokes(bad, "s.json", 8);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("s.json: strokes[0].", 0), 0u) << e.what();
    }
  }
  // Run: the pick reports the channels painted there.
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  MaterialTexture mat = MaterialTexture::from_color(OctreeTexture::create(s));
  PaintHistory h;
  const StrokeScript run = parse_strokes(
      R"({"strokes": [{"type": "fill", "roughness": 0.8, "depth": 5},
                      {"type": "pick", "point": [0, 0, 1]}, {"type": "undo"},
                      {"type": "pick", "point": [0, 0, 1]}]})",
      "r.json", 8);
  const ScriptResult r = run_strokes(mat, s, run, h, {0.4f, 0.0f, 0.5f});
  ASSERT_EQ(r.picks.size(), 2u);
  EXPECT_NEAR(r.picks[0].channels[0], 0.8f, 1.0f / 255);
  EXPECT_NEAR(r.picks[1].channels[0], 0.4f, 1.0f / 255);
  EXPECT_EQ(r.undos, 1u);
}

}  // namespace
}  // namespace limn
