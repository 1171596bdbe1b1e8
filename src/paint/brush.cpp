// Brushes: dabs and strokes over the visible, front-facing surface; fill; eyedropper; texture
// creation (the coarse start tree).
#include "limn/paint/brush.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "limn/paint/lookup.hpp"
#include "refine.hpp"

namespace limn {

using namespace detail;
using namespace paint_detail;

namespace {

bool finite_in(float v, float lo, float hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

std::vector<uint32_t> all_triangles(const PaintSurface& s) {
  std::vector<uint32_t> v;
  v.reserve(s.triangle_count());
  for (uint32_t t = 0; t < s.triangle_count(); ++t) {
    const float* n = s.normal(t);
    if (n[0] != 0 || n[1] != 0 || n[2] != 0) v.push_back(t);
  }
  return v;
}

// Straight-alpha blend of `src` into `dst` at strength w in [0,1].
Rgba8 blend(Rgba8 dst, const float src[4], BlendMode mode, float w) {
  float d[4], o[4];
  rgba8_to_float(dst, d);
  const float a = w * src[3];
  switch (mode) {
    case BlendMode::mix: {
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[k] = o[3] > 0 ? (src[k] * a + d[k] * d[3] * (1 - a)) / o[3] : 0;
      break;
    }
    case BlendMode::add:
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[k] = std::min(1.0f, d[k] + src[k] * a);
      break;
    case BlendMode::multiply:
      for (int k = 0; k < 3; ++k) o[k] = d[k] * (1 - a + a * src[k]);
      o[3] = d[3];
      break;
    case BlendMode::erase:
      for (int k = 0; k < 3; ++k) o[k] = d[k];
      o[3] = d[3] * (1 - w);
      break;
  }
  return rgba8_from_float(o);
}

inline float smooth01(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x * x * (3 - 2 * x);
}

}  // namespace

void check_brush(const Brush& b, const char* what) {
  auto bad = [&](const char* field, const std::string& why) {
    throw InputError(std::string(what) + ": " + field + " " + why);
  };
  if (!(std::isfinite(b.radius) && b.radius > 0 && b.radius <= 1e30f))
    bad("radius", "must be a positive number");
  for (int k = 0; k < 4; ++k)
    if (!finite_in(b.color[k], 0, 1)) bad("color", "components must be numbers in [0, 1]");
  if (!finite_in(b.opacity, 0, 1)) bad("opacity", "must be a number in [0, 1]");
  if (!finite_in(b.hardness, 0, 1)) bad("hardness", "must be a number in [0, 1]");
  if (!(std::isfinite(b.spacing) && b.spacing > 0 && b.spacing <= 10))
    bad("spacing", "must be a number in (0, 10]");
  if (b.depth < 1 || b.depth > octree::kMaxDepth)
    bad("depth", "must be 1-" + std::to_string(octree::kMaxDepth));
  if (!finite_in(b.falloff_angle_deg, 0, 90)) bad("falloff angle", "must be 0-90 degrees");
  if (int(b.blend) > int(BlendMode::erase)) bad("blend", "is not a blend mode");
}

// The per-stroke state: the brush, the eye, and per texel the colour before the stroke and the
// strongest weight any dab of the stroke gave it.
struct StrokePainter::State : LeafPainter {
  State(OctreeTexture& t, const PaintSurface& s) : tex(t), surf(s), refiner(t, s) {}

  OctreeTexture& tex;
  const PaintSurface& surf;
  Refiner refiner;
  Brush brush;
  bool has_camera = false;
  PaintCamera camera;
  StrokeStats stats;
  std::chrono::steady_clock::time_point t0;
  struct Texel {
    Rgba8 orig;
    float w;
  };
  std::unordered_map<uint64_t, Texel> texels;
  // The current dab.
  V3 c, n0;
  bool screen = false;
  double cx = 0, cy = 0;
  float r_world = 0;
  std::vector<uint32_t> tris;

