// Binary glTF output read back with tinygltf's own loader (an independent reader).
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"

namespace limn {
namespace {

template <class T>
std::vector<T> accessor_data(const tinygltf::Model& m, int index, size_t width) {
  const tinygltf::Accessor& a = m.accessors[index];
  const tinygltf::BufferView& v = m.bufferViews[a.bufferView];
  std::vector<T> out(a.count * width);
  std::memcpy(out.data(), m.buffers[v.buffer].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(T));
  return out;
}

tinygltf::Model load(const std::string& glb) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                              reinterpret_cast<const unsigned char*>(glb.data()),
                                              static_cast<unsigned int>(glb.size()));
  EXPECT_TRUE(ok) << err;
  return model;
}

TEST(Glb, ColouredPolygonsBecomeTrianglesWithColours) {
  Mesh m = make_cube();
  m.colors.resize(4 * m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (int k = 0; k < 4; ++k) m.colors[4 * v + k] = float((v * 4 + size_t(k)) % 7) / 7.0f;
  std::string glb;
  write_glb(m, glb);
  const tinygltf::Model model = load(glb);
  ASSERT_EQ(model.meshes.size(), 1u);
  const auto& prim = model.meshes[0].primitives[0];
  const auto idx = accessor_data<uint32_t>(model, prim.indices, 1);
  ASSERT_EQ(idx.size(), 36u);  // 6 quads -> 12 triangles
  const auto pos = accessor_data<float>(model, prim.attributes.at("POSITION"), 3);
  const auto col = accessor_data<float>(model, prim.attributes.at("COLOR_0"), 4);
  const auto nrm = accessor_data<float>(model, prim.attributes.at("NORMAL"), 3);
  ASSERT_EQ(pos.size(), 3 * m.vertex_count());
  // Every output vertex carries its source vertex's colour and a unit normal.
  for (size_t o = 0; o < pos.size() / 3; ++o) {
    size_t src = m.vertex_count();
    for (size_t v = 0; v < m.vertex_count(); ++v)
      if (std::equal(&pos[3 * o], &pos[3 * o] + 3, &m.positions[3 * v])) src = v;
    ASSERT_LT(src, m.vertex_count());
    for (int k = 0; k < 4; ++k) EXPECT_EQ(col[4 * o + size_t(k)], m.colors[4 * src + size_t(k)]);
    const float len = std::sqrt(nrm[3 * o] * nrm[3 * o] + nrm[3 * o + 1] * nrm[3 * o + 1] +
                                nrm[3 * o + 2] * nrm[3 * o + 2]);
    EXPECT_NEAR(len, 1.0f, 1e-5f);
  }
  // Triangles keep the faces' orientation: each triangle's normal points away from the centre.
  for (size_t t = 0; t < idx.size(); t += 3) {
    const float* a = &pos[3 * idx[t]];
    const float* b = &pos[3 * idx[t + 1]];
    const float* c = &pos[3 * idx[t + 2]];
    const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const float n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                        u[0] * w[1] - u[1] * w[0]};
    const float centroid[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                               (a[2] + b[2] + c[2]) / 3};
    EXPECT_GT(n[0] * centroid[0] + n[1] * centroid[1] + n[2] * centroid[2], 0.0f);
  }
}

TEST(Glb, PerCornerNormalsSplitVertices) {
  Mesh m = make_cube();
  // Flat shading: one normal per face, so each cube corner needs 3 output vertices.
  m.normals.clear();
  m.normal_indices.clear();
  for (size_t f = 0; f < m.face_count(); ++f) {
    float n[3];
    face_normal(m, f, n);
    m.normals.insert(m.normals.end(), n, n + 3);
    for (size_t c = 0; c < m.face_size(f); ++c) m.normal_indices.push_back(uint32_t(f));
  }
  std::string glb;
  write_glb(m, glb);
  const tinygltf::Model model = load(glb);
  const auto& prim = model.meshes[0].primitives[0];
  EXPECT_EQ(model.accessors[prim.attributes.at("POSITION")].count, 24u);
}

TEST(Glb, EmptyMeshIsAnError) {
  std::string glb;
  EXPECT_THROW(write_glb(Mesh{}, glb), InputError);
}

}  // namespace
}  // namespace limn
