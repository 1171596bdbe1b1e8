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

#include "clock.hpp"
#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::bench {

namespace osd = OpenSubdiv::OPENSUBDIV_VERSION;

/// An unrefined OpenSubdiv refiner for `m` (creases, corners, holes, boundary and crease rules),
/// with its UVs as face-varying channel 0 under `fvar` when `uvs`.
inline std::unique_ptr<osd::Far::TopologyRefiner> osd_refiner(
    const Mesh& m, bool uvs = false, FVarInterpolation fvar = FVarInterpolation::all) {
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
  const std::vector<int> uv_idx(m.uv_indices.begin(), m.uv_indices.end());
  osd::Far::TopologyDescriptor::FVarChannel channel;
  channel.numValues = int(m.uvs.size() / 2);
  channel.valueIndices = uv_idx.data();
  if (uvs) d.numFVarChannels = 1, d.fvarChannels = &channel;
  osd::Sdc::Options so;
  so.SetFVarLinearInterpolation(osd::Sdc::Options::FVarLinearInterpolation(fvar));
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

/// Far's adaptive patch table of `m` at isolation `level` with Gregory-basis end caps, and the
/// refiner it was made from (which its points need).
struct OsdAdaptive {
  std::unique_ptr<osd::Far::TopologyRefiner> refiner;
  std::unique_ptr<osd::Far::PatchTable> table;
};
inline OsdAdaptive osd_adaptive(const Mesh& m, int level, bool single_crease, bool inf_sharp) {
  namespace Far = osd::Far;
  OsdAdaptive a;
  a.refiner = osd_refiner(m);
  Far::TopologyRefiner::AdaptiveOptions ao(level);
  ao.useSingleCreasePatch = single_crease;
  ao.useInfSharpPatch = inf_sharp;
  a.refiner->RefineAdaptive(ao);
  Far::PatchTableFactory::Options po(level);
  po.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  po.useSingleCreasePatch = single_crease;
  po.useInfSharpPatch = inf_sharp;
  a.table.reset(Far::PatchTableFactory::Create(*a.refiner, po));
  return a;
}

/// Every point `a`'s patches read, into `out` (sized by the caller: refined vertices of all
/// levels, then the end caps' local points): the cage's, each level interpolated from the one
/// before, then the local points. P: {x, y, z} with Clear() and AddWithWeight().
template <class P>
void osd_points(const OsdAdaptive& a, const Mesh& m, std::vector<P>& out) {
  const osd::Far::TopologyRefiner& r = *a.refiner;
  const size_t nrefined = size_t(r.GetNumVerticesTotal());
  out.resize(nrefined + size_t(a.table->GetNumLocalPoints()));
  for (size_t v = 0; v < m.vertex_count(); ++v)
    out[v] = {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
  const osd::Far::PrimvarRefiner pr(r);
  P* src = out.data();
  for (int k = 1; k <= r.GetMaxLevel(); ++k) {
    P* dst = src + r.GetLevel(k - 1).GetNumVertices();
    pr.Interpolate(k, src, dst);
    src = dst;
  }
  if (a.table->GetNumLocalPoints())
    a.table->ComputeLocalPointValues(out.data(), out.data() + nrefined);
}

}  // namespace limn::bench
