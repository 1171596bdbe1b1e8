// Polygon meshes on the GPU: fan-triangulated, every corner its own vertex (so face colours and
// the polygon outline need no extra geometry).
#include <fmt/format.h>

#include <chrono>
#include <vector>

#include "gl_util.hpp"
#include "limn/render/draw.hpp"

namespace limn {

namespace {

constexpr const char* kVertex = R"(#version 450 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 nrm;
layout(location = 2) in vec3 col;
layout(location = 3) in vec3 bary;
uniform mat4 view_proj;
out vec3 t_pos;
out vec3 t_nrm;
out vec3 t_col;
out vec3 t_bary;
void main() {
  t_pos = pos;
  t_nrm = nrm;
  t_col = col;
  t_bary = bary;
  gl_Position = view_proj * vec4(pos, 1.0);
}
)";

constexpr const char* kFragment = R"(
in vec3 t_pos;
in vec3 t_nrm;
in vec3 t_col;
in vec3 t_bary;
uniform vec3 eye;
uniform bool outline;
out vec4 frag;
void main() {
  float edge = 1e9;
  if (outline) {
    vec3 d = t_bary / max(fwidth(t_bary), vec3(1e-9));
    edge = min(d.x, min(d.y, d.z));
  }
  frag = vec4(shade(t_col, t_pos, t_nrm, eye, edge, outline), 1.0);
}
)";

// Per corner: position, normal, colour, and barycentrics whose component for an edge inside a
// polygon (a fan diagonal) is lifted by 1, so only polygon edges are outlined.
struct Vertex {
  float pos[3], nrm[3], col[3], bary[3];
};

}  // namespace

struct MeshDrawer::Impl {
  gl::Program program;
  gl::Buffer vertices;
  gl::VertexArray vao;
  gl::Query time_query, primitives_query;
  size_t count = 0, faces = 0;
  bool has_colors = false;
  Box bounds;
};

MeshDrawer::MeshDrawer(const Mesh& mesh, std::span<const float> face_colors)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  validate(mesh, "render mesh");
  if (!face_colors.empty() && face_colors.size() != 3 * mesh.face_count())
    throw InputError(fmt::format("render: {} face colour values for {} faces", face_colors.size(),
                                 mesh.face_count()));
  m.faces = mesh.face_count();
  m.bounds = bounding_box(mesh);
  const bool own_normals = !mesh.normals.empty() && !mesh.normal_indices.empty();
  const std::vector<float> vn = own_normals ? std::vector<float>() : vertex_normals(mesh);
  const bool vertex_colors = mesh.colors.size() == 4 * mesh.vertex_count();
  m.has_colors = vertex_colors || !face_colors.empty();
  std::vector<Vertex> out;
  out.reserve(3 * (mesh.corner_count() - 2 * std::min(mesh.corner_count(), m.faces)));
  auto corner = [&](size_t f, uint32_t c, const float bary[3]) {
    Vertex v{};
    const uint32_t p = mesh.face_vertices[c];
    for (int k = 0; k < 3; ++k) {
      v.pos[k] = mesh.positions[3 * size_t(p) + size_t(k)];
      v.nrm[k] = own_normals ? mesh.normals[3 * size_t(mesh.normal_indices[c]) + size_t(k)]
                             : vn[3 * size_t(p) + size_t(k)];
      v.col[k] = !face_colors.empty() ? face_colors[3 * f + size_t(k)]
                 : vertex_colors      ? mesh.colors[4 * size_t(p) + size_t(k)]
                                      : 1.0f;
      v.bary[k] = bary[k];
    }
    out.push_back(v);
  };
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t b = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t i = 1; i + 1 < n; ++i) {
      // Triangle (0, i, i + 1): the edge opposite corner 0 is a polygon edge; the one opposite
      // corner 1 (from 0 to i + 1) is one only for the last triangle, the one opposite corner
      // 2 (from 0 to i) only for the first.
      const float lift0 = 0, lift1 = i + 2 == n ? 0.0f : 1.0f, lift2 = i == 1 ? 0.0f : 1.0f;
      const float b0[3] = {1 + lift0, lift1, lift2}, b1[3] = {lift0, 1 + lift1, lift2},
                  b2[3] = {lift0, lift1, 1 + lift2};
      corner(f, b, b0);
      corner(f, b + i, b1);
      corner(f, b + i + 1, b2);
    }
  }
  m.count = out.size();
  m.vertices = gl::buffer(out.data(), out.size() * sizeof(Vertex));
  GLuint n = 0;
  glCreateVertexArrays(1, &n);
  m.vao = gl::VertexArray(n);
  glVertexArrayVertexBuffer(n, 0, m.vertices.get(), 0, sizeof(Vertex));
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexArrayAttrib(n, a);
    glVertexArrayAttribFormat(n, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    glVertexArrayAttribBinding(n, a, 0);
  }
  const std::string fs = std::string("#version 450 core\n") + gl::kShadeGlsl + kFragment;
  m.program = gl::program("mesh", {{GL_VERTEX_SHADER, kVertex}, {GL_FRAGMENT_SHADER, fs}});
  glCreateQueries(GL_TIME_ELAPSED, 1, &n);
  m.time_query = gl::Query(n);
  glCreateQueries(GL_PRIMITIVES_GENERATED, 1, &n);
  m.primitives_query = gl::Query(n);
  gl::check("MeshDrawer");
}

MeshDrawer::~MeshDrawer() = default;

DrawStats MeshDrawer::draw(const Camera& camera, const DrawOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  const std::array<float, 16> vp = gl::view_projection(camera, m.bounds);
  const GLuint prog = m.program.get();
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glUseProgram(prog);
  glUniformMatrix4fv(glGetUniformLocation(prog, "view_proj"), 1, GL_FALSE, vp.data());
  glUniform3fv(glGetUniformLocation(prog, "eye"), 1, camera.eye);
  glUniform1i(glGetUniformLocation(prog, "outline"), o.outline);
  glBindVertexArray(m.vao.get());
  // Without colours of its own the mesh takes the options' colour (a constant attribute).
  if (!m.has_colors) glDisableVertexArrayAttrib(m.vao.get(), 2), glVertexAttrib3fv(2, o.color);
  glBeginQuery(GL_TIME_ELAPSED, m.time_query.get());
  glBeginQuery(GL_PRIMITIVES_GENERATED, m.primitives_query.get());
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(m.count));
  glEndQuery(GL_PRIMITIVES_GENERATED);
  glEndQuery(GL_TIME_ELAPSED);
  GLuint64 ns = 0, prims = 0;
  glGetQueryObjectui64v(m.time_query.get(), GL_QUERY_RESULT, &ns);
  glGetQueryObjectui64v(m.primitives_query.get(), GL_QUERY_RESULT, &prims);
  glBindVertexArray(0);
  glUseProgram(0);
  gl::check("MeshDrawer::draw");
  DrawStats st;
  st.patches = m.faces;
  st.triangles = prims;
  st.gpu_ms = double(ns) * 1e-6;
  st.cpu_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

}  // namespace limn
