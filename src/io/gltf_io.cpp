// Binary glTF 2.0 output through tinygltf, so results open in any glTF viewer.
#include <fmt/format.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "limn/io/mesh_io.hpp"
#include "split_seams.hpp"

namespace limn {

namespace {

template <class T>
int add_view(tinygltf::Model& model, std::vector<unsigned char>& bin, const std::vector<T>& data,
             int target) {
  while (bin.size() % 4) bin.push_back(0);  // glTF requires 4-byte aligned accessors
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = bin.size();
  view.byteLength = data.size() * sizeof(T);
  view.target = target;
  const auto* p = reinterpret_cast<const unsigned char*>(data.data());
  bin.insert(bin.end(), p, p + view.byteLength);
  model.bufferViews.push_back(view);
  return static_cast<int>(model.bufferViews.size() - 1);
}

int add_accessor(tinygltf::Model& model, int view, int component, int type, size_t count) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = component;
  a.type = type;
  a.count = count;
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size() - 1);
}

// Per vertex the tangent frame a normal map baked by limn assumes (limn/paint/bake.hpp): xyz
// along +u (the area-weighted mean of the triangles' dP/du, made orthogonal to the normal), w
// the handedness that makes cross(normal, xyz) * w point along +v (v up, as limn's UVs), as
// glTF's TANGENT holds it. Vertices with no usable UV gradient get any unit tangent.
std::vector<float> tangents(const std::vector<float>& pos, const std::vector<float>& nrm,
                            const std::vector<float>& uvs, const std::vector<uint32_t>& tris) {
  const size_t n = pos.size() / 3;
  std::vector<double> t(3 * n, 0.0), b(3 * n, 0.0);
  for (size_t i = 0; i + 2 < tris.size(); i += 3) {
    const uint32_t v[3] = {tris[i], tris[i + 1], tris[i + 2]};
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k)
      e1[k] = double(pos[3 * v[1] + k]) - pos[3 * v[0] + k],
      e2[k] = double(pos[3 * v[2] + k]) - pos[3 * v[0] + k];
    const double du1 = double(uvs[2 * v[1]]) - uvs[2 * v[0]],
                 dv1 = double(uvs[2 * v[1] + 1]) - uvs[2 * v[0] + 1];
    const double du2 = double(uvs[2 * v[2]]) - uvs[2 * v[0]],
                 dv2 = double(uvs[2 * v[2] + 1]) - uvs[2 * v[0] + 1];
    const double det = du1 * dv2 - du2 * dv1;
    if (!(std::fabs(det) > 0) || !std::isfinite(det)) continue;
    // dP/du and dP/dv times |det| (twice the triangle's UV area): larger triangles count more.
    const double s = det > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) {
      const double tk = (e1[k] * dv2 - e2[k] * dv1) * s, bk = (e2[k] * du1 - e1[k] * du2) * s;
      for (uint32_t x : v) t[3 * x + size_t(k)] += tk, b[3 * x + size_t(k)] += bk;
    }
  }
  std::vector<float> out(4 * n);
  for (size_t i = 0; i < n; ++i) {
    const double N[3] = {nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]};
    double T[3] = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
    const double d = T[0] * N[0] + T[1] * N[1] + T[2] * N[2];
    for (int k = 0; k < 3; ++k) T[k] -= d * N[k];
    double l = std::sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
    if (!(l > 1e-20)) {
      // Any unit vector perpendicular to the normal.
      const double a[3] = {std::fabs(N[0]) < 0.9 ? 1.0 : 0.0, std::fabs(N[0]) < 0.9 ? 0.0 : 1.0, 0};
      const double e = a[0] * N[0] + a[1] * N[1];
      for (int k = 0; k < 3; ++k) T[k] = a[k] - e * N[k];
      l = std::sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
    }
    const double C[3] = {N[1] * T[2] - N[2] * T[1], N[2] * T[0] - N[0] * T[2],
                         N[0] * T[1] - N[1] * T[0]};
    const double w = C[0] * b[3 * i] + C[1] * b[3 * i + 1] + C[2] * b[3 * i + 2] < 0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; ++k) out[4 * i + size_t(k)] = float(T[k] / l);
    out[4 * i + 3] = float(w);
  }
  return out;
}

}  // namespace

void write_glb(const Mesh& m, std::string& out) {
  GlbTextures none;
  none.roughness = 0.7f;
  write_glb(m, none, out);
}

