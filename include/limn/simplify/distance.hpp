// limn simplify: how far a simplified surface lies from the original (Hausdorff and RMS).
//
// Closest-point queries run on Embree 3 BVHs (rtcPointQuery with an exact closest-point-on-
// triangle callback), in parallel with TBB.
#pragma once

#include <cstddef>
#include <cstdint>

#include "limn/mesh/mesh.hpp"

namespace limn {

struct SurfaceDistance {
  // All distances are divided by the reference's bounding-box diagonal.
  double hausdorff = 0;           ///< max of the two one-sided maxima below
  double max_to_reference = 0;    ///< max over samples of the simplified surface
  double max_from_reference = 0;  ///< max over the reference's vertices
  double rms_to_reference = 0;    ///< RMS over samples of the simplified surface (area-uniform)
  size_t samples = 0;             ///< points sampled on the simplified surface
};

/// Samples `samples` points on `simplified` (area-uniform, seeded, plus its vertices) and finds
/// each one's closest point on `reference`; also every referenced vertex of `reference` against
/// `simplified`. Polygons are fanned. Precondition: both have faces. O((samples + V) log F).
SurfaceDistance surface_distance(const Mesh& simplified, const Mesh& reference,
                                 size_t samples = 200000, uint64_t seed = 1);

}  // namespace limn
