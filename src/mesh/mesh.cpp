#include "limn/mesh/mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace limn {

uint32_t Mesh::add_vertex(float x, float y, float z) {
  positions.insert(positions.end(), {x, y, z});
  return static_cast<uint32_t>(vertex_count() - 1);
}

uint32_t Mesh::add_face(std::span<const uint32_t> vertices) {
  face_vertices.insert(face_vertices.end(), vertices.begin(), vertices.end());
  face_offsets.push_back(static_cast<uint32_t>(face_vertices.size()));
  return static_cast<uint32_t>(face_count() - 1);
}

float Box::diagonal() const {
  if (empty()) return 0.0f;
  const double dx = max[0] - min[0], dy = max[1] - min[1], dz = max[2] - min[2];
  return static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
}

Box bounding_box(const Mesh& mesh) {
  Box b;
  const float* p = mesh.positions.data();
  for (size_t i = 0, n = mesh.vertex_count(); i < n; ++i, p += 3) {
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], p[k]);
      b.max[k] = std::max(b.max[k], p[k]);
    }
  }
  return b;
}

void face_area_vector(const Mesh& mesh, size_t f, float out[3]) {
  // Newell's method in double: exact for planar polygons, the best-fit normal otherwise.
  const auto fv = mesh.face(f);
  const float* P = mesh.positions.data();
  double n[3] = {0, 0, 0};
  const float* o = P + 3 * size_t(fv[0]);  // relative to the first vertex for precision
  for (size_t i = 0; i < fv.size(); ++i) {
    const float* a = P + 3 * size_t(fv[i]);
    const float* b = P + 3 * size_t(fv[(i + 1) % fv.size()]);
    const double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2];
    const double bx = b[0] - o[0], by = b[1] - o[1], bz = b[2] - o[2];
    n[0] += ay * bz - az * by;
    n[1] += az * bx - ax * bz;
    n[2] += ax * by - ay * bx;
  }
  for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(0.5 * n[k]);
}

float face_area(const Mesh& mesh, size_t f) {
  float a[3];
  face_area_vector(mesh, f, a);
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

void face_normal(const Mesh& mesh, size_t f, float out[3]) {
  face_area_vector(mesh, f, out);
  const float len = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
  const float inv = len > 0.0f ? 1.0f / len : 0.0f;
  for (int k = 0; k < 3; ++k) out[k] *= inv;
}

std::vector<float> vertex_normals(const Mesh& mesh) {
  std::vector<float> n(mesh.positions.size(), 0.0f);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    float a[3];
    face_area_vector(mesh, f, a);
    for (uint32_t v : mesh.face(f))
      for (int k = 0; k < 3; ++k) n[3 * size_t(v) + k] += a[k];
  }
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    float* p = &n[3 * v];
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (len > 0.0f)
      for (int k = 0; k < 3; ++k) p[k] /= len;
  }
  return n;
}

uint32_t repeated_vertex(std::span<const uint32_t> face, std::vector<uint32_t>& scratch) {
  const size_t n = face.size();
  if (n <= 16) {
    for (size_t i = 1; i < n; ++i)
      for (size_t j = 0; j < i; ++j)
        if (face[j] == face[i]) return face[i];
    return kNoRepeat;
  }
  scratch.assign(face.begin(), face.end());
  std::sort(scratch.begin(), scratch.end());
  const auto dup = std::adjacent_find(scratch.begin(), scratch.end());
  return dup == scratch.end() ? kNoRepeat : *dup;
}

