// What the OpenSubdiv-side benchmarks share: OpenSubdiv's headers (warnings off for them), a
// clock, medians, and a Far::TopologyRefiner made from a limn::Mesh with its tags and rules.
#pragma once

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#pragma GCC diagnostic pop

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::bench {

namespace osd = OpenSubdiv::OPENSUBDIV_VERSION;

inline double now_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// An unrefined OpenSubdiv refiner for `m` (creases, corners, holes, boundary and crease rules).
inline std::unique_ptr<osd::Far::TopologyRefiner> osd_refiner(const Mesh& m) {
  std::vector<int> nvpf, idx(m.face_vertices.begin(), m.face_vertices.end());
  std::vector<int> creases(m.crease_edges.begin(), m.crease_edges.end());
  std::vector<int> corners(m.corner_vertices.begin(), m.corner_vertices.end());
  std::vector<int> holes(m.hole_faces.begin(), m.hole_faces.end());
  for (size_t f = 0; f < m.face_count(); ++f) nvpf.push_back(int(m.face_size(f)));
  osd::Far::TopologyDescriptor d;
  d.numVertices = int(m.vertex_count());
  d.numFaces = int(m.face_count());
  d.numVertsPerFace = nvpf.data();
  d.vertIndicesPerFace = idx.data();
  d.numCreases = int(m.crease_sharpness.size());
  d.creaseVertexIndexPairs = creases.data();
  d.creaseWeights = m.crease_sharpness.data();
  d.numCorners = int(corners.size());
  d.cornerVertexIndices = corners.data();
  d.cornerWeights = m.corner_sharpness.data();
  d.numHoles = int(holes.size());
  d.holeIndices = holes.data();
  osd::Sdc::Options so;
  const SubdivOptions lo = subdiv_options(m);
  so.SetVtxBoundaryInterpolation(lo.boundary == BoundaryInterpolation::edge_only
                                     ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                     : osd::Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  so.SetCreasingMethod(lo.crease_method == CreaseMethod::chaikin
                           ? osd::Sdc::Options::CREASE_CHAIKIN
                           : osd::Sdc::Options::CREASE_UNIFORM);
  using Factory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  return std::unique_ptr<osd::Far::TopologyRefiner>(
      Factory::Create(d, Factory::Options(osd::Sdc::SCHEME_CATMARK, so)));
}

}  // namespace limn::bench
