// limn-view: what the viewer shows and edits, independent of the window and the UI. It composes
// the library as the limn CLI does: the adaptive surface (a patch hierarchy built once, then a
// view change only re-selects depths and patches), paint on a dense tessellation of the surface
// into an octree texture (looked up per fragment on the GPU when the surface is drawn, so a
// stroke only sends the words it changed), and VSA of that tessellation.
// Drawing needs a current OpenGL 4.5 context; everything is built on first use.
#pragma once

#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/undo.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/texture.hpp"
#include "limn/simplify/vsa.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "script.hpp"

namespace limn::view {

struct SurfaceSettings {
  bool dynamic = true;        ///< a depth per vertex from the view, else one fixed depth
  int depth = 3;              ///< fixed depth
  float tolerance_px = 1.0f;  ///< dynamic: screen error allowed, pixels
  int max_depth = 8;          ///< dynamic: the hierarchy's depth (a rebuild when changed)
  float tess_px = 8.0f;       ///< about one tessellation segment per this many pixels
};

struct FrameStats {
  DrawStats draw;
  size_t regular = 0, gregory = 0;  ///< patches of the surface shown
  int deepest = 0;                  ///< deepest patch level shown
  double select_ms = 0;             ///< depth + patch selection (0 when the view kept them)
  bool reselected = false;
  bool patches = false;  ///< the limit surface was drawn (the patch counts apply)
};

/// Where a stroke's time went in the viewer (since begin_stroke).
struct StrokeTimes {
  double paint_ms = 0;   ///< in the painter: picking and dabs (the library's work)
  double upload_ms = 0;  ///< sending the texture's changes to the GPU
  size_t uploads = 0, upload_words = 0;
};

class Scene {
 public:
  /// Takes the cage (or mesh) and its name for messages. Cheap: nothing is built yet.
  Scene(Mesh cage, std::string name);
  ~Scene();

  /// Builds what painting needs (the dense mesh, its ray-cast surface, a fresh texture) on a
  /// thread of its own, so the first stroke does not wait for it; everything that reads those
  /// waits for the thread first. Call once, before anything else uses the scene.
  void prepare_paint_in_background();
  /// Between frames: once the background work is done, sends the texture to the GPU, so the
  /// first stroke's frame does not pay for it either. Cheap when there is nothing to do.
  void warm_up_paint();

  const Mesh& cage() const { return cage_; }
  const std::string& name() const { return name_; }
  /// Meshes up to this many faces are treated as subdivision cages: their limit surface is drawn,
  /// painted and simplified. Larger ones (scans) are painted and simplified as they are.
  static constexpr size_t kCageFaces = 20000;
  bool is_cage() const { return cage_.face_count() <= kCageFaces; }

  /// Draws into the bound framebuffer. The surface re-selects its patches when the camera or
  /// the settings changed its depths. `painted` is the surface (cages) or the mesh (scans)
  /// coloured by the texture, sent to the GPU first if it changed since the last draw;
  /// `options.texture` is ignored (the scene's own is used for `painted`, none otherwise).
  FrameStats draw(Display display, const Camera& camera, const SurfaceSettings& surface,
                  const DrawOptions& options);

  /// Deletes every GL object (drawers, the GPU texture); the next draw makes them again. Call
  /// while the context they were made in is still current (before its window closes).
  void release_gl();

