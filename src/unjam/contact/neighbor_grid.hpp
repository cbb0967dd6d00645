#pragma once
// Pair search on the periodic cell with a cell list: O(N) for the near pairs of N disks.
#include <utility>
#include <vector>

#include "unjam/core/cell.hpp"
#include "unjam/packing/particles.hpp"

namespace unjam {

// All pairs (a < b) whose gap |l| - R_a - R_b (minimum image) is below `max_gap`,
// sorted by (a, b). The result does not depend on the thread count.
std::vector<std::pair<int, int>> find_near_pairs(const Particles& particles, const Cell& cell,
                                                 double max_gap);

}  // namespace unjam
