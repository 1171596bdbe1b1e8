// limn paint: brushes, strokes, fill and the eyedropper.
//
// A dab paints the leaves of the surface within its radius that are visible from its eye and face
// it: every leaf cell is split by side (its tag), each side gets the point of its triangles
// nearest the cell centre, and that point is weighted by the radial falloff, by how squarely it
// faces the eye (normal-angle falloff) and by an Embree occlusion ray toward the eye. The octree is
// refined on the way, only in cells the surface passes through, down to the brush's depth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "limn/paint/material.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "limn/paint/undo.hpp"

namespace limn {

enum class BlendMode : uint8_t {
  mix,       ///< paint over (premultiplied "over")
  add,       ///< rgb += colour * strength (clamped); coverage as mix
  multiply,  ///< rgb *= mix(1, colour, strength); alpha kept
  erase      ///< alpha *= 1 - strength; rgb kept
};

/// How a brush paints one material channel (roughness, metallic or height, each in [0, 1]).
/// mix: toward `value`; add: + value (clamped); multiply: times mix(1, value, strength); erase:
/// back toward the channel's default. Strength: the brush's falloff times `opacity`.
struct ChannelPaint {
  bool on = false;  ///< painted by this brush
  float value = 0.5f;
  BlendMode blend = BlendMode::mix;
  float opacity = 1.0f;  ///< [0,1]: the most one stroke changes this channel
};

struct Brush {
  float radius = 0.02f;           ///< model units, or pixels for screen dabs (> 0)
  float color[4] = {1, 0, 0, 1};  ///< straight RGBA in [0,1]
  float opacity = 1.0f;           ///< [0,1]: the most one stroke changes a texel
  float hardness = 0.5f;          ///< [0,1]: full strength within hardness * radius, smooth to 0
  BlendMode blend = BlendMode::mix;
  float spacing = 0.25f;            ///< dab distance along a stroke, in radii, (0, 10]
  int depth = 10;                   ///< the leaf level the brush refines to, [1, kMaxDepth]
  float falloff_angle_deg = 60.0f;  ///< full strength while the surface faces the eye within this
                                    ///< angle, fading to 0 at 90 degrees; [0, 90]
  /// Whether the base colour is painted (color, opacity, blend above); off for a brush that
  /// paints only material channels.
  bool paint_color = true;
  /// The material channels, indexed by MaterialChannel (MaterialPainter; a StrokePainter with
  /// PaintTarget::rmh).
  ChannelPaint material[kMaterialChannels];
  /// Whether any material channel is on. O(1).
  bool paints_material() const { return material[0].on || material[1].on || material[2].on; }
};

/// Which texture a StrokePainter writes: a colour texture (the brush's colour), or an RMH
/// texture (the brush's material channels; see material.hpp).
enum class PaintTarget : uint8_t { color, rmh };

struct StrokeStats {
  size_t dabs = 0;             ///< dabs painted
  size_t dabs_missed = 0;      ///< dabs with no surface under them
  size_t samples_changed = 0;  ///< sample writes that changed a colour
  size_t leaves_created = 0, bricks_created = 0, nodes_created = 0;
  size_t rays = 0;  ///< occlusion rays cast
  /// Task cells the dabs visited (cells 2^4 leaves wide, each painted by one thread), and of
  /// them those visited on TBB's threads beside their siblings.
  size_t tasks = 0, tasks_threaded = 0;
  double ms = 0;  ///< wall time of the stroke
};

/// Throws InputError naming `what` when a field of the brush is out of range or not finite.
void check_brush(const Brush& b, const char* what);

/// Paints strokes: begin, dabs (or whole polylines), end. Within a stroke, a texel takes the
/// strongest weight any dab gave it (opacity is a ceiling, not a build-up), so the result does
/// not depend on the spacing. A dab's cells are painted on TBB's threads (the texture comes out
/// the same bit for bit on any number of them); one painter is not to be called from two threads.
class StrokePainter {
 public:
  /// `history` (may be null) records each stroke for undo. `target`: what the brush paints into
  /// `texture` (its colour, whatever `paint_color` says, or its material channels).
  StrokePainter(OctreeTexture& texture, const PaintSurface& surface,
                PaintHistory* history = nullptr, PaintTarget target = PaintTarget::color);
  ~StrokePainter();
  StrokePainter(const StrokePainter&) = delete;
  StrokePainter& operator=(const StrokePainter&) = delete;

