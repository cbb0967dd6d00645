#include "unjam/probe/kinematic_probe.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/least_norm.hpp"

namespace unjam {

KinematicProbe::KinematicProbe(const Packing& packing, const KinematicProbeSettings& settings)
    : packing_(&packing),
      settings_(settings),
      model_(contact_model_of(packing, settings.model)),
      system_(admissible_system(packing, model_)),
      lp_(system_, settings.method, settings.lp_tolerance),
      system_index_(packing.contacts.size(), -1),
      inverse_mass_(inverse_masses(packing, system_, model_)) {
  for (int k = 0; k < system_.num_contacts(); ++k) system_index_[system_.contacts[k]] = k;
}

ProbeResult KinematicProbe::probe(int contact) {
  const Packing& p = *packing_;
  if (contact < 0 || contact >= static_cast<int>(p.contacts.size()) || system_index_[contact] < 0)
    throw Error("contact " + std::to_string(contact) + " is not a touching contact of the packing");
  const int kc = system_index_[contact];
  const double mu = system_.mu;
  ProbeResult r;
  r.contact = contact;
  r.a = p.contacts[contact].a;
  r.b = p.contacts[contact].b;
  r.f_cont = p.contacts[contact].fn;
  r.g = settings_.g;
  r.f_crit = lp_.max_fn(kc);
  const ForceNetwork net = lp_.network();
  const auto state = contact_states(net, mu, settings_.state_tol * system_.F0);

  // The active set of the kinematic problem: which relative displacements are held at zero.
  // Start from the states at the optimum; a contact whose field breaks its unilateral
  // condition (an open contact that would close, a sliding one that would slip along its
  // friction force) is then held too, and the field recomputed, until none does.
  const int nc = system_.num_contacts();
  std::vector<char> hold_n(nc), hold_t(nc);
  for (int k = 0; k < nc; ++k) {
    hold_n[k] = k == kc || state[k] != ContactState::open;
    hold_t[k] = mu > 0.0 && state[k] == ContactState::closed;
  }
  const double slack = 1e-6 * settings_.g;
  Eigen::VectorXd q;

  // Constraint rows: column (2k + part) of A gives the relative displacement U_n (part 0)
  // or U_t (part 1) of contact k as a row of C = A_sel^T. The least-norm problem is the
  // displacement of least kinetic energy with those held: C q = d, D = M^-1.
  const auto held_system = [&] {
    std::vector<Eigen::Triplet<double>> trip;
    std::vector<double> target;
    const auto add_row = [&](int column, double value) {
      const int row = static_cast<int>(target.size());
      for (Eigen::SparseMatrix<double>::InnerIterator it(system_.A, column); it; ++it)
        trip.emplace_back(row, static_cast<int>(it.row()), it.value());
      target.push_back(value);
    };
    for (int k = 0; k < nc; ++k) {
      if (hold_n[k]) add_row(2 * k, k == kc ? settings_.g : 0.0);
      if (hold_t[k]) add_row(2 * k + 1, 0.0);
    }
    LeastNormSystem ls;
    ls.B.resize(static_cast<int>(target.size()), system_.A.rows());
    ls.B.setFromTriplets(trip.begin(), trip.end());
    ls.D = inverse_mass_;
    ls.d = Eigen::Map<const Eigen::VectorXd>(target.data(),
                                             static_cast<Eigen::Index>(target.size()));
    return ls;
  };

  // The unilateral conditions of the contacts not held: U_n >= -slack for an open one;
  // U_t ft <= slack |ft| for a sliding one (it slips against its friction force).
  const auto hold_violations = [&](const LeastNormSystem& ls, const Eigen::VectorXd& sol) {
    q = sol;
    r.residual = (ls.B * q - ls.d).cwiseAbs().maxCoeff() / settings_.g;
    const Eigen::VectorXd U = system_.A.transpose() * q;
    int violations = 0;
    for (int k = 0; k < nc; ++k) {
      if (!hold_n[k] && U[2 * k] < -slack) {
        hold_n[k] = 1;
        ++violations;
      }
      if (!hold_t[k] && mu > 0.0 && state[k] == ContactState::sliding &&
          U[2 * k + 1] * net.ft[k] > slack * std::abs(net.ft[k])) {
        hold_t[k] = 1;
        ++violations;
      }
    }
    return violations;
  };

  // The first solve and at most max_rounds more.
  const ActiveSetRounds loop =
      solve_active_set(std::max(settings_.max_rounds, 0) + 1, held_system, hold_violations);
  if (!loop.factorised)
    throw Error("kinematic probe: the constraint system could not be factorised");
  r.violations = loop.changes;
  // F_crit is the LP optimum, exact. The field is a solution of the kinematic problem only
  // when no unilateral condition is violated: violations > 0 here means the round limit was
  // reached with contacts newly held whose field was not recomputed.
  r.converged = r.violations == 0;

  r.u.assign(p.size(), Vec2::Zero());
  r.u_rot.assign(p.size(), 0.0);
  for (std::size_t g = 0; g < system_.grains.size(); ++g) {
    const int i = system_.grains[g];
    r.u[i] = {q[3 * g], q[3 * g + 1]};
    r.u_rot[i] = q[3 * g + 2] / p.particles.radius[i];
  }
  r.lambda_dt = q[system_.pressure_row()];
  return r;
}

}  // namespace unjam