  float weight(V3 q, V3 nq, float half, V3& dir, float& tfar) {
    float t;
    if (screen) {
      double px, py;
      const float qq[3] = {q.x, q.y, q.z};
      if (!camera.project(qq, px, py)) return 0;
      t = float(std::hypot(px - cx, py - cy) / double(brush.radius));
    } else {
      t = length(q - c) / r_world;
    }
    if (!(t <= 1)) return 0;
    const float h = brush.hardness;
    const float f = t <= h ? 1.0f : 1.0f - smooth01((t - h) / (1 - h));
    if (has_camera) {
      dir = v3(camera.eye) - q;
      tfar = length(dir);
      if (!(tfar > 0)) return 0;
      dir = (1 / tfar) * dir;
    } else {
      dir = n0;
      tfar = 2 * r_world;
    }
    const float facing = dot(nq, dir);
    if (!(facing > 0)) return 0;
    const float cs = std::cos(brush.falloff_angle_deg * 3.14159265f / 180.0f);
    const float fa = facing >= cs ? 1.0f : smooth01(facing / cs);
    const float w = brush.opacity * f * fa;
    if (!(w > 0)) return 0;
    // Off the surface by a thousandth of the cell: far less than any sheet the tags separate.
    const float eps = std::max(half * 2e-3f, tex.size() * 1e-6f);
    const V3 o = q + eps * nq;
    const float org[3] = {o.x, o.y, o.z}, d[3] = {dir.x, dir.y, dir.z};
    ++stats.rays;
    if (surf.occluded(org, d, 0.0f, tfar - eps)) return 0;
    return w;
  }

  void paint(const CellBox& box, LeafCell& cell, std::span<const uint32_t> cell_tris) override {
    for (int side = 0; side < 2; ++side) {
      float best = INFINITY;
      V3 q, nq;
      for (uint32_t t : cell_tris) {
        const float* n = surf.normal(t);
        if (octree::side_for_normal(cell.tag, n) != side) continue;
        const V3 p = closest_on_triangle(box.c, v3(surf.corner(t, 0)), v3(surf.corner(t, 1)),
                                         v3(surf.corner(t, 2)));
        const V3 d = p - box.c;
        const float d2 = dot(d, d);
        if (d2 < best) best = d2, q = p, nq = v3(n);
      }
      if (best == INFINITY) continue;
      if (side == 1 && !cell.dbl) cell.dbl = true, cell.s[1] = tex.background();
      V3 dir;
      float tfar;
      const float w = weight(q, nq, box.h, dir, tfar);
      if (!(w > 0)) continue;
      const uint64_t key =
          morton3(box.x, box.y, box.z) | uint64_t(box.level) << 48 | uint64_t(side) << 53;
      auto [it, fresh] = texels.try_emplace(key, Texel{cell.s[side], 0.0f});
      if (w <= it->second.w) continue;
      it->second.w = w;
      const Rgba8 nc = blend(it->second.orig, brush.color, brush.blend, w);
      if (nc != cell.s[side]) ++stats.samples_changed, cell.s[side] = nc;
    }
  }

