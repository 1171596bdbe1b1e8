// Material shading on the GPU (llvmpipe here), held to material.glsl's model computed on the CPU
// for pixels whose surface normal is known analytically: a sphere with a glossy metal dab
// (roughness and metallic where painted, the defaults elsewhere), and a flat sheet whose height
// ramp tilts its shading normal as the bump should.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "limn/paint/brush.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "material_oracle.hpp"

namespace limn {
namespace {

GlContext& context() {
  static GlContext gl;
  return gl;
}

using D3 = std::array<double, 3>;
D3 normalized(D3 a) {
  const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  return {a[0] / l, a[1] / l, a[2] / l};
}
double dot(D3 a, D3 b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// material.glsl's shading, written out again: sRGB base colour, roughness, metallic, the shading
// normal n and the direction to the eye v. Returns 8-bit sRGB.
D3 shade_cpu(D3 base, double rough, double metal, D3 n, D3 v) {
  const double pi = 3.14159265;
  rough = std::clamp(rough, 0.03, 1.0);
  const double a = rough * rough, a2 = a * a, k = 0.5 * a;
  D3 albedo, f0, c;
  for (int i = 0; i < 3; ++i) {
    albedo[i] = std::pow(base[i], 2.2);
    f0[i] = 0.04 + (albedo[i] - 0.04) * metal;
    c[i] = 0.1 * albedo[i] * (1 - metal) + (0.55 - 0.3 * rough) * f0[i];
  }
  const double nv = std::max(dot(n, v), 1e-4);
  for (int li = 0; li < 2; ++li) {
    const D3 l = li == 0 ? v : normalized({v[0] + 0.3, v[1] + 0.5, v[2]});
    const double power = li == 0 ? 0.8 : 0.45;
    const double nl = dot(n, l);
    if (nl <= 0) continue;
    const D3 h = normalized({v[0] + l[0], v[1] + l[1], v[2] + l[2]});
    const double nh = std::max(dot(n, h), 0.0), vh = std::max(dot(v, h), 0.0);
    const double dd = nh * nh * (a2 - 1) + 1;
    const double D = a2 / (pi * dd * dd);
    const double G = nl / (nl * (1 - k) + k) * nv / (nv * (1 - k) + k);
    for (int i = 0; i < 3; ++i) {
      const double F = f0[i] + (1 - f0[i]) * std::pow(1 - vh, 5.0);
      const double spec = D * G * F / (4 * nl * nv);
      const double diff = (1 - F) * (1 - metal) * albedo[i] / pi;
      c[i] += (diff + spec) * nl * power * pi;
    }
  }
  for (double& x : c) x = 255 * std::pow(std::clamp(x, 0.0, 1.0), 1 / 2.2);
  return c;
}

Camera looking_down_z(double distance, double fovy) {
  Camera cam;
  cam.eye[0] = 0, cam.eye[1] = 0, cam.eye[2] = float(distance);
  cam.width = cam.height = 200;
  cam.fovy_deg = float(fovy);
  return cam;
}

// The material drawn by MeshDrawer over black, as the viewer and limn render draw it.
std::vector<uint8_t> draw_material(const Mesh& m, const MaterialTexture& mat, const Camera& cam) {
  GpuOctreeTexture color(mat.color), rmh(*mat.rmh);
  MeshDrawer drawer(m);
  RenderTarget target(cam.width, cam.height, 1);
  const float black[4] = {0, 0, 0, 1};
  target.begin(black);
  DrawOptions o;
  o.texture = &color;
  o.material = &rmh;
  o.height_scale = mat.height_scale;
  drawer.draw(cam, o);
  return target.read_rgba();
}

const uint8_t* pixel(const std::vector<uint8_t>& px, const Camera& cam, const float p[3]) {
  double x, y;
  EXPECT_TRUE(cam.project(p, x, y));
  return &px[4 * (size_t(y) * size_t(cam.width) + size_t(x))];
}

TEST(RenderMaterial, AGlossyMetalDabShadesAsTheModelSays) {
  context();
  const Mesh sphere = test::uv_sphere(1.0, 48, 96);
  const PaintSurface s(sphere);
  MaterialTexture mat =
      MaterialTexture::from_color(OctreeTexture::create(s, pack_rgba8(230, 180, 120, 255)));
  const float dab[3] = {0.35f, 0.25f, std::sqrt(1.0f - 0.35f * 0.35f - 0.25f * 0.25f)};
  Brush b;
  b.depth = 9, b.radius = 0.2f, b.hardness = 1, b.paint_color = false;
  b.material[int(MaterialChannel::metallic)] = {true, 1.0f, BlendMode::mix, 1.0f};
  b.material[int(MaterialChannel::roughness)] = {true, 0.25f, BlendMode::mix, 1.0f};
  MaterialPainter p(mat, s, nullptr, {0.6f, 0.0f, 0.5f});
  p.begin(b);
  p.dab_world(dab);
  p.end();
  ASSERT_TRUE(mat.rmh.has_value());
  const MaterialDefaults d = mat.defaults();

  const Camera cam = looking_down_z(4, 40);
  const std::vector<uint8_t> px = draw_material(sphere, mat, cam);
  const D3 base = {230 / 255.0, 180 / 255.0, 120 / 255.0};
  // Points on the sphere: the normal is the point; the eye is at (0, 0, 4).
  struct Probe {
    float p[3];
    double rough, metal;
  };
  const Probe probes[] = {
      {{dab[0], dab[1], dab[2]}, 64 / 255.0, 1.0},  // 0.25 and 1 in 8 bits
      {{-0.4f, -0.3f, std::sqrt(1 - 0.16f - 0.09f)}, d.roughness, d.metallic},
      {{-0.5f, 0.45f, std::sqrt(1 - 0.25f - 0.2025f)}, d.roughness, d.metallic}};
  for (const Probe& q : probes) {
    const D3 n = normalized({q.p[0], q.p[1], q.p[2]});
    const D3 v = normalized({-q.p[0], -q.p[1], 4.0 - q.p[2]});
    const D3 want = shade_cpu(base, q.rough, q.metal, n, v);
    const uint8_t* got = pixel(px, cam, q.p);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(double(got[k]), want[size_t(k)], 6.0)
          << "probe (" << q.p[0] << ", " << q.p[1] << ") channel " << k;
  }
  // The metal dab off the highlight has no diffuse light: darker than the dielectric beside it.
  const D3 metal = shade_cpu(base, 64 / 255.0, 1.0, normalized({dab[0], dab[1], dab[2]}),
                             normalized({-dab[0], -dab[1], 4.0 - dab[2]}));
  const D3 plain = shade_cpu(base, d.roughness, d.metallic, normalized({dab[0], dab[1], dab[2]}),
                             normalized({-dab[0], -dab[1], 4.0 - dab[2]}));
  EXPECT_GT(std::abs(metal[0] - plain[0]), 20.0);  // so the probes above tell them apart
}

TEST(RenderMaterial, AHeightRampTiltsTheShadingNormal) {
  context();
  Mesh m = test::lifted_sheet(-1, 1, 32, -0.7f);
  m.uvs.clear(), m.uv_indices.clear();
  const PaintSurface s(m);
  MaterialTexture mat =
      MaterialTexture::from_color(OctreeTexture::create(s, pack_rgba8(200, 200, 200, 255)));
  mat.height_scale = 2.0f;
  const double slope = test::paint_height_ramp(mat, s) * mat.height_scale;  // model units
  const Camera cam = looking_down_z(3, 30);
  const std::vector<uint8_t> px = draw_material(m, mat, cam);
  const D3 base = {200 / 255.0, 200 / 255.0, 200 / 255.0};
  const MaterialDefaults d = mat.defaults();
  const D3 bumped = normalized({-slope, 0, 1});
  int checked = 0;
  for (float x : {-0.4f, -0.1f, 0.2f, 0.45f})
    for (float y : {-0.3f, 0.25f}) {
      const float p[3] = {x, y, 0};
      const D3 v = normalized({-x, -y, 3.0});
      const D3 want = shade_cpu(base, d.roughness, d.metallic, bumped, v);
      const D3 flat = shade_cpu(base, d.roughness, d.metallic, {0, 0, 1}, v);
      const uint8_t* got = pixel(px, cam, p);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(double(got[k]), want[size_t(k)], 4.0) << x << "," << y;
        // The tilt shows: nearer the bumped shading than the flat one.
        EXPECT_LT(std::abs(got[k] - want[size_t(k)]), std::abs(got[k] - flat[size_t(k)]) + 0.5)
            << x << "," << y;
      }
      ++checked;
    }
  EXPECT_EQ(checked, 8);
}

}  // namespace
}  // namespace limn
