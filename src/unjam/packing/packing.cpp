#include "unjam/packing/packing.hpp"

#include <numeric>

#include "unjam/core/units.hpp"

namespace unjam {

double Packing::mean_radius() const {
  const auto& R = particles.radius;
  if (R.empty()) return 0.0;
  return std::accumulate(R.begin(), R.end(), 0.0) / static_cast<double>(R.size());
}

std::vector<char> Packing::loaded_grains(double fn_min) const {
  std::vector<char> loaded(size(), 0);
  for (const Contact& c : contacts)
    if (c.fn > fn_min) loaded[c.a] = loaded[c.b] = 1;
  return loaded;
}

double Packing::force_unit() const { return unjam::force_unit(mean_radius(), meta.contact.P_ext); }

double Packing::min_cell_side() const {
  double R1 = 0.0, R2 = 0.0;
  for (const double R : particles.radius) {
    if (R > R1) {
      R2 = R1;
      R1 = R;
    } else if (R > R2) {
      R2 = R;
    }
  }
  return 2.0 * (R1 + R2);
}

}  // namespace unjam
