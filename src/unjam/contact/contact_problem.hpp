#pragma once
// The frictional contact problem of one contact-dynamics step from a static packing, in
// Siconos' global form (docs/probe.md, "The exact step"): plain data that every solver of the
// step and the one residual check (step_residual) take.
//
// Unknowns: the generalised displacement q over the step (u_x, u_y, R theta per grain;
// lambda dt of the cell: the cell strain rate is one more unknown) and the contact forces
// f = (fn_0, ft_0, fn_1, ...). With masses M = (m, m, m/2 per grain; 2 V M_lambda for the
// cell), A, b the balance rows of contact/equilibrium_matrix (the contact Jacobian is
// H = A^T, b = 2 V P_ext in the pressure row) and velocities zero at the start, implicit
// Euler gives
//     M q = dt^2 (A f - b),           u = A^T q + g_eff   (relative displacements, length),
// with g_eff per contact: 0 for a touching pair (classify_contact, gap < touch_gap), its gap
// otherwise. Every contact obeys Signorini and Coulomb's law with non-associated sliding:
//     fn >= 0,  u_n >= 0,  fn u_n = 0;   |ft| <= mu fn;
//     |ft| < mu fn  =>  u_t = 0;         u_t != 0  =>  ft = -mu fn sign(u_t).
// In Siconos' local form that is U = W f + q_loc with
//     W = A^T M^-1 A,   q_loc = -A^T M^-1 b + g_eff / dt^2,   U = u / dt^2.
// A probe shifts one contact's g_eff to -g (probe/cd_step); the static network f0 solves the
// unshifted problem (A f0 = b gives u = 0).
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/cell.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

struct ContactProblem {
  Cell cell;                      // the packing's cell; V = Lx Ly
  ContactModel model;             // mu, P_ext, M_lambda, touch_gap
  double dt = 0.0;                // time step of the step (t0); the probes: probe --dt
  EquilibriumSystem system;       // every contact of the packing, in its order; columns (fn_k, ft_k)
  Eigen::VectorXd inverse_mass;   // 1 / M per row of A (generalised coordinate)
  Eigen::VectorXd g_eff;          // per contact (length)
  std::vector<ContactClass> state;  // per contact: classify_contact(touch_gap, fn_min = 0)

  int num_contacts() const { return system.num_contacts(); }
  Eigen::MatrixXd delassus() const;     // W (dense, 2 nc x 2 nc)
  Eigen::VectorXd local_free() const;   // q_loc
  // q = dt^2 M^-1 (A f - b) of forces f = (fn_0, ft_0, fn_1, ...).
  Eigen::VectorXd generalized_displacement(const Eigen::VectorXd& f) const;
  // u = A^T q + g_eff (normal entries) of forces f.
  Eigen::VectorXd relative_displacement(const Eigen::VectorXd& f) const;
};

// The step of `packing` under `model` and time step dt: every contact of packing.contacts
// enters (column pair 2k, 2k + 1 is contact k), mu and P_ext are the model's. Throws
// unjam::Error as build_equilibrium_system does.
ContactProblem build_contact_problem(const Packing& packing, const ContactModel& model, double dt);

// The model a consumer's settings name: `model` if set, else the packing's own
// (packing.meta.contact).
ContactModel contact_model_of(const Packing& packing, const std::optional<ContactModel>& model);

// The balance rows of the listed contacts (indices into packing.contacts, in this order)
// under `model`: build_equilibrium_system's rows with mu = model.mu, F0 = 2 R_avg model.P_ext
// and the pressure row's right-hand side 2 V model.P_ext. Every contact problem's rows come
// from it: build_contact_problem (all contacts), admissible_system (the admissible set) and
// the static polish (solver/force_polish: the touching, loaded contacts). Throws
// unjam::Error as build_equilibrium_system does.
EquilibriumSystem model_system(const Packing& packing, const std::vector<int>& contacts,
                               const ContactModel& model);

// The admissible set of `packing` under `model` (docs/ensemble.md, "The admissible force
// networks"): the balance rows of the contacts select_contacts(packing, model, fn_tol) keeps
// (touching: gap < model.touch_gap, or loaded: fn > fn_tol F0), in the order of
// packing.contacts, with mu = model.mu, F0 = 2 R_avg model.P_ext and the pressure row's
// right-hand side 2 V model.P_ext. Throws unjam::Error as build_equilibrium_system does.
EquilibriumSystem admissible_system(const Packing& packing, const ContactModel& model,
                                    double fn_tol = 1e-9);

// The admissible set under the packing's own contact model with touch_gap = gap_tol: the set of
// `unjam bounds` and `unjam threshold` (--gap-tol, --fn-tol) and of the Python module's.
EquilibriumSystem admissible_system(const Packing& packing, double gap_tol, double fn_tol);

// 1 / M per row of system.A (generalised coordinate): 1/m, 1/m, 2/m for (u_x, u_y, R theta)
// of each grain of the system (I / R^2 = m / 2), 1 / (2 V model.M_lambda) for lambda dt of
// the cell (docs/method.md, "The cell strain rate").
Eigen::VectorXd inverse_masses(const Packing& packing, const EquilibriumSystem& system,
                               const ContactModel& model);

// How far forces f are from solving a step. Displacements in units of `length` (a probe's
// opening g), forces in units of F0; every entry is 0 for an exact solution.
struct StepResidual {
  double penetration = 0.0;      // max(-u_n) over all contacts
  double complementarity = 0.0;  // max min(u_n / length, fn / F0): a pair both open and loaded
  double coulomb = 0.0;          // max(|ft| - mu fn, -fn) / F0
  double sticking_slip = 0.0;    // max min(|u_t| / length, (mu fn - |ft|) / F0): slip inside the cone
  double sliding_direction = 0.0;  // max min(|u_t| / length, |ft| / F0) where ft u_t > 0
  double max() const;
};
StepResidual step_residual(const ContactProblem& problem, const Eigen::VectorXd& f, double length);

}  // namespace unjam
