// limn simplify: Lloyd iterations for the L2,1 energy (Cohen-Steiner, Alliez, Desbrun 2004), the
// baseline the greedy optimiser is compared with.
//
// Each iteration fits proxies (n_i = N_i/|N_i|, the L2,1 optimum for fixed regions), picks per
// proxy the face of its region with the smallest error a |n_T - n_i|^2, and re-partitions by
// flooding from those seeds in order of error. Regions stay edge-connected by construction.
#pragma once

#include <cstddef>
#include <vector>

#include "limn/simplify/vsa.hpp"

namespace limn {

/// Runs Lloyd iterations on a complete partition (every face assigned; clusters edge-connected).
/// O(iterations x F log F).
LloydStats lloyd_optimize(const VsaSurface& s, Partition& p, const LloydOptions& options = {});

}  // namespace limn
