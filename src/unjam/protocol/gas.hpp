#pragma once
// The initial state of the compaction (docs/method.md, "Compaction"): a gas of N disks, radii
// uniform in [R_min, R_max], placed at random without overlap in a square periodic cell
// of packing fraction phi_gas, all at rest.
#include <cstdint>

#include "unjam/packing/packing.hpp"

namespace unjam {

struct GasSettings {
  int N = 500;
  double R_min = 0.5;
  double R_max = 1.0;
  double phi = 0.3;          // packing fraction of the gas
  std::uint64_t seed = 1;
};

// The fewest disks that can jam in a periodic cell: even at the densest packing of disks,
// phi_max = pi / sqrt(12), fewer would need a cell narrower than 4 R_max, where a pair
// touches through two periodic images (Packing::min_cell_side). With <R^2> the mean square
// radius: N_min = ceil(16 R_max^2 phi_max / (pi <R^2>)), 8 for radii in [0.5, 1].
int min_jamming_grains(const GasSettings& settings);

// Throws unjam::Error for invalid settings (N < min_jamming_grains, radii not
// 0 < R_min <= R_max, phi outside (0, 0.45]).
Packing make_gas(const GasSettings& settings);

}  // namespace unjam