void write_glb(const Mesh& m, const GlbTextures& textures, std::string& out) {
  if (m.face_count() == 0) throw InputError("cannot write glTF: the mesh has no faces");
  const bool has_n = !m.normal_indices.empty(), has_uv = !m.uv_indices.empty();
  const bool has_c = !m.colors.empty();
  const std::vector<float> smooth = has_n ? std::vector<float>() : vertex_normals(m);

  // Output vertices: one per distinct (vertex, normal, uv) corner combination.
  std::vector<uint32_t> source;
  const Mesh split = split_at_seams(m, &source);
  const std::vector<uint32_t>& remap = split.face_vertices;
  std::vector<float> pos = split.positions, nrm, uv, col = split.colors;
  if (has_n) {
    nrm = split.normals;
  } else {
    nrm.reserve(3 * source.size());
    for (uint32_t v : source)
      nrm.insert(nrm.end(), &smooth[3 * size_t(v)], &smooth[3 * size_t(v)] + 3);
  }
  uv.reserve(split.uvs.size());
  for (size_t i = 0; i < split.uvs.size(); i += 2)
    uv.insert(uv.end(), {split.uvs[i], 1.0f - split.uvs[i + 1]});
  // glTF wants unit normals; zero ones (isolated or degenerate) get an arbitrary unit vector.
  for (size_t i = 0; i < nrm.size(); i += 3) {
    const float l = std::sqrt(nrm[i] * nrm[i] + nrm[i + 1] * nrm[i + 1] + nrm[i + 2] * nrm[i + 2]);
    if (l > 0) {
      for (int k = 0; k < 3; ++k) nrm[i + k] /= l;
    } else {
      nrm[i] = 0, nrm[i + 1] = 0, nrm[i + 2] = 1;
    }
  }
  std::vector<uint32_t> tris;
  tris.reserve(3 * (m.corner_count() - 2 * m.face_count()));
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t o = m.face_offsets[f], n = m.face_size(f);
    for (uint32_t i = 1; i + 1 < n; ++i)
      tris.insert(tris.end(), {remap[o], remap[o + i], remap[o + i + 1]});
  }

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "limn";
  std::vector<unsigned char> bin;
  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  const size_t nverts = pos.size() / 3;
  prim.indices =
      add_accessor(model, add_view(model, bin, tris, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, tris.size());
  const int pa = add_accessor(model, add_view(model, bin, pos, TINYGLTF_TARGET_ARRAY_BUFFER),
                              TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nverts);
  const Box box = bounding_box(m);
  model.accessors[pa].minValues = {box.min[0], box.min[1], box.min[2]};
  model.accessors[pa].maxValues = {box.max[0], box.max[1], box.max[2]};
  prim.attributes["POSITION"] = pa;
  prim.attributes["NORMAL"] =
      add_accessor(model, add_view(model, bin, nrm, TINYGLTF_TARGET_ARRAY_BUFFER),
                   TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nverts);
  if (has_uv)
    prim.attributes["TEXCOORD_0"] =
        add_accessor(model, add_view(model, bin, uv, TINYGLTF_TARGET_ARRAY_BUFFER),
                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, nverts);
  if (!textures.normal_png.empty() && has_uv) {
    const std::vector<float> tan = tangents(pos, nrm, split.uvs, tris);
    prim.attributes["TANGENT"] =
        add_accessor(model, add_view(model, bin, tan, TINYGLTF_TARGET_ARRAY_BUFFER),
                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, nverts);
  }
  if (has_c)
    prim.attributes["COLOR_0"] =
        add_accessor(model, add_view(model, bin, col, TINYGLTF_TARGET_ARRAY_BUFFER),
                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, nverts);

  tinygltf::Material mat;
  mat.name = "limn";
  mat.pbrMetallicRoughness.metallicFactor = textures.metallic;
  mat.pbrMetallicRoughness.roughnessFactor = textures.roughness;
  mat.doubleSided = true;  // scans and cages are often open; show both sides
  // Each texture: its PNG in the binary chunk, an image naming that view, a texture naming the
  // image (sampled with the default sampler: linear, repeat).
  auto add_texture = [&](const std::string& png, const char* name) {
    if (png.empty()) return -1;
    if (!has_uv) throw InputError(fmt::format("cannot write glTF: a {} texture needs UVs", name));
    std::vector<unsigned char> bytes(png.begin(), png.end());
    tinygltf::Image image;
    image.name = name;
    image.mimeType = "image/png";
    image.bufferView = add_view(model, bin, bytes, 0);  // target 0: no vertex or index data
    model.images.push_back(image);
    tinygltf::Texture texture;
    texture.source = int(model.images.size() - 1);
    model.textures.push_back(texture);
    return int(model.textures.size() - 1);
  };
  mat.pbrMetallicRoughness.baseColorTexture.index =
      add_texture(textures.base_color_png, "base_color");
  mat.pbrMetallicRoughness.metallicRoughnessTexture.index =
      add_texture(textures.metallic_roughness_png, "metallic_roughness");
  mat.normalTexture.index = add_texture(textures.normal_png, "normal");
  model.materials.push_back(mat);
  prim.material = 0;

  tinygltf::Buffer buffer;
  buffer.data = std::move(bin);
  model.buffers.push_back(std::move(buffer));
  tinygltf::Mesh gm;
  gm.name = "limn";
  gm.primitives.push_back(prim);
  model.meshes.push_back(gm);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  std::ostringstream os;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, os, /*prettyPrint=*/false, /*writeBinary=*/true))
    throw std::runtime_error("tinygltf failed to serialise the glTF scene");
  out += os.str();
}

}  // namespace limn