  /// Starts a stroke. `camera` (may be null; copied): screen dabs go through it, and every dab's
  /// eye is the camera's. Without one, a world dab's eye looks down the surface normal at the dab
  /// centre and occlusion is tested over 2 radii. Throws InputError for a bad brush or camera.
  void begin(const Brush& brush, const PaintCamera* camera = nullptr);
  /// A dab centred on the surface point nearest p, if one lies within the brush radius of p.
  /// Returns false (nothing painted) otherwise. Precondition: inside a stroke.
  bool dab_world(const float p[3]);
  /// A dab where the camera ray through pixel (px, py) first meets the surface, radius in pixels;
  /// false when it meets nothing or a back face. Precondition: a stroke begun with a camera.
  bool dab_screen(double px, double py);
  /// Dabs every `spacing * radius` of arc length along a polyline of world points (xyz, the first
  /// dab at the first point). Throws InputError past 10 million dabs.
  void stroke_world(std::span<const float> xyz);
  /// The same along pixel points (xy), spacing in pixels.
  void stroke_screen(std::span<const double> xy);
  /// Extends the stroke's pixel polyline to (px, py), as a mouse drag delivers it: the first call
  /// dabs at its point, later ones every `spacing * radius` of arc length along the whole
  /// polyline, so the points fed one at a time get the same dabs as stroke_screen over all of
  /// them (no dab repeated at a segment's start). Throws InputError for a non-finite point.
  void extend_screen(double px, double py);
  /// Ends the stroke (and its undo record). Returns its counts.
  StrokeStats end();
  /// Whether the dabs of a stroke reuse what earlier dabs of it found that depends only on the
  /// mesh (each brick's leaf triangle lists, each texel's nearest surface point) instead of
  /// finding it again. On by default; the texture comes out the same bit for bit either way (off:
  /// slower, for tests and measurements). Takes effect at the next begin().
  void set_reuse(bool on) { reuse_ = on; }

 private:
  struct State;
  OctreeTexture& t_;
  const PaintSurface& s_;
  PaintHistory* history_;
  PaintTarget target_;
  State* st_ = nullptr;
  bool reuse_ = true;
};

/// Paints a material: the brush's colour into its colour texture (when `paint_color`) and its
/// material channels into its RMH texture (made, with `defaults`, the first time a brush paints
/// one), each dab the same on both, so a stroke's channels line up texel for texel. The same
/// calls as StrokePainter; a stroke is one undo record for both textures. A brush with neither
/// colour nor a channel on paints nothing (its dabs return false).
class MaterialPainter {
 public:
  MaterialPainter(MaterialTexture& material, const PaintSurface& surface,
                  PaintHistory* history = nullptr, MaterialDefaults defaults = {});
  ~MaterialPainter();
  MaterialPainter(const MaterialPainter&) = delete;
  MaterialPainter& operator=(const MaterialPainter&) = delete;

  void begin(const Brush& brush, const PaintCamera* camera = nullptr);
  bool dab_world(const float p[3]);
  bool dab_screen(double px, double py);
  void stroke_world(std::span<const float> xyz);
  void stroke_screen(std::span<const double> xy);
  void extend_screen(double px, double py);
  /// Ends the stroke: the counts of both textures added up (dabs counted once).
  StrokeStats end();
  void set_reuse(bool on) { reuse_ = on; }

 private:
  template <class F>
  bool each(F&& f);
  MaterialTexture& m_;
  const PaintSurface& s_;
  PaintHistory* history_;
  MaterialDefaults defaults_;
  StrokePainter* color_ = nullptr;
  StrokePainter* rmh_ = nullptr;
  bool stroking_ = false;
  bool reuse_ = true;
};

/// Refines every surface cell to level `depth` (no colour change): the full ("regular") octree of
/// the surface in the adaptive layout. O(surface cells at depth); on TBB's threads, the same
/// texture on any number of them.
void refine_surface(OctreeTexture& t, const PaintSurface& s, int depth);

/// Blends `color` into every sample (fill): after refining the whole surface to `depth` when
/// depth > 0 (on TBB's threads, as refine_surface), else at the resolution each region already
/// has. Returns the samples changed.
size_t fill(OctreeTexture& t, const PaintSurface& s, const float color[4], BlendMode mode,
            float opacity, int depth = 0);

/// Eyedropper: the colour (straight RGBA, [0,1]) at the surface point nearest p, within
/// `max_dist`, seen from its own side. False when no surface is that near or nothing is painted
/// there (rgba = the background).
bool pick_world(const OctreeTexture& t, const PaintSurface& s, const float p[3], float max_dist,
                float rgba[4]);
/// Eyedropper through a camera pixel (the first surface the ray meets).
bool pick_screen(const OctreeTexture& t, const PaintSurface& s, const PaintCamera& camera,
                 double px, double py, float rgba[4]);

/// Fill with a whole brush (colour, opacity, blend and material channels; `depth` as above):
/// into the colour texture when the brush paints colour, into the RMH texture (made with
/// `defaults` when absent) when it paints a channel. Returns the samples changed.
size_t fill(MaterialTexture& m, const PaintSurface& s, const Brush& brush, int depth = 0,
            MaterialDefaults defaults = {});

/// What the eyedropper finds on a material.
struct MaterialPick {
  bool found = false;             ///< a painted colour sample was there
  float rgba[4] = {0, 0, 0, 0};   ///< base colour (the background where none)
  float channels[3] = {0, 0, 0};  ///< roughness, metallic, height (the defaults where none)
};
MaterialPick pick_world(const MaterialTexture& m, const PaintSurface& s, const float p[3],
                        float max_dist);
MaterialPick pick_screen(const MaterialTexture& m, const PaintSurface& s, const PaintCamera& camera,
                         double px, double py);

/// Recomputes every mip average from the leaves (after direct sample edits). O(pool).
void recompute_averages(OctreeTexture& t);

}  // namespace limn
