// Small OpenGL helpers the render layer shares: owned GL names, shader programs with their
// compile logs, buffers, a view-projection from limn's Camera. Internal: no GL in public headers.
#pragma once

#include <epoxy/gl.h>

#include <array>
#include <initializer_list>
#include <string_view>
#include <utility>

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/depth.hpp"

namespace limn::gl {

/// An owned GL object name, deleted with `del` (glDeleteBuffers, glDeleteProgram, ...).
template <void (*del)(GLuint)>
class Name {
 public:
  Name() = default;
  explicit Name(GLuint n) : n_(n) {}
  ~Name() { reset(); }
  Name(Name&& o) noexcept : n_(std::exchange(o.n_, 0)) {}
  Name& operator=(Name&& o) noexcept {
    if (this != &o) reset(), n_ = std::exchange(o.n_, 0);
    return *this;
  }
  GLuint get() const { return n_; }
  void reset() {
    if (n_) del(n_), n_ = 0;
  }

 private:
  GLuint n_ = 0;
};

void delete_buffer(GLuint n);
void delete_program(GLuint n);
void delete_vertex_array(GLuint n);
void delete_framebuffer(GLuint n);
void delete_renderbuffer(GLuint n);
void delete_query(GLuint n);
using Buffer = Name<delete_buffer>;
using Program = Name<delete_program>;
using VertexArray = Name<delete_vertex_array>;
using Framebuffer = Name<delete_framebuffer>;
using Renderbuffer = Name<delete_renderbuffer>;
using Query = Name<delete_query>;

/// Compiles and links the stages (type, GLSL source); throws std::runtime_error with `name` and
/// the driver's log. `feedback` (may be empty): outputs captured by transform feedback,
/// interleaved in that order.
Program program(std::string_view name,
                std::initializer_list<std::pair<GLenum, std::string_view>> stages,
                std::initializer_list<const char*> feedback = {});

/// A buffer holding `bytes` (GL_STATIC_DRAW unless `dynamic`).
Buffer buffer(const void* data, size_t bytes, bool dynamic = false);

/// Replaces a buffer's contents, growing it when needed.
void upload(Buffer& b, size_t& capacity, const void* data, size_t bytes);

/// GPU time and primitives of the draws issued between `begin` and `end` (a timer query and a
/// primitives-generated query); `end` waits for both results.
class DrawQueries {
 public:
  DrawQueries();
  void begin();
  /// GPU nanoseconds and primitives generated since `begin`.
  std::pair<GLuint64, GLuint64> end();

 private:
  Query time_, primitives_;
};

/// Throws std::runtime_error naming `where` when GL reports an error.
void check(std::string_view where);

/// Column-major 4x4 view-projection of `camera` for points within `bounds` (near and far planes
/// fitted to the box, so depth precision goes where the model is).
std::array<float, 16> view_projection(const Camera& camera, const Box& bounds);
/// The same camera's view and projection apart (column-major; view_projection is their product):
/// for shaders that measure in view space, such as OpenSubdiv's screen-space tessellation.
void view_and_projection(const Camera& camera, const Box& bounds, std::array<float, 16>& view,
                         std::array<float, 16>& projection);

}  // namespace limn::gl
