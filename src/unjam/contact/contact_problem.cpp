#include "unjam/contact/contact_problem.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "unjam/core/units.hpp"

namespace unjam {

Eigen::MatrixXd ContactProblem::delassus() const {
  const Eigen::MatrixXd A = Eigen::MatrixXd(system.A);
  return A.transpose() * inverse_mass.asDiagonal() * A;
}

Eigen::VectorXd ContactProblem::local_free() const {
  Eigen::VectorXd q = -(system.A.transpose() * inverse_mass.cwiseProduct(system.rhs));
  for (int k = 0; k < num_contacts(); ++k) q[2 * k] += g_eff[k] / (dt * dt);
  return q;
}

Eigen::VectorXd ContactProblem::generalized_displacement(const Eigen::VectorXd& f) const {
  return (dt * dt) * inverse_mass.cwiseProduct(system.A * f - system.rhs);
}

Eigen::VectorXd ContactProblem::relative_displacement(const Eigen::VectorXd& f) const {
  Eigen::VectorXd u = system.A.transpose() * generalized_displacement(f);
  for (int k = 0; k < num_contacts(); ++k) u[2 * k] += g_eff[k];
  return u;
}

ContactModel contact_model_of(const Packing& packing, const std::optional<ContactModel>& model) {
  return model ? *model : packing.meta.contact;
}

EquilibriumSystem model_system(const Packing& packing, const std::vector<int>& contacts,
                               const ContactModel& model) {
  EquilibriumSystem sys = build_equilibrium_system(packing, contacts);
  sys.mu = model.mu;
  sys.F0 = force_unit(packing.mean_radius(), model.P_ext);
  sys.rhs[sys.pressure_row()] = 2.0 * packing.cell.area() * model.P_ext;
  return sys;
}

EquilibriumSystem admissible_system(const Packing& packing, const ContactModel& model, double fn_tol) {
  return model_system(packing, select_contacts(packing, model, fn_tol), model);
}

EquilibriumSystem admissible_system(const Packing& packing, double gap_tol, double fn_tol) {
  return admissible_system(packing, with_touch_gap(packing.meta.contact, gap_tol), fn_tol);
}

Eigen::VectorXd inverse_masses(const Packing& packing, const EquilibriumSystem& system,
                               const ContactModel& model) {
  Eigen::VectorXd inverse_mass(system.A.rows());
  for (std::size_t i = 0; i < system.grains.size(); ++i) {
    const double m = packing.particles.mass(system.grains[i]);
    inverse_mass[3 * i] = inverse_mass[3 * i + 1] = 1.0 / m;
    inverse_mass[3 * i + 2] = 2.0 / m;  // coordinate R theta: mass I / R^2 = m / 2
  }
  inverse_mass[system.pressure_row()] = 1.0 / (2.0 * packing.cell.area() * model.M_lambda);
  return inverse_mass;
}

ContactProblem build_contact_problem(const Packing& packing, const ContactModel& model, double dt) {
  const int nc = static_cast<int>(packing.contacts.size());
  ContactProblem pb;
  pb.cell = packing.cell;
  pb.model = model;
  pb.dt = dt;
  std::vector<int> all(nc);
  std::iota(all.begin(), all.end(), 0);
  pb.system = model_system(packing, all, model);
  pb.inverse_mass = inverse_masses(packing, pb.system, model);
  pb.g_eff.resize(nc);
  pb.state.resize(nc);
  for (int k = 0; k < nc; ++k) {
    const Contact& c = packing.contacts[k];
    pb.state[k] = classify_contact(c, model.touch_gap, 0.0);
    pb.g_eff[k] = pb.state[k].touching ? 0.0 : c.gap;
  }
  return pb;
}

double StepResidual::max() const {
  return std::max({penetration, complementarity, coulomb, sticking_slip, sliding_direction});
}

StepResidual step_residual(const ContactProblem& pb, const Eigen::VectorXd& f, double length) {
  const Eigen::VectorXd u = pb.relative_displacement(f);
  const double mu = pb.system.mu, F0 = pb.system.F0;
  StepResidual r;
  for (int k = 0; k < pb.num_contacts(); ++k) {
    const double fn = f[2 * k], ft = f[2 * k + 1];
    const double un = u[2 * k] / length, ut = u[2 * k + 1] / length;
    r.penetration = std::max(r.penetration, -un);
    r.complementarity = std::max(r.complementarity, std::min(un, fn / F0));
    r.coulomb = std::max({r.coulomb, (std::abs(ft) - mu * fn) / F0, -fn / F0});
    r.sticking_slip = std::max(r.sticking_slip, std::min(std::abs(ut), (mu * fn - std::abs(ft)) / F0));
    if (ft * ut > 0.0)
      r.sliding_direction = std::max(r.sliding_direction, std::min(std::abs(ut), std::abs(ft) / F0));
  }
  return r;
}

}  // namespace unjam
