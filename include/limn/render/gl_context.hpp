// limn render: an OpenGL 4.5 core context without a window.
//
// EGL on the surfaceless platform (Mesa): no window and no display server, so it runs in CI and
// over ssh. On machines without a GPU Mesa's llvmpipe renders in software; LIBGL_ALWAYS_SOFTWARE=1
// forces it where a GPU exists (the same pixels everywhere, for image tests). Windows (the viewer)
// make their own context with GLFW: the drawing classes only need some current 4.5 context.
#pragma once

#include <string>

namespace limn {

class GlContext {
 public:
  /// Creates the context and makes it current on the calling thread. Throws std::runtime_error
  /// naming what failed (no EGL display, no OpenGL 4.5 core context, ...).
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// The GL renderer and version, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile)
  /// Mesa 22.3.6".
  const std::string& renderer() const { return renderer_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string renderer_;
};

/// In AddressSanitizer builds, marks every library loaded so far as never to be unloaded: the GL
/// driver keeps a few allocations to the end of the process and unloads itself at teardown, so
/// LeakSanitizer would report them under no module name; pinned, they keep their names, which
/// tests/lsan.supp suppresses. GlContext calls it; windowed apps call it once their context is
/// up. A no-op in other builds. O(loaded libraries).
void keep_gl_libraries_loaded();

}  // namespace limn
