#include "scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <stdexcept>

#include "limn/io/mesh_io.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/surface.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"

namespace limn::view {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Cages above this are isolated per view instead of selected from a hierarchy, as `limn
// subdivide --adaptive --errors auto` decides (the hierarchy is built whole, level by level).
constexpr size_t kMeasuredFaces = 32768;
// About this many triangles in the dense mesh painted on: close enough to the limit surface that
// filtered lookups on the drawn surface find the texels painted on the mesh (nearest ones miss
// a few, where the surface crosses into a cell the mesh does not), few enough for quick brush
// hit tests and a quick simplify.
constexpr double kDenseTriangles = 120000;

void count_patches(const PatchTable& t, FrameStats& fs) {
  fs.regular = t.regular_params.size(), fs.gregory = t.gregory_params.size();
  fs.deepest = 0;
  for (const auto* params : {&t.regular_params, &t.gregory_params})
    for (const PatchParam& p : *params) fs.deepest = std::max(fs.deepest, int(p.level));
}

bool same_camera(const Camera& a, const Camera& b) {
  return std::equal(a.eye, a.eye + 3, b.eye) && std::equal(a.target, a.target + 3, b.target) &&
         std::equal(a.up, a.up + 3, b.up) && a.fovy_deg == b.fovy_deg && a.width == b.width &&
         a.height == b.height;
}

}  // namespace

std::vector<float> cluster_palette(const std::vector<uint32_t>& ids) {
  // Hue steps by the golden ratio of a turn; saturation and value alternate, so clusters split
  // from one another (neighbouring ids) differ even when their hues come out close.
  std::vector<float> out(3 * ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    const uint32_t id = ids[i];
    const double h = std::fmod(double(id) * 0.618033988749895, 1.0) * 6.0;
    const double s = id % 2 ? 0.75 : 0.45, v = (id / 2) % 2 ? 0.78 : 0.95;
    const double f = h - std::floor(h);
    const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    const double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    for (int k = 0; k < 3; ++k) out[3 * i + size_t(k)] = float(rgb[int(h) % 6][k]);
  }
  return out;
}

Scene::Scene(Mesh cage, std::string name) : cage_(std::move(cage)), name_(std::move(name)) {
  options_.subdiv = subdiv_options(cage_);
}

Scene::~Scene() {
  if (preparing_.valid()) preparing_.wait();
}

void Scene::prepare_paint_in_background() {
  if (preparing_.valid() || texture_) return;
  preparing_ = std::async(std::launch::async, [this] { build_paint(); });
}

void Scene::join_preparation() {
  if (preparing_.valid()) preparing_.get();  // rethrows what the thread threw
}