  // Paint (on the dense mesh; screen strokes through a camera, radius in pixels).
  /// `replayable`: keeps a copy of the texture as it was, for replay_stroke.
  void begin_stroke(const Brush& brush, const Camera& camera, bool replayable = false);
  /// Extends the stroke to (x, y), window pixels (StrokePainter::extend_screen).
  void stroke_to(double x, double y);
  StrokeStats end_stroke();
  bool stroking() const { return stroking_; }
  /// Where the current (or last) stroke's time went.
  const StrokeTimes& stroke_times() const { return stroke_times_; }
  /// The last stroke (begun replayable) painted again by the library alone, in one call over all
  /// its points (with an undo record, as the viewer keeps), on a copy of the texture as it was
  /// before it: what the same dabs cost without the viewer. The scene's texture is not touched.
  StrokeStats replay_stroke() const;
  bool undo();
  bool redo();
  size_t undo_count() const { return history_.undo_count(); }
  size_t redo_count() const { return history_.redo_count(); }
  void save_texture(const std::filesystem::path& path);
  /// Replaces the texture (the undo history is cleared). Throws InputError naming the file.
  void load_texture(const std::filesystem::path& path);
  /// The dense mesh painted on and simplified (built on first use).
  const Mesh& dense();
  /// Words in the texture's pool (0 before any painting) and words sent to the GPU by its last
  /// upload or update (0 before the first painted draw).
  size_t texture_words() const {
    return !preparing_.valid() && texture_ ? texture_->bytes() / 4 : 0;
  }
  size_t texture_upload_words() const {
    return gpu_texture_ ? gpu_texture_->last_upload_words() : 0;
  }

  // Simplify the dense mesh into `proxies` clusters.
  const VsaResult& simplify(size_t proxies);
  const VsaResult* simplified() const { return vsa_ ? &*vsa_ : nullptr; }
  double simplify_ms() const { return vsa_ms_; }
  /// Writes the simplified mesh (OBJ, PLY, OFF or GLB by extension). Throws if none yet.
  void export_simplified(const std::filesystem::path& path) const;

 private:
  void join_preparation();
  const Mesh& dense_mesh();  // dense() without waiting (the preparation thread's own)
  void build_paint();        // the dense mesh, its surface, a texture and the painter
  void ensure_paint();
  void sync_gpu_texture();
  void ensure_hierarchy(int max_depth);
  void draw_surface(const Camera& camera, const SurfaceSettings& s, const DrawOptions& o,
                    FrameStats& fs);

  Mesh cage_;
  std::string name_;
  PatchOptions options_;

  // Cage.
  std::unique_ptr<MeshDrawer> cage_drawer_;

  // Fixed-depth surface.
  int fixed_depth_ = -1;
  PatchTable fixed_;
  std::vector<float> fixed_points_;
  std::unique_ptr<PatchDrawer> fixed_drawer_;

  // Dynamic surface: hierarchy once per max depth, a selection per view that changes depths.
  int hierarchy_depth_ = -1;
  bool measured_ = false;
  PatchHierarchy hierarchy_;
  std::vector<float> hierarchy_points_;
  VertexErrorModel model_;
  std::vector<uint8_t> vdepth_;
  PatchTable selection_;
  std::vector<float> selection_points_;  // estimated errors: the selection's own points
  std::unique_ptr<PatchDrawer> dynamic_drawer_;
  bool dynamic_from_hierarchy_ = false;  // dynamic_drawer_ reads hierarchy_points_
  float selected_tolerance_ = -1;
  Camera selected_camera_;

  // Paint.
  std::optional<Mesh> dense_;
  std::unique_ptr<PaintSurface> surface_;
  std::unique_ptr<MaterialTexture> texture_;
  PaintHistory history_;
  std::unique_ptr<MaterialPainter> painter_;
  std::unique_ptr<GpuOctreeTexture> gpu_texture_;
  std::unique_ptr<GpuOctreeTexture> gpu_rmh_;   // the material channels, once painted
  std::unique_ptr<MeshDrawer> painted_drawer_;  // scans: the mesh itself, smooth shaded
  bool stroking_ = false, gpu_dirty_ = true;
  std::future<void> preparing_;  // valid while the background preparation may be running
  StrokeTimes stroke_times_;
  std::optional<MaterialTexture> before_stroke_;  // replayable strokes: the material before
  Brush stroke_brush_;
  PaintCamera stroke_camera_;
  std::vector<double> stroke_points_;

  // Simplify.
  std::optional<VsaResult> vsa_;
  double vsa_ms_ = 0;
  std::unique_ptr<MeshDrawer> clusters_drawer_, simplified_drawer_;
};

/// A colour per cluster id (RGB, 3 per entry), neighbouring ids far apart in hue.
std::vector<float> cluster_palette(const std::vector<uint32_t>& ids);

}  // namespace limn::view