namespace {

void check_indices(const std::vector<uint32_t>& idx, size_t bound, const char* kind, const Mesh& m,
                   const std::string& what) {
  if (idx.empty()) return;
  if (idx.size() != m.corner_count())
    throw InputError(fmt::format("{}: {} index count {} does not match corner count {}", what, kind,
                                 idx.size(), m.corner_count()));
  for (size_t c = 0; c < idx.size(); ++c)
    if (idx[c] >= bound) {
      const auto f = std::upper_bound(m.face_offsets.begin(), m.face_offsets.end(), c) -
                     m.face_offsets.begin() - 1;
      throw InputError(fmt::format("{}: face {} has {} index {} out of range (count {})", what, f,
                                   kind, idx[c], bound));
    }
}

void check(const Mesh& m, const std::string& what, bool simple_faces) {
  if (m.positions.size() % 3 != 0)
    throw InputError(
        fmt::format("{}: position array size {} is not a multiple of 3", what, m.positions.size()));
  const size_t nv = m.vertex_count();
  for (size_t i = 0; i < m.positions.size(); ++i)
    if (!std::isfinite(m.positions[i]))
      throw InputError(fmt::format("{}: vertex {} has a non-finite coordinate ({})", what, i / 3,
                                   m.positions[i]));
  if (m.face_offsets.empty() || m.face_offsets.front() != 0 ||
      m.face_offsets.back() != m.face_vertices.size())
    throw InputError(fmt::format("{}: face offsets do not span the corner array", what));
  std::vector<uint32_t> sorted;
  for (size_t f = 0; f < m.face_count(); ++f) {
    if (m.face_offsets[f + 1] < m.face_offsets[f])
      throw InputError(fmt::format("{}: face offsets decrease at face {}", what, f));
    const auto fv = m.face(f);
    if (fv.size() < 3)
      throw InputError(
          fmt::format("{}: face {} has {} vertices (at least 3 needed)", what, f, fv.size()));
    for (size_t i = 0; i < fv.size(); ++i)
      if (fv[i] >= nv)
        throw InputError(fmt::format("{}: face {} references vertex {} but there are {} vertices",
                                     what, f, fv[i], nv));
    if (!simple_faces) continue;
    if (const uint32_t r = repeated_vertex(fv, sorted); r != kNoRepeat)
      throw RepairableError(fmt::format("{}: face {} repeats vertex {}", what, f, r));
  }
  check_indices(m.normal_indices, m.normals.size() / 3, "normal", m, what);
  check_indices(m.uv_indices, m.uvs.size() / 2, "uv", m, what);
  for (float x : m.normals)
    if (!std::isfinite(x)) throw InputError(fmt::format("{}: a normal is not finite", what));
  for (float x : m.uvs)
    if (!std::isfinite(x))
      throw InputError(fmt::format("{}: a texture coordinate is not finite", what));
  if (!m.colors.empty() && m.colors.size() != 4 * nv)
    throw InputError(
        fmt::format("{}: {} colour values for {} vertices", what, m.colors.size(), nv));
  for (float x : m.colors)
    if (!std::isfinite(x)) throw InputError(fmt::format("{}: a vertex colour is not finite", what));
  if (m.crease_edges.size() != 2 * m.crease_sharpness.size())
    throw InputError(fmt::format("{}: crease arrays disagree", what));
  for (size_t i = 0; i < m.crease_edges.size(); ++i)
    if (m.crease_edges[i] >= nv)
      throw InputError(fmt::format("{}: crease {} references vertex {} out of range", what, i / 2,
                                   m.crease_edges[i]));
  for (size_t i = 0; i < m.crease_sharpness.size(); ++i)
    if (!(m.crease_sharpness[i] >= 0.0f) || !std::isfinite(m.crease_sharpness[i]))
      throw InputError(
          fmt::format("{}: crease {} has invalid sharpness {}", what, i, m.crease_sharpness[i]));
  if (m.corner_vertices.size() != m.corner_sharpness.size())
    throw InputError(fmt::format("{}: corner arrays disagree", what));
  for (size_t i = 0; i < m.corner_vertices.size(); ++i) {
    if (m.corner_vertices[i] >= nv)
      throw InputError(fmt::format("{}: corner tag references vertex {} out of range", what,
                                   m.corner_vertices[i]));
    if (!(m.corner_sharpness[i] >= 0.0f) || !std::isfinite(m.corner_sharpness[i]))
      throw InputError(
          fmt::format("{}: corner {} has invalid sharpness {}", what, i, m.corner_sharpness[i]));
  }
  for (uint32_t f : m.hole_faces)
    if (f >= m.face_count())
      throw InputError(fmt::format("{}: hole tag references face {} out of range", what, f));
}

}  // namespace

void validate(const Mesh& mesh, const std::string& what) {
  check(mesh, what, true);
}

void validate_soup(const Mesh& mesh, const std::string& what) {
  check(mesh, what, false);
}

}  // namespace limn
