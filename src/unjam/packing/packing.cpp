#include "unjam/packing/packing.hpp"

#include <numeric>

#include "unjam/core/units.hpp"

namespace unjam {

double Packing::mean_radius() const {
  const auto& R = particles.radius;
  if (R.empty()) return 0.0;
  return std::accumulate(R.begin(), R.end(), 0.0) / static_cast<double>(R.size());
}

double Packing::force_unit() const { return unjam::force_unit(mean_radius(), meta.P_ext); }

}  // namespace unjam
