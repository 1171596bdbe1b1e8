// Binary glTF output read back with tinygltf's own loader (an independent reader), and glTF
// input (.gltf with embedded or external buffers, .glb): files written by another program
// (tests/data/gltf/make_files.py), limn's own GLB read back, welding, and bad files.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/file.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/mesh/weld.hpp"

#ifndef LIMN_TEST_DATA
#define LIMN_TEST_DATA "tests/data"
#endif

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

// ---- reading glTF ----

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kGltf = fs::path(LIMN_TEST_DATA) / "gltf";

// Geometric normal of triangle f (unnormalised).
std::array<float, 3> triangle_normal(const Mesh& m, size_t f) {
  const auto fv = m.face(f);
  const float* a = &m.positions[3 * size_t(fv[0])];
  const float* b = &m.positions[3 * size_t(fv[1])];
  const float* c = &m.positions[3 * size_t(fv[2])];
  const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const float w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
}

void expect_position(const Mesh& m, size_t v, float x, float y, float z) {
  EXPECT_NEAR(m.positions[3 * v], x, 1e-5f) << "vertex " << v;
  EXPECT_NEAR(m.positions[3 * v + 1], y, 1e-5f) << "vertex " << v;
  EXPECT_NEAR(m.positions[3 * v + 2], z, 1e-5f) << "vertex " << v;
}

TEST(GltfRead, QuadWithInterleavedNormalsAndUvs) {
  const Mesh m = read_mesh(kGltf / "quad.gltf");
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.face_count(), 2u);
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(m.normal_indices, m.face_vertices);
  EXPECT_EQ(m.uv_indices, m.face_vertices);
  for (size_t v = 0; v < 4; ++v) {
    // The file stores v downwards; limn's uv equals the quad's (x, y).
    EXPECT_EQ(m.uvs[2 * v], m.positions[3 * v]);
    EXPECT_EQ(m.uvs[2 * v + 1], m.positions[3 * v + 1]);
    EXPECT_EQ(m.normals[3 * v + 2], 1.0f);
  }
  EXPECT_TRUE(m.colors.empty());
}

TEST(GltfRead, NodeTransformsParentFirstAndMirroringFlipsWinding) {
  const Mesh m = read_mesh(kGltf / "scene_trs.gltf");
  // Two instances in the scene (the node outside it is not read).
  ASSERT_EQ(m.vertex_count(), 6u);
  ASSERT_EQ(m.face_count(), 2u);
  // Child: T(10,0,0) * T(0,2,0) * Rz(90) * S(2) applied to (0,0,0), (1,0,0), (0,1,0).
  expect_position(m, 0, 10, 2, 0);
  expect_position(m, 1, 10, 4, 0);
  expect_position(m, 2, 8, 2, 0);
  // Mirror in x, then z += 5.
  expect_position(m, 3, 0, 0, 5);
  expect_position(m, 4, -1, 0, 5);
  expect_position(m, 5, 0, 1, 5);
  // Normals follow by the inverse transpose, stay unit, and the winding agrees with them.
  for (size_t f = 0; f < 2; ++f) {
    const auto n = triangle_normal(m, f);
    const uint32_t v = m.face(f)[0];
    EXPECT_NEAR(m.normals[3 * v + 2], 1.0f, 1e-6f);
    EXPECT_GT(n[0] * m.normals[3 * v] + n[1] * m.normals[3 * v + 1] + n[2] * m.normals[3 * v + 2],
              0.0f)
        << "face " << f;
  }
}

TEST(GltfRead, StripAndFanBecomeConsistentTriangles) {
  size_t dropped = 9;
  const Mesh m = read_gltf(read_file(kGltf / "strip_fan.gltf"), "strip_fan.gltf", kGltf, &dropped);
  EXPECT_EQ(dropped, 0u);
  EXPECT_EQ(m.vertex_count(), 9u);
  ASSERT_EQ(m.face_count(), 5u);  // 5-vertex strip: 3 triangles; 4-vertex fan: 2
  for (size_t f = 0; f < m.face_count(); ++f) EXPECT_GT(triangle_normal(m, f)[2], 0.0f) << f;
  // The fan's triangles all share its first vertex (5, 0, 0), vertex 5 here.
  for (size_t f = 3; f < 5; ++f) EXPECT_THAT(m.face(f), ::testing::Contains(5u));
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.inconsistent_edges, 0u);
  EXPECT_EQ(s.components, 2u);
}

