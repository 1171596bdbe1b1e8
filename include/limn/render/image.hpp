// limn render: offscreen images and PNG files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

namespace limn {

/// An offscreen colour (RGBA8) + depth target, multisampled when samples > 1. Needs a current
/// OpenGL 4.5 context (GlContext or a window's) for its whole life.
class RenderTarget {
 public:
  /// 1 <= width, height <= 16384; samples 1-16 (clamped to what the driver offers). Throws
  /// std::runtime_error if the driver refuses the framebuffer.
  RenderTarget(int width, int height, int samples = 1);
  ~RenderTarget();
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  /// Binds it for drawing, sets the viewport, clears colour (RGBA 0-1) and depth.
  void begin(const float clear_rgba[4]);
  /// The image as RGBA8, rows top to bottom (multisampling resolved). O(pixels).
  std::vector<uint8_t> read_rgba();
  /// Waits until every command issued so far has finished (glFinish): what frame timings stop at,
  /// since a software driver's timer queries see only the submission.
  void finish();
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int width_, height_;
};

/// Encodes RGBA8 pixels (rows top to bottom) as a PNG and writes it atomically (temporary file
/// beside `path`, then renamed). Throws std::runtime_error naming the path when the file
/// cannot be written (the old file, if any, is then untouched).
void write_png(const std::filesystem::path& path, int width, int height,
               std::span<const uint8_t> rgba);

/// Decodes a PNG into RGBA8 (rows top to bottom). Throws InputError naming the file for a file
/// that is not a PNG.
std::vector<uint8_t> read_png(const std::filesystem::path& path, int& width, int& height);

}  // namespace limn
