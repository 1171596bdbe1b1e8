// Face-varying channels through uniform refinement: the channel's own topology on each level
// (which values meet at a vertex, where seams run) and the stencils of one refinement step.
// Internal header of the subdiv layer.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "refine_levels.hpp"

namespace limn::refine_detail {

// A channel on one level. Values are numbered vertex by vertex (like OpenSubdiv's sibling
// values): vertex v owns values [offsets[v], offsets[v+1]), one per distinct value around it.
struct FVarState {
  std::vector<uint32_t> corner_value;  // per corner of the level: its value
  std::vector<uint32_t> offsets{0};    // per vertex, + 1
  std::vector<uint8_t> tag;            // per value: FVarTag bits
  std::vector<uint8_t> edge;           // per edge: FVarEdge bits
  std::vector<uint32_t> source;        // cage level only: per value, the caller's value index
  size_t value_count() const { return tag.size(); }
};

// Value tags (OpenSubdiv's Vtr::FVarLevel::ValueTag, the parts refinement reads). A value
// without kFvCrease is a corner: it stays put.
enum FVarTag : uint8_t {
  kFvMismatch = 1,   // the channel's topology differs from the vertex's here (seam, pinned)
  kFvCrease = 2,     // a smooth boundary of the channel: the crease rule along its two ends
  kFvSemiSharp = 4,  // pinned until semi-sharp edges (or the vertex) decay, then a crease
  kFvDepSharp = 8    // semi-sharp because its sibling is
};
// Edge tags: the faces on it disagree on a value at an end; linearly interpolated.
enum FVarEdge : uint8_t { kFvEdgeMismatch = 1, kFvEdgeLinear = 2 };

// Throws InputError unless `channel` has one index per corner (`corners` of them), each below
// its value count.
void check_face_varying(const FaceVaryingInput& channel, size_t corners);

// The channel on the cage (level 0, with its adjacency `a`). Throws InputError when
// corner_values has the wrong size or an index >= value_count.
FVarState fvar_cage_state(const SubdivOptions& o, const RefinedLevel& L0, const Adj& a,
                          std::span<const uint32_t> corner_values, size_t value_count);

// One uniform refinement step of level P (adjacency a, channel `parent`): returns the stencils
// of the child level's values over the parent's (the caller's indices on the cage) and sets
// `child` to the channel on the child level (derive_child's numbering).
StencilTable fvar_refine(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                         const FVarState& parent, FVarState& child);

// The same step applied at once to `width` (1-4) floats per parent value (the caller's
// indices on the cage): returns the child level's values, with no table built.
std::vector<float> fvar_refine_apply(const SubdivOptions& o, const RefinedLevel& P, const Adj& a,
                                     const FVarState& parent, FVarState& child, const float* values,
                                     int width);

// Limit stencils of the values of level L (quads, adjacency a, channel s) over its values
// (Far::PrimvarRefiner::LimitFaceVarying): matching vertices take their vertex's limit mask,
// creases 2/3 of the value and 1/6 of each end, corners stay. Throws InputError on non-quads.
StencilTable fvar_limit(const SubdivOptions& o, const RefinedLevel& L, const Adj& a,
                        const FVarState& s);

// The cage's non-manifold test (as OpenSubdiv's tagging): faces around v are not one fan, or a
// non-manifold edge touches it.
bool cage_vertex_non_manifold(const Adj& a, uint32_t v);

}  // namespace limn::refine_detail
