// The render layer on the machine's OpenGL (llvmpipe in CI): the GPU's patch evaluation against
// limn's CPU evaluator (which the subdivision tests hold to OpenSubdiv), the drawn coverage
// against the CPU tessellation, and images against what the geometry says they must show.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "limn/mesh/io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/tessellate.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = LIMN_SHARED_MODELS;

// One context for the whole suite (creating one per test costs ~0.3 s on llvmpipe).
GlContext& context() {
  static GlContext gl;
  return gl;
}

struct Case {
  std::string name;
  bool view_depths = false;
  Mesh cage;
  PatchTable table;
  std::vector<float> points;
};

Case make_case(const std::string& name, int depth, bool view_depths) {
  Case c;
  c.name = name;
  c.view_depths = view_depths;
  c.cage = name.starts_with("shape:") ? make_shape(name.substr(6)) : read_mesh(kModels / name);
  PatchOptions po;
  po.subdiv = subdiv_options(c.cage);
  po.depth = depth;
  std::vector<uint8_t> vd;
  if (view_depths) {  // a depth per vertex from a close camera: end caps at many levels
    Camera cam = frame_camera(c.cage, 640, 480);
    for (int k = 0; k < 3; ++k) cam.eye[k] = cam.target[k] + 0.45f * (cam.eye[k] - cam.target[k]);
    DepthOptions d;
    d.tolerance_px = 0.5f;
    d.max_depth = depth;
    vd = select_depths(c.cage, vertex_error_model(c.cage, po.subdiv), cam, d);
  }
  c.table = build_patches(c.cage, po, vd);
  c.points = c.table.points(c.cage.positions);
  return c;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back(make_case("quads/bigguy.obj", 3, false));
  out.push_back(make_case("osd/catmark_car.obj", 2, false));  // creases: single-crease patches
  out.push_back(make_case("osd/catmark_nonquads.obj", 2, true));
  out.push_back(make_case("osd/catmark_hole_test1.obj", 3, false));
  out.push_back(make_case("osd/catmark_single_crease.obj", 3, true));
  out.push_back(make_case("shape:cage", 4, true));  // boundaries, corners, a hole, creases
  out.push_back(make_case("shape:torus", 5, true));
  return out;
}

TEST(Render, ContextStarts) {
  EXPECT_FALSE(context().renderer().empty());
}

// Every point the tessellation shaders produce is where limn's CPU evaluator puts the same
// (patch, s, t): regular, boundary, corner, single-crease and end-cap patches.
TEST(Render, GpuEvaluationEqualsCpu) {
  context();
  for (const Case& c : cases()) {
    PatchDrawer drawer(c.cage, c.table, c.points);
    // A fixed factor from afar, and screen-space rates (a different level on every patch edge)
    // from close by.
    for (int mode = 0; mode < 2; ++mode) {
      Camera cam = frame_camera(c.cage, 640, 480);
      DrawOptions o;
      if (mode == 0) {
        o.factor = 3;
      } else {
        for (int k = 0; k < 3; ++k)
          cam.eye[k] = cam.target[k] + 0.45f * (cam.eye[k] - cam.target[k]);
        o.pixels_per_segment = 24;
      }
      const PatchDrawer::Capture cap = drawer.capture(cam, o);
      ASSERT_FALSE(cap.coords.empty()) << c.name;
      std::set<uint32_t> seen;
      for (const PatchCoord& pc : cap.coords) {
        ASSERT_LT(pc.patch, c.table.patch_count()) << c.name;
        ASSERT_TRUE(pc.s >= 0 && pc.s <= 1 && pc.t >= 0 && pc.t <= 1) << c.name;
        seen.insert(pc.patch);
      }
      EXPECT_EQ(seen.size(), c.table.patch_count()) << c.name << ": every patch is drawn";
      std::vector<float> cpu(cap.positions.size());
      evaluate_patches(c.table, c.points, cap.coords, cpu.data());
      const double diag = bounding_box(c.cage).diagonal();
      double worst = 0;
      for (size_t i = 0; i < cap.coords.size(); ++i) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k)
          d2 += std::pow(double(cpu[3 * i + k]) - cap.positions[3 * i + k], 2);
        worst = std::max(worst, std::sqrt(d2) / diag);
      }
      EXPECT_LT(worst, 1e-5) << c.name << " mode " << mode;
    }
  }
}

std::vector<uint8_t> mask(const std::vector<uint8_t>& rgba) {
  std::vector<uint8_t> m(rgba.size() / 4);
  for (size_t i = 0; i < m.size(); ++i)
    m[i] = rgba[4 * i] != 255 || rgba[4 * i + 1] != 255 || rgba[4 * i + 2] != 255;
  return m;
}

// Background pixels with surface on both sides (left and right, or above and below): cracks.
size_t pinholes(const std::vector<uint8_t>& m, int w, int h) {
  size_t n = 0;
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      if (!m[i] && ((m[i - 1] && m[i + 1]) || (m[i - size_t(w)] && m[i + size_t(w)]))) ++n;
    }
  return n;
}

