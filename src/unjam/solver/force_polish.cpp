#include "unjam/solver/force_polish.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/least_norm.hpp"
#include "unjam/packing/contact_model.hpp"

namespace unjam {
namespace {

// A contact that NLGS left on the edge of its Coulomb cone: |ft| = mu fn to rounding. The
// polish's first active set takes as sliding every contact with |ft| >= (1 - kOnTheCone) mu fn:
// contact_state with tol = mu fn - (1 - kOnTheCone) mu fn (that is kOnTheCone mu fn, written
// so that the rounded comparison is exactly |ft| >= (1 - kOnTheCone) mu fn).
constexpr double kOnTheCone = 1e-9;

// The tolerance of the checks of a corrected network, just below zero: contact_state is open
// iff fn < 0 and sliding iff |ft| > mu fn (for doubles, x <= -denorm_min iff x < 0, and the
// rounded mu fn - |ft| is negative iff mu fn < |ft|). A contact on the boundary (fn = 0 or
// |ft| = mu fn exactly, which the least-norm correction can give) breaks no condition and
// keeps its state.
constexpr double kStrictly = -std::numeric_limits<double>::denorm_min();

// Rounds of the active-set loop before the polish gives up (the NLGS network's active set
// has not settled yet; the static solve then goes on with NLGS).
constexpr int kMaxRounds = 30;

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

PolishResult polish_forces(Packing& packing, double tol, const ContactModel& model) {
  const double mu = model.mu;
  std::vector<int> loaded;
  for (int k = 0; k < static_cast<int>(packing.contacts.size()); ++k) {
    const ContactClass cls = classify_contact(packing.contacts[k], model.touch_gap, 0.0);
    if (cls.touching && cls.loaded) loaded.push_back(k);
  }
  PolishResult res;
  if (loaded.empty()) return res;
  const EquilibriumSystem sys = model_system(packing, loaded, model);
  const int nc = sys.num_contacts();
  const Eigen::VectorXd f0 = packing_forces(packing, sys);

  // The active set: the state of every contact (contact_state, packing/contact.hpp) and, for
  // a sliding one, the sign of ft (ft = slip[k] mu fn).
  std::vector<ContactState> state(nc);
  std::vector<double> slip(nc, 0.0);
  for (int k = 0; k < nc; ++k) {
    const double fn = f0[2 * k], ft = f0[2 * k + 1];
    const double cone = mu * fn;
    state[k] = contact_state(fn, ft, mu, cone - cone * (1.0 - kOnTheCone));
    if (state[k] == ContactState::sliding) slip[k] = ft > 0 ? 1.0 : -1.0;
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

  Eigen::VectorXd f = f0;
  std::vector<std::pair<int, int>> col_of;  // (contact, 0: fn-like, 1: ft) per column of B
  Eigen::VectorXd x;  // the network on the columns of B: the NLGS one projected, then corrected

  // B: the balance rows on the free components of every contact that is not open: fn along
  // n + slip mu t of a sliding contact, (fn, ft) of a closed one (fn alone when mu = 0).
  // The least-norm problem is the smallest correction of x that restores balance:
  //     B dx = rhs - B x,   D = 1.
  const auto active_system = [&] {
    std::vector<Eigen::Triplet<double>> trip;
    col_of.clear();
    for (int k = 0; k < nc; ++k) {
      if (state[k] == ContactState::open) continue;
      const double s = state[k] == ContactState::sliding ? slip[k] * mu : 0.0;
      const int c = static_cast<int>(col_of.size());
      col_of.emplace_back(k, 0);
      for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k); it; ++it)
        if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c, it.value());
      if (s != 0.0)
        for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k + 1); it; ++it)
          if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c, s * it.value());
      if (state[k] == ContactState::closed && mu > 0.0) {
        col_of.emplace_back(k, 1);
        for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * k + 1); it; ++it)
          if (row_map[it.row()] >= 0) trip.emplace_back(row_map[it.row()], c + 1, it.value());
      }
    }
    LeastNormSystem ls;
    ls.B.resize(rows, static_cast<int>(col_of.size()));
    ls.B.setFromTriplets(trip.begin(), trip.end());

    // Start from the NLGS network projected onto the active set.
    x.resize(static_cast<Eigen::Index>(col_of.size()));
    for (std::size_t c = 0; c < col_of.size(); ++c) {
      const auto [k, part] = col_of[c];
      x[c] = part == 0 ? f0[2 * k] : f0[2 * k + 1];
    }
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(rows);
    rhs[row_map[sys.pressure_row()]] = sys.rhs[sys.pressure_row()];
    ls.D = Eigen::VectorXd::Ones(ls.B.cols());
    ls.d = rhs - ls.B * x;
    return ls;
  };

  // Back to (fn, ft), then the states of the corrected network (contact_state, kStrictly): a
  // contact whose fn turned negative opens, a closed one outside the cone slides. States only
  // move closed -> sliding -> open (a sliding contact is on its cone's edge by construction).
  const auto update_states = [&](const LeastNormSystem&, const Eigen::VectorXd& dx) {
    x += dx;
    f.setZero();
    for (std::size_t c = 0; c < col_of.size(); ++c) {
      const auto [k, part] = col_of[c];
      f[2 * k + part] = x[c];
      if (part == 0 && state[k] == ContactState::sliding) f[2 * k + 1] = (slip[k] * mu) * x[c];
    }
    int changes = 0;
    for (int k = 0; k < nc; ++k) {
      if (state[k] == ContactState::open) continue;
      const double fn = f[2 * k], ft = f[2 * k + 1];
      const ContactState now = contact_state(fn, ft, mu, kStrictly);
      const bool moves = now == ContactState::open ||
                         (now == ContactState::sliding && state[k] == ContactState::closed);
      if (!moves) continue;
      if (now == ContactState::sliding) slip[k] = ft > 0 ? 1.0 : -1.0;
      state[k] = now;
      ++changes;
    }
    return changes;
  };

  const ActiveSetRounds loop = solve_active_set(kMaxRounds, active_system, update_states);
  res.rounds = loop.rounds;
  if (!loop.settled()) return res;

  std::tie(res.max_residual_F0, res.pressure_error) = residuals(sys, f);
  res.max_change_F0 = (f - f0).cwiseAbs().maxCoeff() / sys.F0;
  res.success = res.max_residual_F0 < tol && res.pressure_error < tol;
  if (!res.success) return res;
  for (Contact& c : packing.contacts) c.fn = c.ft = 0.0;  // pairs left out are open
  res.states.assign(packing.contacts.size(), ContactState::open);
  for (int k = 0; k < nc; ++k) {
    Contact& c = packing.contacts[sys.contacts[k]];
    c.fn = f[2 * k];
    c.ft = f[2 * k + 1];
    res.states[sys.contacts[k]] = state[k];
    if (c.fn > 0.0) ++res.active;
  }
  return res;
}

}  // namespace unjam
