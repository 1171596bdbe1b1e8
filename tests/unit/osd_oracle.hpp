// OpenSubdiv 3.5 as the conformance oracle for limn's refinement: builds a Far::TopologyRefiner
// from a limn::Mesh, refines it uniformly and interpolates the cage positions level by level.
// Only the tests include this, so limn itself never depends on OpenSubdiv.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wpedantic"
#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/ptexIndices.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyLevel.h>
#include <opensubdiv/far/topologyRefiner.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#pragma GCC diagnostic pop

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::test {

/// The OpenSubdiv regression cages and the FAS quad cages of the shared models folder
/// (`models_dir`/osd and /quads), sorted; empty when the folder is missing.
inline std::vector<std::filesystem::path> shared_cages(const std::filesystem::path& models_dir) {
  std::vector<std::filesystem::path> out;
  for (const char* sub : {"osd", "quads"}) {
    const std::filesystem::path dir = models_dir / sub;
    if (!std::filesystem::is_directory(dir)) continue;
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".obj") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace osd = OpenSubdiv::OPENSUBDIV_VERSION;

/// The primvar type Far::PrimvarRefiner interpolates: it only needs Clear and AddWithWeight.
struct OsdPoint {
  double x = 0, y = 0, z = 0;  // double: the oracle should not add float round-off of its own
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const OsdPoint& p, float w) {
    x += w * p.x;
    y += w * p.y;
    z += w * p.z;
  }
};

inline osd::Sdc::Options osd_options(const SubdivOptions& options) {
  osd::Sdc::Options o;
  switch (options.boundary) {
    case BoundaryInterpolation::none:
      o.SetVtxBoundaryInterpolation(osd::Sdc::Options::VTX_BOUNDARY_NONE);
      break;
    case BoundaryInterpolation::edge_only:
      o.SetVtxBoundaryInterpolation(osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
      break;
    case BoundaryInterpolation::edge_and_corner:
    case BoundaryInterpolation::unset:  // limn's default, see SubdivOptions
      o.SetVtxBoundaryInterpolation(osd::Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
      break;
  }
  o.SetCreasingMethod(options.crease_method == CreaseMethod::chaikin
                          ? osd::Sdc::Options::CREASE_CHAIKIN
                          : osd::Sdc::Options::CREASE_UNIFORM);
  o.SetTriangleSubdivision(options.smooth_triangles ? osd::Sdc::Options::TRI_SUB_SMOOTH
                                                    : osd::Sdc::Options::TRI_SUB_CATMARK);
  // The enum values are OpenSubdiv's FVarLinearInterpolation's (face-varying rules never change
  // the vertex results).
  o.SetFVarLinearInterpolation(
      static_cast<osd::Sdc::Options::FVarLinearInterpolation>(options.face_varying));
  return o;
}

/// One OpenSubdiv level: positions (3 doubles per vertex, OpenSubdiv's vertex order) and the
/// topology, which points into OsdRefinement::refiner.
struct OsdLevel {
  std::vector<double> positions;
  const osd::Far::TopologyLevel* topology = nullptr;
};

struct OsdRefinement {
  std::unique_ptr<osd::Far::TopologyRefiner> refiner;  // owns what levels[k].topology points to
  std::vector<OsdLevel> levels;                        // levels[0] is the cage
};

/// An unrefined OpenSubdiv refiner for `cage`, with the cage's UVs as face-varying channel 0
/// when `with_uvs`. Throws std::runtime_error when OpenSubdiv rejects the topology.
inline std::unique_ptr<osd::Far::TopologyRefiner> osd_refiner(const Mesh& cage,
                                                              const SubdivOptions& options,
                                                              bool with_uvs = false) {
  using Index = osd::Far::Index;
  const size_t nf = cage.face_count();
  std::vector<int> verts_per_face(nf);
  for (size_t f = 0; f < nf; ++f) verts_per_face[f] = static_cast<int>(cage.face_size(f));
  const std::vector<Index> face_verts(cage.face_vertices.begin(), cage.face_vertices.end());
  const std::vector<Index> crease_verts(cage.crease_edges.begin(), cage.crease_edges.end());
  const std::vector<Index> corner_verts(cage.corner_vertices.begin(), cage.corner_vertices.end());
  const std::vector<Index> holes(cage.hole_faces.begin(), cage.hole_faces.end());

  osd::Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(cage.vertex_count());
  desc.numFaces = static_cast<int>(nf);
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = face_verts.data();
  desc.numCreases = static_cast<int>(cage.crease_sharpness.size());
  desc.creaseVertexIndexPairs = crease_verts.data();
  desc.creaseWeights = cage.crease_sharpness.data();
  desc.numCorners = static_cast<int>(cage.corner_sharpness.size());
  desc.cornerVertexIndices = corner_verts.data();
  desc.cornerWeights = cage.corner_sharpness.data();
  desc.numHoles = static_cast<int>(holes.size());
  desc.holeIndices = holes.data();
  const std::vector<Index> uv_indices(cage.uv_indices.begin(), cage.uv_indices.end());
  osd::Far::TopologyDescriptor::FVarChannel uv_channel;
  if (with_uvs) {
    uv_channel.numValues = static_cast<int>(cage.uvs.size() / 2);
    uv_channel.valueIndices = uv_indices.data();
    desc.numFVarChannels = 1;
    desc.fvarChannels = &uv_channel;
  }

  using Factory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  Factory::Options factory_options(osd::Sdc::SCHEME_CATMARK, osd_options(options));
  std::unique_ptr<osd::Far::TopologyRefiner> refiner(Factory::Create(desc, factory_options));
  if (!refiner) throw std::runtime_error("OpenSubdiv rejected the cage topology");
  return refiner;
}

/// Refines `cage` uniformly `depth` times with OpenSubdiv. Throws std::runtime_error when
/// OpenSubdiv rejects the topology.
inline OsdRefinement osd_refine(const Mesh& cage, int depth, const SubdivOptions& options) {
  OsdRefinement out;
  out.refiner = osd_refiner(cage, options);

  osd::Far::TopologyRefiner::UniformOptions uniform(depth);
  // Edges and sharpness of the last level are compared too, so keep its full topology.
  uniform.fullTopologyInLastLevel = true;
  out.refiner->RefineUniform(uniform);

  std::vector<std::vector<OsdPoint>> points(static_cast<size_t>(depth) + 1);
  points[0].resize(cage.vertex_count());
  for (size_t v = 0; v < cage.vertex_count(); ++v)
    points[0][v] = {cage.positions[3 * v], cage.positions[3 * v + 1], cage.positions[3 * v + 2]};
  const osd::Far::PrimvarRefiner primvar(*out.refiner);
  for (int k = 1; k <= depth; ++k) {
    const auto n = static_cast<size_t>(out.refiner->GetLevel(k).GetNumVertices());
    points[static_cast<size_t>(k)].resize(n);
    primvar.Interpolate(k, points[static_cast<size_t>(k) - 1], points[static_cast<size_t>(k)]);
  }

  out.levels.resize(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    OsdLevel& level = out.levels[k];
    level.topology = &out.refiner->GetLevel(static_cast<int>(k));
    level.positions.reserve(3 * points[k].size());
    for (const OsdPoint& p : points[k])
      level.positions.insert(level.positions.end(), {p.x, p.y, p.z});
  }
  return out;
}

/// OpenSubdiv's limit positions and tangents (3 doubles per vertex each) at the last level, from
/// Far::PrimvarRefiner::Limit.
struct OsdLimit {
  std::vector<double> position, tangent1, tangent2;
};

inline OsdLimit osd_limit(const OsdRefinement& r) {
  const std::vector<double>& last = r.levels.back().positions;
  const size_t n = last.size() / 3;
  std::vector<OsdPoint> src(n), p(n), t1(n), t2(n);
  for (size_t v = 0; v < n; ++v) src[v] = {last[3 * v], last[3 * v + 1], last[3 * v + 2]};
  osd::Far::PrimvarRefiner(*r.refiner).Limit(src, p, t1, t2);
  OsdLimit out;
  for (size_t v = 0; v < n; ++v) {
    out.position.insert(out.position.end(), {p[v].x, p[v].y, p[v].z});
    out.tangent1.insert(out.tangent1.end(), {t1[v].x, t1[v].y, t1[v].z});
    out.tangent2.insert(out.tangent2.end(), {t2[v].x, t2[v].y, t2[v].z});
  }
  return out;
}

/// The primvar type for UVs.
struct OsdUv {
  double u = 0, v = 0;
  void Clear(void* = nullptr) { u = v = 0; }
  void AddWithWeight(const OsdUv& p, float w) {
    u += w * p.u;
    v += w * p.v;
  }
};

/// OpenSubdiv's face-varying refinement of the cage's UVs: per level, the vertex positions (3
/// doubles per vertex), the UV values (InterpolateFaceVarying) and the topology, which gives
/// each face's value indices (GetFaceFVarValues(f, 0)).
struct OsdFaceVarying {
  std::unique_ptr<osd::Far::TopologyRefiner> refiner;
  std::vector<std::vector<double>> positions;
  std::vector<std::vector<OsdUv>> uvs;
  std::vector<OsdUv> limit;  ///< LimitFaceVarying of the last level's values
};

inline OsdFaceVarying osd_refine_uvs(const Mesh& cage, int depth, const SubdivOptions& options) {
  OsdFaceVarying out;
  out.refiner = osd_refiner(cage, options, true);
  osd::Far::TopologyRefiner::UniformOptions uniform(depth);
  uniform.fullTopologyInLastLevel = true;
  out.refiner->RefineUniform(uniform);
  const osd::Far::PrimvarRefiner primvar(*out.refiner);
  std::vector<OsdPoint> p(cage.vertex_count());
  for (size_t v = 0; v < cage.vertex_count(); ++v)
    p[v] = {cage.positions[3 * v], cage.positions[3 * v + 1], cage.positions[3 * v + 2]};
  std::vector<OsdUv> uv(cage.uvs.size() / 2);
  for (size_t i = 0; i < uv.size(); ++i) uv[i] = {cage.uvs[2 * i], cage.uvs[2 * i + 1]};
  for (int k = 0;; ++k) {
    std::vector<double>& pos = out.positions.emplace_back();
    for (const OsdPoint& q : p) pos.insert(pos.end(), {q.x, q.y, q.z});
    out.uvs.push_back(uv);
    if (k == depth) break;
    const osd::Far::TopologyLevel& next = out.refiner->GetLevel(k + 1);
    std::vector<OsdPoint> p2(static_cast<size_t>(next.GetNumVertices()));
    std::vector<OsdUv> uv2(static_cast<size_t>(next.GetNumFVarValues(0)));
    primvar.Interpolate(k + 1, p, p2);
    primvar.InterpolateFaceVarying(k + 1, uv, uv2, 0);
    p.swap(p2);
    uv.swap(uv2);
  }
  out.limit.resize(uv.size());
  if (depth > 0) primvar.LimitFaceVarying(uv, out.limit, 0);
  return out;
}

}  // namespace limn::test
