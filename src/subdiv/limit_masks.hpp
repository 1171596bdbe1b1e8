// Catmull-Clark limit masks at the vertices of a refined level of quads (limit.cpp), for the
// vertex limit stencils and for face-varying limits. Internal header of the subdiv layer.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "limn/mesh/topology.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {

// A mask under construction: (point, weight) terms, zero weights left out.
struct Weighted {
  std::vector<std::pair<uint32_t, double>> terms;
  void add(uint32_t v, double w) {
    if (w != 0.0) terms.emplace_back(v, w);
  }
  void emit(StencilTable& t) {
    for (const auto& [v, w] : terms) {
      t.indices.push_back(v);
      t.weights.push_back(static_cast<float>(w));
    }
    t.offsets.push_back(static_cast<uint32_t>(t.indices.size()));
    terms.clear();
  }
};

class LimitMasks {
 public:
  // Throws InputError when the level has non-quad faces.
  explicit LimitMasks(const RefinedLevel& L);
  // Appends vertex v's limit position and tangent masks (over the level's vertices) to P, T1,
  // T2, by the rule of v on this level.
  void compute(uint32_t v, Weighted& P, Weighted& T1, Weighted& T2);
  const Topology& topology() const { return t_; }

 private:
  const RefinedLevel& L_;
  Topology t_;
  std::vector<float> sharp_of_edge_;
  std::vector<uint32_t> ring_e_, ring_f_;
  std::vector<float> es_;
};

}  // namespace limn
