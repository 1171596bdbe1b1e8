// Paint memory per painted texel at depth 10, by stroke shape: the goal of issue 28 (<= 6 bytes
// per painted texel for strokes, radius 4-32 leaves, straight and curved, fills no worse),
// measured on the shared meshes beside a whole-surface fill of the same mesh.
//   straight: a line 320 leaves long through a surface point along a tangent there;
//   curved:   3/4 of a circle of radius 64 leaves around a surface point, in its tangent plane;
// each polyline sampled every leaf and pulled to the nearest surface point, painted as one world
// stroke (hardness 0.5, spacing 0.25, depth 10) on a fresh texture. A leaf is the texture cube's
// edge / 2^10. Bytes are the pool's after compact(), as `limn paint` saves it; painted texels are
// the samples whose colour differs from the background (OctreeTexture::stats). Means over the
// seeds, and the worst seed.
//   limn_bench_paint_memory [--models DIR] [--seeds N] [--only NAME]
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/vec3.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"

namespace fs = std::filesystem;

namespace {

using limn::Mesh;

struct Frame {
  limn::Vec3f p, t1, t2;  // a surface point and two unit tangents there
};

Frame seed_frame(const Mesh& m, const std::vector<float>& normals, std::mt19937& rng) {
  std::uniform_int_distribution<size_t> pick(0, m.vertex_count() - 1);
  for (;;) {
    const size_t v = pick(rng);
    const limn::Vec3f n = limn::load3<float>(&normals[3 * v]);
    const float len = limn::length(n);
    if (!(len > 0)) continue;
    const limn::Vec3f u = (1 / len) * n;
    const limn::Vec3f a = std::fabs(u.x) < 0.9f ? limn::Vec3f{1, 0, 0} : limn::Vec3f{0, 1, 0};
    const limn::Vec3f c = limn::cross(a, u);
    const limn::Vec3f t1 = (1 / limn::length(c)) * c;
    return {limn::load3<float>(&m.positions[3 * v]), t1, limn::cross(u, t1)};
  }
}

// Points every `leaf` along the curve, each pulled to the nearest surface point (dropped when
// none lies within 40 leaves).
template <class Curve>
std::vector<float> on_surface(const limn::PaintSurface& s, float length, float leaf, Curve at) {
  std::vector<float> xyz;
  for (float d = 0; d <= length; d += leaf) {
    float q[3];
    at(d, q);
    limn::SurfaceHit h;
    if (s.closest_point(q, 40 * leaf, h)) xyz.insert(xyz.end(), {h.p[0], h.p[1], h.p[2]});
  }
  return xyz;
}

struct Result {
  double bytes = 0, painted = 0, per_texel = 0;
};

Result measure(limn::OctreeTexture& t) {
  t.compact();
  const limn::OctreeTextureStats s = t.stats();
  return {double(s.bytes), double(s.painted_samples), s.bytes_per_painted_texel};
}

}  // namespace

int main(int argc, char** argv) {
  fs::path models = fs::path(LIMN_SHARED_MODELS) / "tri";
  int seeds = 2;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--models") && i + 1 < argc) {
      models = argv[++i];
    } else if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) {
      seeds = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) {
      only = argv[++i];
    } else {
      fmt::print(stderr,
                 "usage: limn_bench_paint_memory [--models DIR] [--seeds N] [--only NAME]\n");
      return 2;
    }
  }
  const float red[4] = {1, 0, 0, 1};
  fmt::print("{:<16} {:<9} {:>6} {:>10} {:>11} {:>9} {:>9}\n", "mesh", "stroke", "radius",
             "painted", "bytes", "B/texel", "worst");
  for (const char* name : {"spot.obj", "fandisk.obj", "rocker-arm.obj"}) {
    if (!only.empty() && only != name) continue;
    const Mesh mesh = limn::read_mesh(models / name);
    const limn::PaintSurface surface(mesh);
    const std::vector<float> normals = limn::vertex_normals(mesh);
    const limn::OctreeTexture fresh = limn::OctreeTexture::create(surface);
    const float leaf = fresh.size() / 1024.0f;
    for (const char* shape : {"straight", "curved"}) {
      for (const int radius : {4, 8, 16, 32}) {
        std::mt19937 rng(11);
        double bytes = 0, painted = 0, worst = 0;
        for (int s = 0; s < seeds; ++s) {
          const Frame f = seed_frame(mesh, normals, rng);
          std::vector<float> xyz;
          if (!std::strcmp(shape, "straight")) {
            xyz = on_surface(surface, 320 * leaf, leaf, [&](float d, float q[3]) {
              const limn::Vec3f x = f.p + (d - 160 * leaf) * f.t1;
              q[0] = x.x, q[1] = x.y, q[2] = x.z;
            });
          } else {
            const float r = 64 * leaf;
            xyz = on_surface(surface, 1.5f * float(M_PI) * r, leaf, [&](float d, float q[3]) {
              const float a = d / r;
              const limn::Vec3f x = f.p + r * (std::cos(a) * f.t1 + std::sin(a) * f.t2);
              q[0] = x.x, q[1] = x.y, q[2] = x.z;
            });
          }
          limn::OctreeTexture t = fresh;
          limn::StrokePainter painter(t, surface);
          limn::Brush b;
          b.radius = float(radius) * leaf, b.depth = 10, b.hardness = 0.5f, b.spacing = 0.25f;
          std::copy_n(red, 4, b.color);
          painter.begin(b);
          painter.stroke_world(xyz);
          painter.end();
          const Result r = measure(t);
          bytes += r.bytes, painted += r.painted, worst = std::max(worst, r.per_texel);
        }
        fmt::print("{:<16} {:<9} {:>6} {:>10.0f} {:>11.0f} {:>9.2f} {:>9.2f}\n", name, shape,
                   radius, painted / seeds, bytes / seeds, bytes / std::max(painted, 1.0), worst);
        std::fflush(stdout);
      }
    }
    limn::OctreeTexture t = fresh;
    limn::fill(t, surface, red, limn::BlendMode::mix, 1.0f, 10);
    const Result r = measure(t);
    fmt::print("{:<16} {:<9} {:>6} {:>10.0f} {:>11.0f} {:>9.2f} {:>9.2f}\n", name, "fill", "-",
               r.painted, r.bytes, r.per_texel, r.per_texel);
  }
  return 0;
}
