#pragma once
// The 50-disk mu = 0.1 fixture (tests/fixtures/p50-mu0.1) with its admissible set and LP
// bounds, computed once per test run and shared by the ensemble tests.
#include <algorithm>
#include <cmath>
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

// The worst violation of each admissibility condition over the networks passed to add():
// balance rows (absolute, force units), pressure row (relative), all rows (relative to
// |rhs|), fn >= 0 (most negative fn) and Coulomb (largest |ft| - mu fn).
struct WorstViolation {
  const EquilibriumSystem& sys;
  double balance = 0.0, pressure = 0.0, residual = 0.0, fn = 0.0, coulomb = 0.0;

  void add(const ForceNetwork& net) {
    for (Eigen::Index k = 0; k < net.fn.size(); ++k) {
      fn = std::min(fn, net.fn[k]);
      coulomb = std::max(coulomb, std::abs(net.ft[k]) - sys.mu * net.fn[k]);
    }
    const int p_row = sys.pressure_row();
    const Eigen::VectorXd r = sys.A * stacked(net) - sys.rhs;
    balance = std::max(balance, r.head(p_row).cwiseAbs().maxCoeff());
    pressure = std::max(pressure, std::abs(r[p_row]) / sys.rhs[p_row]);
    residual = std::max(residual, r.cwiseAbs().maxCoeff() / sys.rhs.norm());
  }
};

}  // namespace unjam::testing
