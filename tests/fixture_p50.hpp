#pragma once
// The 50-disk mu = 0.1 fixture (tests/fixtures/p50-mu0.1) with its admissible set and LP
// bounds, computed once per test run and shared by the ensemble tests.
#include <string>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::testing {

struct P50 {
  Packing packing = read_packing(std::string(UNJAM_FIXTURES_DIR) + "/p50-mu0.1");
  EquilibriumSystem sys = build_equilibrium_system(packing);
  ForceBounds bounds = compute_force_bounds(sys);
};

inline const P50& p50() {
  static const P50 data;
  return data;
}

// A sampled network as the column vector of the balance rows: (fn_0, ft_0, fn_1, ft_1, ...).
inline Eigen::VectorXd stacked(const ForceNetwork& net) {
  Eigen::VectorXd x(2 * net.fn.size());
  for (Eigen::Index k = 0; k < net.fn.size(); ++k) {
    x[2 * k] = net.fn[k];
    x[2 * k + 1] = net.ft[k];
  }
  return x;
}

}  // namespace unjam::testing