// The drawn surface covers the pixels the CPU tessellation (watertight by construction) covers,
// with screen-space rates, at a framing and a close camera; where the CPU mesh has no cracks,
// neither has the GPU's.
TEST(Render, CoverageMatchesCpuTessellation) {
  context();
  const int w = 480, h = 360;
  RenderTarget target(w, h, 1);
  const float white[4] = {1, 1, 1, 1};
  for (const Case& c : cases()) {
    PatchDrawer gpu(c.cage, c.table, c.points);
    TessellateOptions to;
    to.factor = 8;
    const Mesh tess = tessellate_patches(c.cage, c.table, c.points, to);
    MeshDrawer cpu(tess);
    for (float zoom : {1.0f, 0.45f}) {
      Camera cam = frame_camera(c.cage, w, h);
      for (int k = 0; k < 3; ++k) cam.eye[k] = cam.target[k] + zoom * (cam.eye[k] - cam.target[k]);
      DrawOptions o;
      o.pixels_per_segment = 4;
      target.begin(white);
      gpu.draw(cam, o);
      const std::vector<uint8_t> a = mask(target.read_rgba());
      target.begin(white);
      cpu.draw(cam, o);
      const std::vector<uint8_t> b = mask(target.read_rgba());
      size_t differ = 0, covered = 0;
      for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i], covered += a[i] || b[i];
      ASSERT_GT(covered, size_t(1000)) << c.name << ": the model is in view";
      EXPECT_LE(double(differ), 0.01 * double(covered)) << c.name << " zoom " << zoom;
      // Cracks: the tessellation rates never open one. With a depth per vertex the patch
      // surface itself has gaps where end caps of two levels meet at an extraordinary vertex
      // (each cap is within the tolerance of the limit surface, so the gap is at most twice
      // it, about a pixel at 0.5 px); the CPU tessellator zips them, the GPU draws them as they
      // are. So the crack count is compared at fixed depths only.
      if (!c.view_depths && pinholes(b, w, h) == 0) {
        EXPECT_EQ(pinholes(a, w, h), 0u) << c.name << " zoom " << zoom;
      }
    }
  }
}

// A cube whose faces have six colours, seen from the front: the middle of the image shows the
// face nearest the camera, in its colour, and the corners show the background.
TEST(Render, MeshFaceColoursLandWhereTheFacesAre) {
  context();
  const Mesh cube = make_shape("cube");
  std::vector<float> colors(3 * cube.face_count());
  const float palette[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {0, 1, 1}, {1, 0, 1}};
  for (size_t f = 0; f < cube.face_count(); ++f)
    for (int k = 0; k < 3; ++k) colors[3 * f + size_t(k)] = palette[f % 6][k];
  // The face whose normal points most towards the camera.
  const Camera cam = frame_camera(cube, 200, 200);
  size_t front = 0;
  double best = -1e9;
  for (size_t f = 0; f < cube.face_count(); ++f) {
    float n[3], c[3] = {0, 0, 0};
    face_normal(cube, f, n);
    for (uint32_t v : cube.face(f))
      for (int k = 0; k < 3; ++k) c[k] += cube.positions[3 * size_t(v) + size_t(k)] / 4;
    double d = 0, len = 0;
    for (int k = 0; k < 3; ++k)
      d += (cam.eye[k] - c[k]) * n[k], len += std::pow(cam.eye[k] - c[k], 2);
    if (d / std::sqrt(len) > best) best = d / std::sqrt(len), front = f;
  }
  MeshDrawer drawer(cube, colors);
  RenderTarget target(200, 200, 1);
  const float black[4] = {0, 0, 0, 1};
  target.begin(black);
  drawer.draw(cam, DrawOptions{});
  const std::vector<uint8_t> px = target.read_rgba();
  const uint8_t* mid = &px[4 * (100 * 200 + 100)];
  for (int k = 0; k < 3; ++k) {
    if (palette[front % 6][k] == 0) {
      EXPECT_LT(mid[k], 40) << "channel " << k;
    } else {
      EXPECT_GT(mid[k], 60) << "channel " << k;
    }
  }
  for (size_t corner : {size_t(0), size_t(199), size_t(199 * 200), size_t(200 * 200 - 1)})
    EXPECT_EQ(px[4 * corner] + px[4 * corner + 1] + px[4 * corner + 2], 0);
}

TEST(Render, PngRoundTripsAndFailsCleanly) {
  const fs::path dir = fs::temp_directory_path() / "limn_render_png";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<uint8_t> px(7 * 5 * 4);
  for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(i * 37 % 256);
  write_png(dir / "a.png", 7, 5, px);
  int w = 0, h = 0;
  EXPECT_EQ(read_png(dir / "a.png", w, h), px);
  EXPECT_EQ(w, 7);
  EXPECT_EQ(h, 5);
  EXPECT_THROW(write_png(dir / "missing" / "b.png", 7, 5, px), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "missing"));
  EXPECT_THROW(write_png(dir / "c.png", 7, 5, std::vector<uint8_t>(3)), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "c.png"));
  { std::ofstream(dir / "not.png") << "no image here"; }
  EXPECT_THROW(read_png(dir / "not.png", w, h), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace limn
