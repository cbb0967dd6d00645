#include "unjam/solver/force_polish.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/least_norm.hpp"
#include "unjam/packing/contact_model.hpp"

namespace unjam {
namespace {

enum class State { kOpen, kStick, kSlidePos, kSlideNeg };

// Largest grain residual (|force|, |torque / R|) / F0 and the relative pressure error of
// the network f = (fn_0, ft_0, ...) in the rows of `sys`.
std::pair<double, double> residuals(const EquilibriumSystem& sys, const Eigen::VectorXd& f) {
  const Eigen::VectorXd r = sys.A * f - sys.rhs;
  double worst = 0.0;
  for (std::size_t g = 0; g < sys.grains.size(); ++g)
    worst = std::max({worst, std::hypot(r[3 * g], r[3 * g + 1]), std::abs(r[3 * g + 2])});
  const int p = sys.pressure_row();
  return {worst / sys.F0, std::abs(r[p]) / sys.rhs[p]};
}

}  // namespace

PolishResult polish_forces(Packing& packing, double tol, double touch_gap) {
  const double mu = packing.meta.contact.mu;
  std::vector<int> loaded;
  for (int k = 0; k < static_cast<int>(packing.contacts.size()); ++k) {
    const ContactClass state = classify_contact(packing.contacts[k], touch_gap, 0.0);
    if (state.touching && state.loaded) loaded.push_back(k);
  }
  PolishResult res;
  if (loaded.empty()) return res;
  const EquilibriumSystem sys = build_equilibrium_system(packing, loaded);
  const int nc = sys.num_contacts();
  const Eigen::VectorXd f0 = packing_forces(packing, sys);

  std::vector<State> state(nc, State::kStick);
  for (int k = 0; k < nc; ++k) {
    const double fn = f0[2 * k], ft = f0[2 * k + 1];
    if (mu > 0.0 && std::abs(ft) >= mu * fn * (1.0 - 1e-9)) state[k] = ft > 0 ? State::kSlidePos : State::kSlideNeg;
  }

  // Rows kept: all but the x and y rows of the first grain (global translation makes them
  // redundant) and, for mu = 0, the torque rows (identically zero).
  std::vector<int> row_map(sys.A.rows(), -1);
  int rows = 0;
  for (int i = 0; i < sys.A.rows(); ++i) {
    const bool translation = i < 2;
    const bool torque = i != sys.pressure_row() && i % 3 == 2;
    if (!translation && !(mu == 0.0 && torque)) row_map[i] = rows++;
  }

  constexpr int kMaxRounds = 30;
  Eigen::VectorXd f = f0;
  for (res.rounds = 1; res.rounds <= kMaxRounds; ++res.rounds) {
    // Columns of B: the free components of every non-open contact.
    std::vector<Eigen::Triplet<double>> trip;
    std::vector<std::pair<int, int>> col_of;  // (contact, 0: fn-like, 1: ft)
    for (int k = 0; k < nc; ++k) {
      if (state[k] == State::kOpen) continue;
      const double s = state[k] == State::kSlidePos ? mu : state[k] == State::kSlideNeg ? -mu : 0.0;
      const int c = static_cast<int>(col_of.size());
      col_of.emplace_back(k, 0);
      for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k); it; ++it)
        if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c, it.value());
      if (s != 0.0)
        for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k + 1); it; ++it)
          if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c, s * it.value());
      if (state[k] == State::kStick && mu > 0.0) {
        col_of.emplace_back(k, 1);
        for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k + 1); it; ++it)
          if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c + 1, it.value());
      }
    }
    Eigen::SparseMatrix<double> B(rows, static_cast<int>(col_of.size()));
    B.setFromTriplets(trip.begin(), trip.end());

    // Start from the NLGS network projected onto the active set.
    Eigen::VectorXd x(col_of.size());
    for (std::size_t c = 0; c < col_of.size(); ++c) {
      const auto [k, part] = col_of[c];
      x[c] = part == 0 ? f0[2 * k] : f0[2 * k + 1];
    }
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(rows);
    rhs[row_map[sys.pressure_row()]] = sys.rhs[sys.pressure_row()];

    // The smallest correction that restores balance.
    const auto dx = least_norm_solution(B, Eigen::VectorXd::Ones(B.cols()), rhs - B * x);
    if (!dx) return res;
    x += *dx;

    // Back to (fn, ft) and the active-set checks.
    f.setZero();
    for (std::size_t c = 0; c < col_of.size(); ++c) {
      const auto [k, part] = col_of[c];
      f[2 * k + part] = x[c];
      if (part == 0 && (state[k] == State::kSlidePos || state[k] == State::kSlideNeg))
        f[2 * k + 1] = (state[k] == State::kSlidePos ? mu : -mu) * x[c];
    }
    bool changed = false;
    for (int k = 0; k < nc; ++k) {
      if (state[k] == State::kOpen) continue;
      const double fn = f[2 * k], ft = f[2 * k + 1];
      if (fn < 0.0) {
        state[k] = State::kOpen;
        changed = true;
      } else if (state[k] == State::kStick && std::abs(ft) > mu * fn) {
        state[k] = ft > 0 ? State::kSlidePos : State::kSlideNeg;
        changed = true;
      }
    }
    if (!changed) break;
  }
  if (res.rounds > kMaxRounds) return res;

  std::tie(res.max_residual_F0, res.pressure_error) = residuals(sys, f);
  res.max_change_F0 = (f - f0).cwiseAbs().maxCoeff() / sys.F0;
  res.success = res.max_residual_F0 < tol && res.pressure_error < tol;
  if (!res.success) return res;
  for (Contact& c : packing.contacts) c.fn = c.ft = 0.0;  // pairs left out are open
  for (int k = 0; k < nc; ++k) {
    Contact& c = packing.contacts[sys.contacts[k]];
    c.fn = f[2 * k];
    c.ft = f[2 * k + 1];
    if (c.fn > 0.0) ++res.active;
  }
  return res;
}

}  // namespace unjam