void Scene::warm_up_paint() {
  if (!preparing_.valid() || stroking_) return;
  if (preparing_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  join_preparation();
  sync_gpu_texture();
}

void Scene::release_gl() {
  cage_drawer_.reset();
  fixed_drawer_.reset();
  dynamic_drawer_.reset();
  painted_drawer_.reset();
  gpu_texture_.reset();
  gpu_rmh_.reset();
  clusters_drawer_.reset();
  simplified_drawer_.reset();
  fixed_depth_ = -1;
}

void Scene::ensure_hierarchy(int max_depth) {
  if (hierarchy_depth_ == max_depth) return;
  PatchOptions po = options_;
  po.depth = max_depth;
  model_ = vertex_error_model(cage_, po.subdiv);
  measured_ = cage_.face_count() <= kMeasuredFaces;
  hierarchy_ = {};
  hierarchy_points_.clear();
  if (measured_) {
    hierarchy_ = build_patch_hierarchy(cage_, po);
    measure_vertex_errors(cage_, hierarchy_, model_);
    hierarchy_points_ = hierarchy_.table.points(cage_.positions);
  }
  hierarchy_depth_ = max_depth;
  vdepth_.clear();
  dynamic_drawer_.reset();
}

void Scene::draw_surface(const Camera& camera, const SurfaceSettings& s, const DrawOptions& o,
                         FrameStats& fs) {
  fs.patches = true;
  if (!s.dynamic) {
    if (fixed_depth_ != s.depth || !fixed_drawer_) {
      const auto t0 = std::chrono::steady_clock::now();
      PatchOptions po = options_;
      po.depth = s.depth;
      fixed_ = build_patches(cage_, po);
      fixed_points_ = fixed_.points(cage_.positions);
      fixed_drawer_ = std::make_unique<PatchDrawer>(cage_, fixed_, fixed_points_);
      fixed_depth_ = s.depth;
      fs.select_ms = ms_since(t0), fs.reselected = true;
    }
    count_patches(fixed_, fs);
    fs.draw = fixed_drawer_->draw(camera, o);
    return;
  }
  ensure_hierarchy(s.max_depth);
  const bool unchanged = dynamic_drawer_ && selected_tolerance_ == s.tolerance_px &&
                         same_camera(selected_camera_, camera);
  if (!unchanged) {
    const auto t0 = std::chrono::steady_clock::now();
    DepthOptions d;
    d.tolerance_px = s.tolerance_px;
    d.max_depth = s.max_depth;
    // Hysteresis only across camera moves: a new tolerance starts from scratch.
    const bool keep = selected_tolerance_ == s.tolerance_px;
    std::vector<uint8_t> depth =
        select_depths(cage_, model_, camera, d, keep ? vdepth_ : std::vector<uint8_t>{});
    if (depth != vdepth_ || !dynamic_drawer_) {
      vdepth_ = std::move(depth);
      if (measured_) {
        selection_ = select_patches(hierarchy_, vdepth_);
        // Same hierarchy, same points: only the selection's patch arrays go to the GPU.
        if (dynamic_drawer_ && dynamic_from_hierarchy_)
          dynamic_drawer_->set_patches(selection_);
        else
          dynamic_drawer_ = std::make_unique<PatchDrawer>(cage_, selection_, hierarchy_points_);
        dynamic_from_hierarchy_ = true;
      } else {
        PatchOptions po = options_;
        po.depth = s.max_depth;
        selection_ = build_patches(cage_, po, vdepth_);
        selection_points_ = selection_.points(cage_.positions);
        dynamic_drawer_ = std::make_unique<PatchDrawer>(cage_, selection_, selection_points_);
        dynamic_from_hierarchy_ = false;
      }
      fs.reselected = true;
    }
    selected_tolerance_ = s.tolerance_px;
    selected_camera_ = camera;
    fs.select_ms = ms_since(t0);
  }
  count_patches(selection_, fs);
  fs.draw = dynamic_drawer_->draw(camera, o);
}

FrameStats Scene::draw(Display display, const Camera& camera, const SurfaceSettings& s,
                       const DrawOptions& options) {
  FrameStats fs;
  DrawOptions o = options;
  o.texture = nullptr;
  o.material = nullptr;
  if ((display == Display::clusters || display == Display::simplified) && !vsa_)
    display = Display::painted;
  switch (display) {
    case Display::cage:
      if (!cage_drawer_)
        cage_drawer_ = std::make_unique<MeshDrawer>(cage_, std::span<float>{}, true);
      fs.draw = cage_drawer_->draw(camera, o);
      break;
    case Display::surface:
      draw_surface(camera, s, o, fs);
      break;
    case Display::painted:
      // The texture was painted on the dense tessellation and is looked up on what is drawn:
      // for cages the limit surface itself, as `surface` draws it (no bake to keep in step;
      // see kDenseTriangles for how close the two are).
      sync_gpu_texture();
      o.texture = gpu_texture_.get();
      o.material = gpu_rmh_.get();
      o.height_scale = texture_->height_scale;
      if (is_cage()) {
        draw_surface(camera, s, o, fs);
      } else {
        if (!painted_drawer_) painted_drawer_ = std::make_unique<MeshDrawer>(dense());
        fs.draw = painted_drawer_->draw(camera, o);
      }
      break;
    case Display::clusters:
      if (!clusters_drawer_)
        clusters_drawer_ = std::make_unique<MeshDrawer>(dense(), cluster_palette(vsa_->labels));
      fs.draw = clusters_drawer_->draw(camera, o);
      break;
    case Display::simplified:
      if (!simplified_drawer_)
        simplified_drawer_ = std::make_unique<MeshDrawer>(
            vsa_->output.mesh, cluster_palette(vsa_->output.face_cluster), true);
      fs.draw = simplified_drawer_->draw(camera, o);
      break;
  }
  return fs;
}

const Mesh& Scene::dense() {
  join_preparation();
  return dense_mesh();
}

const Mesh& Scene::dense_mesh() {
  if (dense_) return *dense_;
  if (!is_cage()) {
    dense_ = cage_;
    return *dense_;
  }
  // Depth 2 everywhere: every patch is a quad of the twice-refined cage, so one tessellation
  // factor gives an even triangle size over the whole surface.
  PatchOptions po = options_;
  po.depth = 2;
  const PatchTable t = build_patches(cage_, po);
  TessellateOptions to;
  to.factor = std::clamp(
      int(std::sqrt(kDenseTriangles / (2.0 * double(std::max<size_t>(t.patch_count(), 1))))), 1,
      16);
  dense_ = tessellate_patches(cage_, t, t.points(cage_.positions), to);
  return *dense_;
}

void Scene::build_paint() {
  surface_ = std::make_unique<PaintSurface>(dense_mesh());
  texture_ = std::make_unique<MaterialTexture>(MaterialTexture::from_color(
      OctreeTexture::create(*surface_, pack_rgba8(214, 214, 220, 255))));
  painter_ = std::make_unique<MaterialPainter>(*texture_, *surface_, &history_);
}

void Scene::ensure_paint() {
  join_preparation();
  if (texture_) return;
  build_paint();
  gpu_dirty_ = true;
}

void Scene::sync_gpu_texture() {
  ensure_paint();
  if (gpu_texture_ && !gpu_dirty_) return;
  const auto t0 = std::chrono::steady_clock::now();
  if (!gpu_texture_) {
    gpu_texture_ = std::make_unique<GpuOctreeTexture>(texture_->color);
  } else {
    gpu_texture_->update(texture_->color);
  }
  size_t words = gpu_texture_->last_upload_words();
  if (texture_->rmh) {
    if (!gpu_rmh_)
      gpu_rmh_ = std::make_unique<GpuOctreeTexture>(*texture_->rmh);
    else
      gpu_rmh_->update(*texture_->rmh);
    words += gpu_rmh_->last_upload_words();
  } else {
    gpu_rmh_.reset();
  }
  gpu_dirty_ = false;
  stroke_times_.upload_ms += ms_since(t0);
  ++stroke_times_.uploads;
  stroke_times_.upload_words += words;
}

void Scene::begin_stroke(const Brush& brush, const Camera& camera, bool replayable) {
  ensure_paint();
  if (stroking_) end_stroke();
  stroke_times_ = {};
  stroke_points_.clear();
  before_stroke_.reset();
  if (replayable) before_stroke_ = *texture_;
  stroke_brush_ = brush;
  PaintCamera pc;
  std::copy(camera.eye, camera.eye + 3, pc.eye);
  std::copy(camera.target, camera.target + 3, pc.target);
  std::copy(camera.up, camera.up + 3, pc.up);
  pc.fovy_deg = camera.fovy_deg, pc.width = camera.width, pc.height = camera.height;
  stroke_camera_ = pc;
  painter_->begin(brush, &pc);
  stroking_ = true;
}

void Scene::stroke_to(double x, double y) {
  if (!stroking_) throw std::logic_error("stroke_to outside a stroke");
  const auto t0 = std::chrono::steady_clock::now();
  // The drag's points extend one polyline: its dabs are those of the whole stroke painted at
  // once, none repeated where one mouse move ends and the next begins.
  painter_->extend_screen(x, y);
  stroke_points_.insert(stroke_points_.end(), {x, y});
  gpu_dirty_ = true;
  stroke_times_.paint_ms += ms_since(t0);
}

StrokeStats Scene::replay_stroke() const {
  if (!before_stroke_ || stroke_points_.empty()) return {};
  // With an undo record, as the viewer's own painter keeps one: the same work asked of the
  // library. Caches are emptied first: the viewer's stroke began after a frame had filled them
  // with other data, and a replay right after the stroke would find its data still there.
  MaterialTexture copy = *before_stroke_;
  {
    std::vector<uint8_t> flush(size_t(64) << 20);
    for (size_t i = 0; i < flush.size(); i += 64) flush[i] = uint8_t(i);
    volatile uint8_t sink = flush[flush.size() / 2];
    (void)sink;
  }
  PaintHistory history;
  MaterialPainter painter(copy, *surface_, &history);
  painter.begin(stroke_brush_, &stroke_camera_);
  if (stroke_points_.size() == 2)
    painter.dab_screen(stroke_points_[0], stroke_points_[1]);
  else
    painter.stroke_screen(stroke_points_);
  return painter.end();
}

StrokeStats Scene::end_stroke() {
  if (!stroking_) return {};
  stroking_ = false;
  gpu_dirty_ = true;
  return painter_->end();
}

bool Scene::undo() {
  join_preparation();
  if (!texture_ || stroking_ || !history_.undo(*texture_)) return false;
  gpu_dirty_ = true;
  return true;
}

bool Scene::redo() {
  join_preparation();
  if (!texture_ || stroking_ || !history_.redo(*texture_)) return false;
  gpu_dirty_ = true;
  return true;
}

void Scene::save_texture(const std::filesystem::path& path) {
  ensure_paint();
  save_lot(*texture_, path);
}

void Scene::load_texture(const std::filesystem::path& path) {
  ensure_paint();
  if (stroking_) end_stroke();
  MaterialTexture t = load_lot(path);
  // The painter holds a reference to *texture_: replace the contents, not the object.
  *texture_ = std::move(t);
  history_.clear();
  gpu_dirty_ = true;
}

const VsaResult& Scene::simplify(size_t proxies) {
  const auto t0 = std::chrono::steady_clock::now();
  VsaOptions vo;
  vo.proxies = proxies;
  vo.meshing.polygons = true;
  vsa_ = simplify_vsa(dense(), vo, name_);
  vsa_ms_ = ms_since(t0);
  clusters_drawer_.reset();
  simplified_drawer_.reset();
  return *vsa_;
}

void Scene::export_simplified(const std::filesystem::path& path) const {
  if (!vsa_) throw std::runtime_error(fmt::format("{}: nothing simplified yet", path.string()));
  write_mesh(vsa_->output.mesh, path);
}

}  // namespace limn::view