  void dab(V3 centre, float region_r) {
    c = centre;
    const int depth = brush.depth;
    const float leaf_diag = tex.size() / float(1u << depth) * 1.7320508f;
    const float list_r = region_r + leaf_diag * 1.001f + tex.size() * 1e-5f;
    tris.clear();
    const float cc[3] = {c.x, c.y, c.z};
    surf.triangles_near(cc, list_r, tris);
    Region reg;
    reg.everything = false, reg.c = c, reg.r = region_r;
    refiner.run(reg, tris, depth, this);
    ++stats.dabs;
  }
};

StrokePainter::StrokePainter(OctreeTexture& texture, const PaintSurface& surface,
                             PaintHistory* history)
    : t_(texture), s_(surface), history_(history) {}

StrokePainter::~StrokePainter() {
  if (st_) {
    if (history_) history_->end(t_);
    delete st_;
  }
}

void StrokePainter::begin(const Brush& brush, const PaintCamera* camera) {
  check_brush(brush, "brush");
  if (camera && !camera->valid())
    throw InputError("camera: degenerate (eye at the target, up along the view, or bad fovy/size)");
  if (st_) end();
  st_ = new State(t_, s_);
  st_->brush = brush;
  st_->has_camera = camera != nullptr;
  if (camera) st_->camera = *camera;
  st_->t0 = std::chrono::steady_clock::now();
  if (history_) history_->begin(t_);
}

bool StrokePainter::dab_world(const float p[3]) {
  if (!st_) throw std::logic_error("StrokePainter::dab_world outside a stroke");
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
    throw InputError("stroke: a point is not finite");
  SurfaceHit hit;
  if (!s_.closest_point(p, st_->brush.radius, hit)) {
    ++st_->stats.dabs_missed;
    return false;
  }
  st_->screen = false;
  st_->n0 = v3(hit.n);
  st_->r_world = st_->brush.radius;
  st_->dab(v3(hit.p), st_->brush.radius);
  return true;
}

bool StrokePainter::dab_screen(double px, double py) {
  if (!st_) throw std::logic_error("StrokePainter::dab_screen outside a stroke");
  if (!st_->has_camera) throw InputError("stroke: screen points need a camera");
  if (!(std::isfinite(px) && std::isfinite(py))) throw InputError("stroke: a point is not finite");
  float dir[3];
  SurfaceHit hit;
  if (!st_->camera.ray(px, py, dir) || !s_.intersect(st_->camera.eye, dir, 0.0f, INFINITY, hit) ||
      dot(v3(hit.n), v3(dir)) >= 0) {
    ++st_->stats.dabs_missed;
    return false;
  }
  st_->screen = true;
  st_->cx = px, st_->cy = py;
  st_->n0 = v3(hit.n);
  st_->r_world = float(st_->brush.radius * st_->camera.world_per_pixel(hit.p));
  // A disc on screen is a cone in space: take the surface within twice its radius at the hit.
  st_->dab(v3(hit.p), 2 * st_->r_world);
  return true;
}

namespace {

// Calls f(point) every `step` of arc length along a polyline of `dim`-vectors.
template <class T, class F>
void along(std::span<const T> pts, int dim, double step, F&& f) {
  const size_t n = pts.size() / size_t(dim);
  if (n == 0) return;
  for (T v : pts)
    if (!std::isfinite(double(v))) throw InputError("stroke: a point is not finite");
  double total = 0;
  for (size_t i = 1; i < n; ++i) {
    double l2 = 0;
    for (int k = 0; k < dim; ++k) {
      const double d =
          double(pts[i * size_t(dim) + size_t(k)]) - double(pts[(i - 1) * size_t(dim) + size_t(k)]);
      l2 += d * d;
    }
    total += std::sqrt(l2);
  }
  if (total / step + double(n) > 1e7)
    throw InputError("stroke: more than 10 million dabs (spacing too small for its length)");
  // Dab k sits at arc length k * step, computed from k (not accumulated), so no rounding drift
  // drops or adds the last dab.
  double p[3];
  for (int k = 0; k < dim; ++k) p[k] = double(pts[size_t(k)]);
  f(p);
  uint64_t next = 1;
  double start = 0;  // arc length at the current segment's start
  for (size_t i = 1; i < n; ++i) {
    const T* a = &pts[(i - 1) * size_t(dim)];
    const T* b = &pts[i * size_t(dim)];
    double l2 = 0;
    for (int k = 0; k < dim; ++k)
      l2 += (double(b[k]) - double(a[k])) * (double(b[k]) - double(a[k]));
    const double len = std::sqrt(l2);
    while (double(next) * step <= start + len + 1e-9 * step) {
      const double u = len > 0 ? std::clamp((double(next) * step - start) / len, 0.0, 1.0) : 1.0;
      for (int k = 0; k < dim; ++k) p[k] = double(a[k]) + (double(b[k]) - double(a[k])) * u;
      f(p);
      ++next;
    }
    start += len;
  }
}

}  // namespace

void StrokePainter::stroke_world(std::span<const float> xyz) {
  if (!st_) throw std::logic_error("StrokePainter::stroke_world outside a stroke");
  along(xyz, 3, double(st_->brush.spacing) * st_->brush.radius, [&](const double* p) {
    const float q[3] = {float(p[0]), float(p[1]), float(p[2])};
    dab_world(q);
  });
}

void StrokePainter::stroke_screen(std::span<const double> xy) {
  if (!st_) throw std::logic_error("StrokePainter::stroke_screen outside a stroke");
  along(xy, 2, double(st_->brush.spacing) * st_->brush.radius,
        [&](const double* p) { dab_screen(p[0], p[1]); });
}

StrokeStats StrokePainter::end() {
  if (!st_) return {};
  StrokeStats s = st_->stats;
  s.leaves_created = st_->refiner.stats.leaves_created;
  s.bricks_created = st_->refiner.stats.bricks_created;
  s.nodes_created = st_->refiner.stats.generals_created + st_->refiner.stats.bricks_created;
  s.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - st_->t0).count();
  delete st_;
  st_ = nullptr;
  if (history_) history_->end(t_);
  return s;
}

OctreeTexture OctreeTexture::create(const PaintSurface& s, Rgba8 background, float margin) {
  const Box& b = s.bounds();
  float ext = 0;
  for (int k = 0; k < 3; ++k) ext = std::max(ext, b.max[k] - b.min[k]);
  if (!(ext > 0) || !std::isfinite(ext))
    throw InputError("mesh: its bounding box has no extent; nothing to paint on");
  if (!(margin >= 0 && margin < 10)) throw InputError("texture: margin must be in [0, 10)");
  const float size = ext * (1 + 2 * margin);
  float origin[3];
  for (int k = 0; k < 3; ++k) origin[k] = 0.5f * (b.min[k] + b.max[k]) - 0.5f * size;
  OctreeTexture t = empty(origin, size, background);
  refine_surface(t, s, octree::kStartDepth);
  return t;
}

OctreeTexture OctreeTexture::create(const Mesh& mesh, Rgba8 background, float margin) {
  const PaintSurface s(mesh);
  return create(s, background, margin);
}

void refine_surface(OctreeTexture& t, const PaintSurface& s, int depth) {
  if (depth < 1 || depth > octree::kMaxDepth)
    throw InputError("depth " + std::to_string(depth) + ": must be 1-" +
                     std::to_string(octree::kMaxDepth));
  Refiner r(t, s);
  const std::vector<uint32_t> all = all_triangles(s);
  r.run(Region{}, all, depth, nullptr);
}

namespace {

struct FillPainter : LeafPainter {
  const float* color;
  BlendMode mode;
  float opacity;
  size_t changed = 0;
  void paint(const CellBox&, LeafCell& cell, std::span<const uint32_t>) override {
    for (int side = 0; side < (cell.dbl ? 2 : 1); ++side) {
      const Rgba8 nc = blend(cell.s[side], color, mode, opacity);
      if (nc != cell.s[side]) cell.s[side] = nc, ++changed;
    }
  }
};

}  // namespace

size_t fill(OctreeTexture& t, const PaintSurface& s, const float color[4], BlendMode mode,
            float opacity, int depth) {
  Brush b;
  std::copy_n(color, 4, b.color);
  b.opacity = opacity, b.blend = mode;
  if (depth > 0) b.depth = depth;
  check_brush(b, "fill");
  if (depth > 0) {
    FillPainter p;
    p.color = color, p.mode = mode, p.opacity = opacity;
    Refiner r(t, s);
    const std::vector<uint32_t> all = all_triangles(s);
    r.run(Region{}, all, depth, &p);
    return p.changed;
  }
  std::vector<std::pair<size_t, Rgba8>> writes;
  t.for_each_sample([&](const OctreeSample& x) {
    const Rgba8 nc = blend(x.color, color, mode, opacity);
    if (nc != x.color) writes.push_back({x.word, nc});
  });
  OctreeEditor ed(t);
  for (auto [w, c] : writes) ed.set(uint32_t(w), c);
  recompute_averages(t);
  return writes.size();
}

bool pick_world(const OctreeTexture& t, const PaintSurface& s, const float p[3], float max_dist,
                float rgba[4]) {
  rgba8_to_float(t.background(), rgba);
  SurfaceHit hit;
  if (!s.closest_point(p, max_dist, hit)) return false;
  Rgba8 c;
  const bool ok = lookup_nearest(t, hit.p, hit.n, c);
  rgba8_to_float(c, rgba);
  return ok;
}

bool pick_screen(const OctreeTexture& t, const PaintSurface& s, const PaintCamera& camera,
                 double px, double py, float rgba[4]) {
  rgba8_to_float(t.background(), rgba);
  float dir[3];
  SurfaceHit hit;
  if (!camera.ray(px, py, dir) || !s.intersect(camera.eye, dir, 0.0f, INFINITY, hit)) return false;
  Rgba8 c;
  const bool ok = lookup_nearest(t, hit.p, hit.n, c);
  rgba8_to_float(c, rgba);
  return ok;
}

namespace {

Rgba8 average_brick(OctreeEditor& ed, uint32_t word) {
  const Rgba8 avg = brick_average(decode_brick(ed.pool(), word));
  ed.set((word & ~octree::kBrickDoubleFlag) + ((word & octree::kBrickDoubleFlag) ? 4 : 2), avg);
  return avg;
}

Rgba8 average_general(OctreeEditor& ed, uint32_t ptr, uint32_t info) {
  const GeneralNode n = decode_general(ed.pool(), ptr, info);
  ColorMean m;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::leaf) add_leaf(m, n.leaf[c]);
    if (n.kind[c] == CellKind::general) m.add(average_general(ed, n.ptr[c], n.info[c]));
    if (n.kind[c] == CellKind::brick) m.add(average_brick(ed, n.ptr[c]));
  }
  const Rgba8 avg = m.mean();
  ed.set(ptr + 2 * uint32_t(popc(octree::generals(info))) + uint32_t(popc(octree::bricks(info))),
         avg);
  return avg;
}

}  // namespace

void recompute_averages(OctreeTexture& t) {
  OctreeEditor ed(t);
  const uint32_t info = ed.word(1);
  if (octree::occupied(info)) average_general(ed, ed.word(0), info);
}

}  // namespace limn
