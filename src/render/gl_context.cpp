#include "limn/render/gl_context.hpp"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <fmt/format.h>

#include <stdexcept>

#if defined(__SANITIZE_ADDRESS__)
#define LIMN_PIN_GL_LIBRARIES 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LIMN_PIN_GL_LIBRARIES 1
#endif
#endif
#ifdef LIMN_PIN_GL_LIBRARIES
#include <dlfcn.h>
#include <link.h>
#endif

namespace limn {

namespace {

std::runtime_error egl_error(const char* what) {
  return std::runtime_error(
      fmt::format("OpenGL: {} failed (EGL error 0x{:x})", what, eglGetError()));
}

// The surfaceless platform (Mesa); else the first EGL device (NVIDIA's driver has no
// surfaceless platform); else the default display.
EGLDisplay open_display() {
  if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) return d;
  }
  if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[4];
    EGLint n = 0;
    if (eglQueryDevicesEXT(4, devices, &n) && n > 0) {
      EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[0], nullptr);
      if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) return d;
    }
  }
  EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) return d;
  throw egl_error("opening an EGL display (is Mesa's libegl-mesa0 installed?)");
}

}  // namespace

void keep_gl_libraries_loaded() {
#ifdef LIMN_PIN_GL_LIBRARIES
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) -> int {
        if (info->dlpi_name && info->dlpi_name[0])
          dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        return 0;
      },
      nullptr);
#endif
}

GlContext::GlContext() {
  EGLDisplay d = open_display();
  display_ = d;
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(d);
    throw egl_error("eglBindAPI(OpenGL)");
  }
  const EGLint attrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                          4,
                          EGL_CONTEXT_MINOR_VERSION,
                          5,
                          EGL_CONTEXT_OPENGL_PROFILE_MASK,
                          EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                          EGL_NONE};
  EGLContext c = eglCreateContext(d, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attrs);
  if (c == EGL_NO_CONTEXT) {
    eglTerminate(d);
    throw egl_error("creating an OpenGL 4.5 core context");
  }
  context_ = c;
  if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c)) {
    eglDestroyContext(d, c);
    eglTerminate(d);
    throw egl_error("eglMakeCurrent");
  }
  renderer_ = fmt::format("{}, {}", reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                          reinterpret_cast<const char*>(glGetString(GL_VERSION)));
  keep_gl_libraries_loaded();
}

GlContext::~GlContext() {
  EGLDisplay d = display_;
  eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(d, static_cast<EGLContext>(context_));
  keep_gl_libraries_loaded();
  eglTerminate(d);
}

}  // namespace limn
