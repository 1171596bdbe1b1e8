// Material textures: the RMH texture beside the colour one, the painter that strokes both, and
// the material eyedropper.
#include "limn/paint/material.hpp"

#include <cmath>
#include <memory>
#include <string>

#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "refine.hpp"

namespace limn {

const char* channel_name(MaterialChannel c) {
  switch (c) {
    case MaterialChannel::roughness:
      return "roughness";
    case MaterialChannel::metallic:
      return "metallic";
    case MaterialChannel::height:
      return "height";
  }
  return "?";
}

Rgba8 rmh_background(const MaterialDefaults& d) {
  const float v[3] = {d.roughness, d.metallic, d.height};
  for (int k = 0; k < kMaterialChannels; ++k)
    if (!(std::isfinite(v[k]) && v[k] >= 0 && v[k] <= 1))
      throw InputError(std::string("default ") + channel_name(MaterialChannel(k)) +
                       ": must be a number in [0, 1]");
  const float rgba[4] = {v[0], v[1], v[2], 0};
  return rgba8_from_float(rgba);
}

std::array<float, 3> material_value(const float rgba[4], Rgba8 background) {
  float def[4];
  rgba8_to_float(background, def);
  std::array<float, 3> v{};
  for (int k = 0; k < 3; ++k) v[size_t(k)] = rgba[k] * rgba[3] + def[k] * (1 - rgba[3]);
  return v;
}

MaterialTexture MaterialTexture::from_color(OctreeTexture color) {
  MaterialTexture m;
  m.height_scale = kDefaultHeightScale * color.size();
  m.color = std::move(color);
  return m;
}

OctreeTexture& MaterialTexture::ensure_rmh(const PaintSurface& surface,
                                           const MaterialDefaults& defaults) {
  if (!rmh) {
    const Rgba8 bg = rmh_background(defaults);
    // The colour texture's cube, so both textures split space alike.
    rmh = OctreeTexture::empty(color.origin(), color.size(), bg);
    refine_surface(*rmh, surface, octree::kStartDepth);
    detail::Refiner(*rmh, surface).prepare_start_lists();
  }
  return *rmh;
}

MaterialDefaults MaterialTexture::defaults() const {
  MaterialDefaults d;
  if (!rmh) return d;
  const Rgba8 bg = rmh->background();
  d.roughness = float(channel(bg, 0)) / 255.0f;
  d.metallic = float(channel(bg, 1)) / 255.0f;
  d.height = float(channel(bg, 2)) / 255.0f;
  return d;
}

size_t MaterialTexture::bytes() const {
  return color.words().size() * 4 + (rmh ? rmh->words().size() * 4 : 0);
}

MaterialPainter::MaterialPainter(MaterialTexture& material, const PaintSurface& surface,
                                 PaintHistory* history, MaterialDefaults defaults)
    : m_(material), s_(surface), history_(history), defaults_(defaults) {}

MaterialPainter::~MaterialPainter() {
  if (stroking_) end();
}

void MaterialPainter::begin(const Brush& brush, const PaintCamera* camera) {
  check_brush(brush, "brush");
  if (stroking_) end();
  // Made before the history starts: the record then holds the stroke's writes to it, and an
  // undo leaves an unpainted RMH texture.
  if (brush.paints_material()) m_.ensure_rmh(s_, defaults_);
  std::unique_ptr<StrokePainter> c, r;
  if (brush.paint_color) c = std::make_unique<StrokePainter>(m_.color, s_, nullptr);
  if (brush.paints_material())
    r = std::make_unique<StrokePainter>(*m_.rmh, s_, nullptr, PaintTarget::rmh);
  for (StrokePainter* p : {c.get(), r.get()})
    if (p) p->set_reuse(reuse_), p->begin(brush, camera);
  if (history_) history_->begin(m_);
  color_ = c.release(), rmh_ = r.release();
  // A brush with neither colour nor a channel on makes a stroke that paints nothing.
  stroking_ = true;
}

template <class F>
bool MaterialPainter::each(F&& f) {
  if (!stroking_) throw std::logic_error("MaterialPainter: outside a stroke");
  bool any = false;
  for (StrokePainter* p : {color_, rmh_})
    if (p) any = f(*p) || any;
  return any;
}

bool MaterialPainter::dab_world(const float p[3]) {
  return each([&](StrokePainter& s) { return s.dab_world(p); });
}

bool MaterialPainter::dab_screen(double px, double py) {
  return each([&](StrokePainter& s) { return s.dab_screen(px, py); });
}

void MaterialPainter::stroke_world(std::span<const float> xyz) {
  each([&](StrokePainter& s) { return s.stroke_world(xyz), true; });
}

void MaterialPainter::stroke_screen(std::span<const double> xy) {
  each([&](StrokePainter& s) { return s.stroke_screen(xy), true; });
}

void MaterialPainter::extend_screen(double px, double py) {
  each([&](StrokePainter& s) { return s.extend_screen(px, py), true; });
}

StrokeStats MaterialPainter::end() {
  StrokeStats total;
  bool first = true;
  for (StrokePainter* p : {color_, rmh_}) {
    if (!p) continue;
    const StrokeStats s = p->end();
    if (first) {
      total = s;
    } else {
      total.samples_changed += s.samples_changed;
      total.leaves_created += s.leaves_created, total.bricks_created += s.bricks_created;
      total.nodes_created += s.nodes_created, total.rays += s.rays;
      total.tasks += s.tasks, total.tasks_threaded += s.tasks_threaded;
      total.ms += s.ms;
    }
    first = false;
  }
  delete color_;
  delete rmh_;
  color_ = rmh_ = nullptr;
  if (stroking_ && history_) history_->end(m_);
  stroking_ = false;
  return total;
}

namespace {

MaterialPick nothing_picked(const MaterialTexture& m) {
  MaterialPick r;
  rgba8_to_float(m.color.background(), r.rgba);
  const MaterialDefaults d = m.defaults();
  r.channels[0] = d.roughness, r.channels[1] = d.metallic, r.channels[2] = d.height;
  return r;
}

MaterialPick pick_at(const MaterialTexture& m, const SurfaceHit& hit) {
  MaterialPick r;
  Rgba8 c;
  r.found = lookup_nearest(m.color, hit.p, hit.n, c);
  rgba8_to_float(c, r.rgba);
  const MaterialDefaults d = m.defaults();
  float rmh[4] = {d.roughness, d.metallic, d.height, 0};
  if (m.rmh) {
    Rgba8 v;
    lookup_nearest(*m.rmh, hit.p, hit.n, v);
    rgba8_to_float(v, rmh);
    const std::array<float, 3> x = material_value(rmh, m.rmh->background());
    for (int k = 0; k < 3; ++k) rmh[k] = x[size_t(k)];
  }
  for (int k = 0; k < 3; ++k) r.channels[k] = rmh[k];
  return r;
}

}  // namespace

MaterialPick pick_world(const MaterialTexture& m, const PaintSurface& s, const float p[3],
                        float max_dist) {
  SurfaceHit hit;
  if (!s.closest_point(p, max_dist, hit)) return nothing_picked(m);
  return pick_at(m, hit);
}

MaterialPick pick_screen(const MaterialTexture& m, const PaintSurface& s, const PaintCamera& camera,
                         double px, double py) {
  float dir[3];
  SurfaceHit hit;
  if (!camera.ray(px, py, dir) || !s.intersect(camera.eye, dir, 0.0f, INFINITY, hit))
    return nothing_picked(m);
  return pick_at(m, hit);
}

}  // namespace limn