TEST(GltfRead, NormalizedIntegerUvsAndColours) {
  const Mesh m = read_mesh(kGltf / "colors.gltf");
  ASSERT_EQ(m.vertex_count(), 6u);
  const std::vector<float> uvs = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  EXPECT_EQ(m.uvs, uvs);
  ASSERT_EQ(m.colors.size(), 24u);
  const float a = 128.0f / 255.0f;
  const std::vector<float> first = {1, 0, 0, 1, 0, 1, 0, a, 0, 0, 1, 0};
  EXPECT_EQ(std::vector<float>(m.colors.begin(), m.colors.begin() + 12), first);
  for (size_t v = 3; v < 6; ++v)
    EXPECT_EQ(std::vector<float>(&m.colors[4 * v], &m.colors[4 * v] + 4),
              (std::vector<float>{0.25f, 0.5f, 0.75f, 1}));
}

TEST(GltfRead, ExternalBufferResolvesAgainstTheFilesFolder) {
  const Mesh ext = read_mesh(kGltf / "external.gltf");
  const Mesh quad = read_mesh(kGltf / "quad.gltf");
  EXPECT_EQ(ext.positions, quad.positions);
  EXPECT_EQ(ext.face_vertices, quad.face_vertices);
  EXPECT_EQ(ext.uvs, quad.uvs);
  // From memory, buffers resolve against ReadOptions::base_dir (else the current directory).
  const std::string text = read_file(kGltf / "external.gltf");
  ReadOptions opt;
  opt.base_dir = kGltf;
  EXPECT_EQ(read_mesh_memory(text, opt, "external.gltf").positions, quad.positions);
  opt.base_dir = kGltf / "no-such-folder";
  try {
    read_mesh_memory(text, opt, "external.gltf");
    FAIL() << "read a buffer that is not there";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("external.gltf: "));
    EXPECT_THAT(e.what(), HasSubstr("external.bin"));
  }
}

TEST(GltfRead, FormatsFromNamesAndContent) {
  EXPECT_EQ(format_from_name("gltf"), MeshFormat::gltf);
  EXPECT_EQ(format_from_name(".GLB"), MeshFormat::glb);
  EXPECT_EQ(format_from_path("a/b.gltf"), MeshFormat::gltf);
  const std::string text = read_file(kGltf / "quad.gltf");
  EXPECT_EQ(read_mesh_memory(text, MeshFormat::automatic, "q").face_count(), 2u);
  std::string glb;
  write_glb(make_cube(), glb);
  EXPECT_EQ(read_mesh_memory(glb, MeshFormat::automatic, "c").face_count(), 12u);
  // .gltf is read, not written.
  EXPECT_THROW(write_mesh_memory(make_cube(), MeshFormat::gltf), InputError);
}

TEST(GltfRead, ImagesNeverFailTheLoadAndNoSceneReadsEveryMesh) {
  auto j = nlohmann::json::parse(read_file(kGltf / "quad.gltf"));
  j["images"] = {{{"uri", "missing.png"}}, {{"uri", "data:image/png;base64,iVBORw0KGgo="}}};
  j["textures"] = {{{"source", 0}}, {{"source", 1}}};
  EXPECT_EQ(read_gltf(j.dump(), "images.gltf", kGltf).face_count(), 2u);
  j.erase("scene");
  j.erase("scenes");
  j.erase("nodes");
  EXPECT_EQ(read_gltf(j.dump(), "noscene.gltf", kGltf).face_count(), 2u);
}

