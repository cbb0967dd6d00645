#pragma once
// The initial state of the compaction (PHYSICS.md section 5): a gas of N disks, radii
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

// Throws unjam::Error for invalid settings (N < 2, radii not 0 < R_min <= R_max,
// phi outside (0, 0.45]).
Packing make_gas(const GasSettings& settings);

}  // namespace unjam
