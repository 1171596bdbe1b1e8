#include "gl_util.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace limn::gl {

void delete_buffer(GLuint n) {
  glDeleteBuffers(1, &n);
}
void delete_program(GLuint n) {
  glDeleteProgram(n);
}
void delete_vertex_array(GLuint n) {
  glDeleteVertexArrays(1, &n);
}
void delete_framebuffer(GLuint n) {
  glDeleteFramebuffers(1, &n);
}
void delete_renderbuffer(GLuint n) {
  glDeleteRenderbuffers(1, &n);
}
void delete_query(GLuint n) {
  glDeleteQueries(1, &n);
}

Program program(std::string_view name,
                std::initializer_list<std::pair<GLenum, std::string_view>> stages,
                std::initializer_list<const char*> feedback) {
  Program p(glCreateProgram());
  std::vector<GLuint> shaders;
  for (const auto& [type, source] : stages) {
    const GLuint s = glCreateShader(type);
    const char* text = source.data();
    const GLint len = GLint(source.size());
    glShaderSource(s, 1, &text, &len);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      GLint n = 0;
      glGetShaderiv(s, GL_INFO_LOG_LENGTH, &n);
      std::string log(size_t(std::max(n, 1)), '\0');
      glGetShaderInfoLog(s, n, nullptr, log.data());
      glDeleteShader(s);
      for (GLuint o : shaders) glDeleteShader(o);
      throw std::runtime_error(fmt::format("OpenGL: shader {} does not compile: {}", name, log));
    }
    glAttachShader(p.get(), s);
    shaders.push_back(s);
  }
  if (feedback.size())
    glTransformFeedbackVaryings(p.get(), GLsizei(feedback.size()), feedback.begin(),
                                GL_INTERLEAVED_ATTRIBS);
  glLinkProgram(p.get());
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(p.get(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(p.get(), GL_INFO_LOG_LENGTH, &n);
    std::string log(size_t(std::max(n, 1)), '\0');
    glGetProgramInfoLog(p.get(), n, nullptr, log.data());
    throw std::runtime_error(fmt::format("OpenGL: program {} does not link: {}", name, log));
  }
  return p;
}

Buffer buffer(const void* data, size_t bytes, bool dynamic) {
  GLuint n = 0;
  glCreateBuffers(1, &n);
  // A zero-sized store cannot be bound as a storage buffer: keep at least a word.
  glNamedBufferData(n, GLsizeiptr(std::max<size_t>(bytes, 4)), bytes ? data : nullptr,
                    dynamic ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW);
  return Buffer(n);
}

void upload(Buffer& b, size_t& capacity, const void* data, size_t bytes) {
  if (!b.get() || bytes > capacity) {
    b = buffer(data, bytes, true);
    capacity = bytes;
    return;
  }
  if (bytes) glNamedBufferSubData(b.get(), 0, GLsizeiptr(bytes), data);
}

DrawQueries::DrawQueries() {
  GLuint n = 0;
  glCreateQueries(GL_TIME_ELAPSED, 1, &n);
  time_ = Query(n);
  glCreateQueries(GL_PRIMITIVES_GENERATED, 1, &n);
  primitives_ = Query(n);
}

void DrawQueries::begin() {
  glBeginQuery(GL_TIME_ELAPSED, time_.get());
  glBeginQuery(GL_PRIMITIVES_GENERATED, primitives_.get());
}

std::pair<GLuint64, GLuint64> DrawQueries::end() {
  glEndQuery(GL_PRIMITIVES_GENERATED);
  glEndQuery(GL_TIME_ELAPSED);
  GLuint64 ns = 0, prims = 0;
  glGetQueryObjectui64v(time_.get(), GL_QUERY_RESULT, &ns);
  glGetQueryObjectui64v(primitives_.get(), GL_QUERY_RESULT, &prims);
  return {ns, prims};
}

void check(std::string_view where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR)
    throw std::runtime_error(fmt::format("OpenGL: error 0x{:x} in {}", unsigned(e), where));
}

namespace {

// Row-major view (rows s, u, -f) and projection of a camera, near and far fitted to `bounds`.
void camera_matrices(const Camera& c, const Box& bounds, double V[4][4], double P[4][4]) {
  double f[3], up[3] = {c.up[0], c.up[1], c.up[2]};
  for (int k = 0; k < 3; ++k) f[k] = double(c.target[k]) - c.eye[k];
  auto normalize = [](double* v) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
      for (int k = 0; k < 3; ++k) v[k] /= l;
  };
  auto cross = [](const double* a, const double* b, double* o) {
    o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2],
    o[2] = a[0] * b[1] - a[1] * b[0];
  };
  normalize(f);
  double s[3], u[3];
  cross(f, up, s);
  normalize(s);
  cross(s, f, u);
  // Near and far from the box's corners along the view axis.
  double zmin = 1e300, zmax = -1e300;
  for (int i = 0; i < 8; ++i) {
    const double p[3] = {(i & 1) ? bounds.max[0] : bounds.min[0],
                         (i & 2) ? bounds.max[1] : bounds.min[1],
                         (i & 4) ? bounds.max[2] : bounds.min[2]};
    double z = 0;
    for (int k = 0; k < 3; ++k) z += (p[k] - c.eye[k]) * f[k];
    zmin = std::min(zmin, z), zmax = std::max(zmax, z);
  }
  const double span = std::max(zmax - zmin, 1e-6);
  const double far_z = std::max(zmax + 0.01 * span, 1e-3);
  const double near_z = std::max(zmin - 0.01 * span, far_z * 1e-4);
  const double t = 1.0 / std::tan(double(c.fovy_deg) * 3.14159265358979323846 / 360.0);
  const double aspect = double(c.width) / double(std::max(c.height, 1));
  const double view[4][4] = {
      {s[0], s[1], s[2], 0}, {u[0], u[1], u[2], 0}, {-f[0], -f[1], -f[2], 0}, {0, 0, 0, 1}};
  const double proj[4][4] = {
      {t / aspect, 0, 0, 0},
      {0, t, 0, 0},
      {0, 0, -(far_z + near_z) / (far_z - near_z), -2.0 * far_z * near_z / (far_z - near_z)},
      {0, 0, -1, 0}};
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) V[r][col] = view[r][col], P[r][col] = proj[r][col];
  for (int r = 0; r < 3; ++r)
    V[r][3] = -(V[r][0] * c.eye[0] + V[r][1] * c.eye[1] + V[r][2] * c.eye[2]);
}

}  // namespace

void view_and_projection(const Camera& c, const Box& bounds, std::array<float, 16>& view,
                         std::array<float, 16>& projection) {
  double V[4][4], P[4][4];
  camera_matrices(c, bounds, V, P);
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) {
      view[size_t(col * 4 + r)] = float(V[r][col]);
      projection[size_t(col * 4 + r)] = float(P[r][col]);
    }
}

std::array<float, 16> view_projection(const Camera& c, const Box& bounds) {
  double V[4][4], P[4][4];
  camera_matrices(c, bounds, V, P);
  std::array<float, 16> out{};  // P V, stored column-major
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) {
      double x = 0;
      for (int k = 0; k < 4; ++k) x += P[r][k] * V[k][col];
      out[size_t(col * 4 + r)] = float(x);
    }
  return out;
}

}  // namespace limn::gl