TEST(GltfRead, PrimitivesWithoutAnAttributeDropItForTheWholeMesh) {
  auto j = nlohmann::json::parse(read_file(kGltf / "quad.gltf"));
  auto prim = j["meshes"][0]["primitives"][0];
  prim["attributes"].erase("TEXCOORD_0");
  j["meshes"][0]["primitives"].push_back(prim);
  const Mesh m = read_gltf(j.dump(), "mixed.gltf", kGltf);
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.face_count(), 4u);
  EXPECT_TRUE(m.uvs.empty());
  EXPECT_EQ(m.normal_indices, m.face_vertices);
}

TEST(GltfRead, DegenerateTrianglesAreDroppedAndCounted) {
  // The quad's indices 0 1 2 0 2 3 read as a strip: (0 1 2) (1 0 2) (2 0 2) (0 3 2).
  auto j = nlohmann::json::parse(read_file(kGltf / "quad.gltf"));
  j["meshes"][0]["primitives"][0]["mode"] = 5;
  size_t dropped = 0;
  const Mesh m = read_gltf(j.dump(), "strip.gltf", kGltf, &dropped);
  EXPECT_EQ(m.face_count(), 3u);
  EXPECT_EQ(dropped, 1u);
}

// limn's writer, read back: the triangles of each face keep their corners' positions and UVs.
void expect_glb_round_trip(const Mesh& m) {
  std::string glb;
  write_glb(m, glb);
  const Mesh r = read_gltf(glb, "roundtrip.glb", {});
  ASSERT_EQ(r.face_count(), m.corner_count() - 2 * m.face_count());
  size_t t = 0;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    const uint32_t o = m.face_offsets[f];
    for (uint32_t i = 1; i + 1 < fv.size(); ++i, ++t) {
      const uint32_t corners[3] = {o, o + i, o + i + 1};
      for (int k = 0; k < 3; ++k) {
        const uint32_t c = corners[k], rc = uint32_t(3 * t + size_t(k));
        const uint32_t v = m.face_vertices[c], rv = r.face_vertices[rc];
        EXPECT_TRUE(std::equal(&m.positions[3 * v], &m.positions[3 * v] + 3, &r.positions[3 * rv]))
            << "triangle " << t;
        if (!m.uv_indices.empty()) {
          EXPECT_NEAR(r.uvs[2 * r.uv_indices[rc]], m.uvs[2 * m.uv_indices[c]], 1e-7f);
          EXPECT_NEAR(r.uvs[2 * r.uv_indices[rc] + 1], m.uvs[2 * m.uv_indices[c] + 1], 1e-7f);
        }
      }
    }
  }
  // Welding gives back the cage's vertices (all positions of these shapes are distinct).
  const Mesh w = weld_vertices(r);
  EXPECT_EQ(w.vertex_count(), m.vertex_count());
  EXPECT_EQ(w.face_count(), r.face_count());
  EXPECT_EQ(w.uv_indices.empty(), m.uv_indices.empty());
}

TEST(GltfRead, LimnsOwnGlbReadsBack) {
  expect_glb_round_trip(make_cube());
  const int valences[] = {3, 5};
  Mesh torus = make_torus(24, 12, valences);
  expect_glb_round_trip(torus);
  // With per-corner UVs (every face its own UV island), so the GLB splits every corner.
  for (size_t c = 0; c < torus.corner_count(); ++c) {
    const uint32_t v = torus.face_vertices[c];
    torus.uvs.insert(torus.uvs.end(),
                     {0.3f * torus.positions[3 * v] + 0.5f,
                      0.3f * torus.positions[3 * v + 1] + 0.5f + 0.01f * float(c % 4)});
    torus.uv_indices.push_back(uint32_t(c));
  }
  expect_glb_round_trip(torus);
}

