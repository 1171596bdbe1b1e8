// Polygon meshes on the GPU: fan-triangulated, every corner its own vertex (so face colours and
// the polygon outline need no extra geometry).
#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <vector>

#include "core/timer.hpp"
#include "gl_util.hpp"
#include "limn/render/draw.hpp"
#include "material_shader.hpp"
#include "shaders.hpp"

namespace limn {

namespace {

// Per corner: position, normal, colour, and barycentrics whose component for an edge inside a
// polygon (a diagonal of its triangulation) is lifted by 1, so only polygon edges are outlined.
struct Vertex {
  float pos[3], nrm[3], col[3], bary[3];
  float uv[3];  // u, v, and 1 when the mesh has UVs
};

// Triangles of polygon `f` as triples of corner offsets 0..n-1: ear clipping in the plane of its
// Newell normal, so concave polygons (VSA's cluster polygons, holes bridged) come out right;
// a fan for what is left when no ear is found (degenerate input).
void triangulate(const Mesh& m, size_t f, std::vector<uint32_t>& out) {
  const uint32_t b = m.face_offsets[f], n = m.face_size(f);
  out.clear();
  if (n == 3) {
    out.insert(out.end(), {0, 1, 2});
    return;
  }
  float nv[3];
  face_area_vector(m, f, nv);
  int drop = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(nv[k]) > std::abs(nv[drop])) drop = k;
  const int ax = (drop + 1) % 3, ay = (drop + 2) % 3;
  const double sign = nv[drop] >= 0 ? 1.0 : -1.0;
  std::vector<double> x(n), y(n);
  for (uint32_t i = 0; i < n; ++i) {
    const float* p = &m.positions[3 * size_t(m.face_vertices[b + i])];
    x[i] = p[ax], y[i] = p[ay];
  }
  auto cross = [&](uint32_t a, uint32_t c, uint32_t d) {
    return ((x[c] - x[a]) * (y[d] - y[a]) - (y[c] - y[a]) * (x[d] - x[a])) * sign;
  };
  std::vector<uint32_t> ring(n);
  for (uint32_t i = 0; i < n; ++i) ring[i] = i;
  while (ring.size() > 3) {
    bool clipped = false;
    for (size_t i = 0; i < ring.size() && !clipped; ++i) {
      const uint32_t a = ring[(i + ring.size() - 1) % ring.size()], c = ring[i],
                     d = ring[(i + 1) % ring.size()];
      if (cross(a, c, d) <= 0) continue;  // reflex or flat
      bool empty = true;
      for (const uint32_t q : ring) {
        if (q == a || q == c || q == d) continue;
        const bool at_corner = (x[q] == x[a] && y[q] == y[a]) || (x[q] == x[c] && y[q] == y[c]) ||
                               (x[q] == x[d] && y[q] == y[d]);
        if (!at_corner && cross(a, c, q) >= 0 && cross(c, d, q) >= 0 && cross(d, a, q) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.insert(out.end(), {a, c, d});
      ring.erase(ring.begin() + long(i));
      clipped = true;
    }
    if (!clipped) break;
  }
  for (size_t i = 1; i + 1 < ring.size(); ++i)
    out.insert(out.end(), {ring[0], ring[i], ring[i + 1]});
}

}  // namespace

struct MeshDrawer::Impl {
  // One program per combination of options, compiled at its first use: bit 0 an octree texture,
  // bit 1 outlines, bit 2 a material.
  std::array<gl::Program, 8> programs;
  gl::Buffer vertices;
  gl::VertexArray vao;
  gl::DrawQueries queries;
  size_t count = 0, faces = 0;
  bool has_colors = false;
  Box bounds;
};

MeshDrawer::MeshDrawer(const Mesh& mesh, std::span<const float> face_colors, bool flat)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  validate(mesh, "render mesh");
  if (!face_colors.empty() && face_colors.size() != 3 * mesh.face_count())
    throw InputError(fmt::format("render: {} face colour values for {} faces", face_colors.size(),
                                 mesh.face_count()));
  m.faces = mesh.face_count();
  m.bounds = bounding_box(mesh);
  const bool own_normals = !flat && !mesh.normals.empty() && !mesh.normal_indices.empty();
  const std::vector<float> vn = own_normals || flat ? std::vector<float>() : vertex_normals(mesh);
  float fn[3] = {0, 0, 1};
  const bool vertex_colors = mesh.colors.size() == 4 * mesh.vertex_count();
  m.has_colors = vertex_colors || !face_colors.empty();
  const bool has_uvs = !mesh.uv_indices.empty();
  std::vector<Vertex> out;
  out.reserve(3 * (mesh.corner_count() - 2 * std::min(mesh.corner_count(), m.faces)));
  auto corner = [&](size_t f, uint32_t c, const float bary[3]) {
    Vertex v{};
    const uint32_t p = mesh.face_vertices[c];
    for (int k = 0; k < 3; ++k) {
      v.pos[k] = mesh.positions[3 * size_t(p) + size_t(k)];
      v.nrm[k] = flat          ? fn[k]
                 : own_normals ? mesh.normals[3 * size_t(mesh.normal_indices[c]) + size_t(k)]
                               : vn[3 * size_t(p) + size_t(k)];
      v.col[k] = !face_colors.empty() ? face_colors[3 * f + size_t(k)]
                 : vertex_colors      ? mesh.colors[4 * size_t(p) + size_t(k)]
                                      : 1.0f;
      v.bary[k] = bary[k];
    }
    if (has_uvs) {
      const uint32_t t = mesh.uv_indices[c];
      v.uv[0] = mesh.uvs[2 * size_t(t)], v.uv[1] = mesh.uvs[2 * size_t(t) + 1], v.uv[2] = 1.0f;
    }
    out.push_back(v);
  };
  std::vector<uint32_t> tris;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t b = mesh.face_offsets[f], n = mesh.face_size(f);
    triangulate(mesh, f, tris);
    if (flat) face_area_vector(mesh, f, fn);
    for (size_t t = 0; t < tris.size(); t += 3) {
      // The edge opposite corner j is outlined only when it is an edge of the polygon.
      float lift[3];
      for (int j = 0; j < 3; ++j) {
        const uint32_t p = tris[t + size_t(j + 1) % 3], q = tris[t + size_t(j + 2) % 3];
        lift[j] = (p + 1) % n == q || (q + 1) % n == p ? 0.0f : 1.0f;
      }
      for (int j = 0; j < 3; ++j) {
        float bary[3] = {lift[0], lift[1], lift[2]};
        bary[j] += 1;
        corner(f, b + tris[t + size_t(j)], bary);
      }
    }
  }
  m.count = out.size();
  m.vertices = gl::buffer(out.data(), out.size() * sizeof(Vertex));
  GLuint n = 0;
  glCreateVertexArrays(1, &n);
  m.vao = gl::VertexArray(n);
  glVertexArrayVertexBuffer(n, 0, m.vertices.get(), 0, sizeof(Vertex));
  for (GLuint a = 0; a < 5; ++a) {
    glEnableVertexArrayAttrib(n, a);
    glVertexArrayAttribFormat(n, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    glVertexArrayAttribBinding(n, a, 0);
  }
  gl::check("MeshDrawer");
}

MeshDrawer::~MeshDrawer() = default;

DrawStats MeshDrawer::draw(const Camera& camera, const DrawOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  const std::array<float, 16> vp = gl::view_projection(camera, m.bounds);
  gl::Program& program =
      m.programs[size_t((o.texture ? 1 : 0) | (o.outline ? 2 : 0) | (o.material ? 4 : 0))];
  if (!program.get()) {
    const std::string fs =
        std::string("#version 450 core\n") + (o.outline ? "#define OUTLINE\n" : "") +
        (o.material ? "#define MATERIAL\n" : "") + shaders::shade +
        (o.texture ? shaders::octree : shaders::no_octree) +
        (o.material ? detail::material_glsl() : std::string()) + shaders::mesh_frag;
    program =
        gl::program("mesh", {{GL_VERTEX_SHADER, shaders::mesh_vert}, {GL_FRAGMENT_SHADER, fs}});
  }
  const GLuint prog = program.get();
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glUseProgram(prog);
  glUniformMatrix4fv(glGetUniformLocation(prog, "view_proj"), 1, GL_FALSE, vp.data());
  glUniform3fv(glGetUniformLocation(prog, "eye"), 1, camera.eye);
  glUniform1f(glGetUniformLocation(prog, "uv_checker"), o.uv_checker);
  if (o.texture) o.texture->bind(prog, o.texture_nearest ? 1 : 2);
  if (o.material) {
    o.material->bind(prog, 2, "rmh_", detail::kRmhBinding);
    glUniform1f(glGetUniformLocation(prog, "height_scale"), o.height_scale);
  }
  glBindVertexArray(m.vao.get());
  // Without colours of its own the mesh takes the options' colour (a constant attribute).
  if (!m.has_colors) glDisableVertexArrayAttrib(m.vao.get(), 2), glVertexAttrib3fv(2, o.color);
  m.queries.begin();
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(m.count));
  const auto [ns, prims] = m.queries.end();
  glBindVertexArray(0);
  glUseProgram(0);
  gl::check("MeshDrawer::draw");
  DrawStats st;
  st.patches = m.faces;
  st.triangles = prims;
  st.gpu_ms = double(ns) * 1e-6;
  st.cpu_ms = ms_since(t0);
  return st;
}

}  // namespace limn