TEST(GltfRead, WeldTurnsASeamedCubeIntoItsCage) {
  const Mesh seamed = read_mesh(kGltf / "cube_seams.gltf");
  EXPECT_EQ(seamed.vertex_count(), 24u);
  ReadOptions opt;
  opt.weld = true;
  const Mesh cage = read_mesh(kGltf / "cube_seams.gltf", opt);
  EXPECT_EQ(cage.vertex_count(), 8u);
  EXPECT_EQ(cage.face_count(), 12u);
  EXPECT_EQ(cage.uvs.size() / 2, 14u);  // the cross-shaped unwrap's distinct corners
  EXPECT_EQ(cage.normals.size() / 3, 6u);
  for (size_t c = 0; c < cage.corner_count(); ++c) {
    EXPECT_EQ(cage.uvs[2 * cage.uv_indices[c]], seamed.uvs[2 * seamed.uv_indices[c]]);
    EXPECT_EQ(cage.uvs[2 * cage.uv_indices[c] + 1], seamed.uvs[2 * seamed.uv_indices[c] + 1]);
    EXPECT_EQ(cage.normals[3 * cage.normal_indices[c] + 1],
              seamed.normals[3 * seamed.normal_indices[c] + 1]);
  }
  const MeshStats s = analyze(cage, build_topology(cage));
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.inconsistent_edges, 0u);
  EXPECT_EQ(s.euler_characteristic, 2);
  // weld is ignored for other formats.
  const Mesh obj = read_mesh_memory("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nf 1 2 3\n", opt, "x.obj");
  EXPECT_EQ(obj.vertex_count(), 4u);
}

TEST(GltfRead, BadFilesInTestData) {
  const std::map<std::string, std::string> expected = {
      {"bad_missing_buffer.gltf", "no_such_buffer.bin"},
      {"bad_accessor_past_view.gltf", "POSITION accessor 0"},
      {"bad_view_past_buffer.gltf", "past the end of buffer 0"},
      {"bad_index_past_count.gltf", "past the vertex count 3"},
      {"bad_position_type.gltf", "VEC2"},
      {"bad_points_mode.gltf", "mode 0 (points)"},
      {"bad_nan_position.gltf", "not finite"},
      {"bad_attribute_count.gltf", "NORMAL accessor 1 has 2 elements but POSITION has 3"},
      {"bad_node_cycle.gltf", "reached twice"},
      {"bad_truncated.glb", "GLB"},
  };
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(LIMN_TEST_DATA) / "bad")) {
    if (e.path().extension() != ".gltf" && e.path().extension() != ".glb") continue;
    const std::string name = e.path().filename().string();
    SCOPED_TRACE(name);
    try {
      read_mesh(e.path());
      ADD_FAILURE() << "accepted";
    } catch (const InputError& err) {
      const std::string msg = err.what();
      EXPECT_THAT(msg, HasSubstr(name + ": "));
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      if (expected.count(name)) {
        EXPECT_THAT(msg, HasSubstr(expected.at(name)));
      }
    }
    ++n;
  }
  EXPECT_EQ(n, expected.size());
}

TEST(GltfRead, BadInline) {
  const auto bad = [](const std::string& data, const char* fragment) {
    try {
      read_gltf(data, "inline.gltf", "/nonexistent-limn-dir");
      ADD_FAILURE() << "accepted: " << fragment;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("inline.gltf: "));
      EXPECT_THAT(e.what(), HasSubstr(fragment));
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  bad("", "empty file");
  bad("{", "cannot read glTF");
  bad("glTF\x02\0\0\0", "cannot read GLB");
  auto j = nlohmann::json::parse(read_file(kGltf / "quad.gltf"));
  auto k = j;
  k["meshes"][0]["primitives"][0]["mode"] = 1;
  bad(k.dump(), "mode 1 (lines)");
  k = j;
  k["meshes"][0]["primitives"][0]["attributes"].erase("POSITION");
  bad(k.dump(), "no POSITION");
  k = j;
  k["accessors"][1]["byteOffset"] = 16;  // interleaved: the last normal now runs past the view
  bad(k.dump(), "NORMAL accessor 1 (4 elements of 12 bytes, stride 24, offset 16) runs past");
  k = j;
  k["nodes"][0]["rotation"] = {0, 0, 0};
  bad(k.dump(), "rotation has 3 numbers");
  k = j;
  k["scene"] = 3;
  bad(k.dump(), "scene 3");
  k = j;
  k["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  k["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  bad(k.dump(), "KHR_draco_mesh_compression");
  k = j;
  k["accessors"][3]["componentType"] = 5126;  // float indices
  bad(k.dump(), "indices accessor 3");
}

}  // namespace
}  // namespace limn
