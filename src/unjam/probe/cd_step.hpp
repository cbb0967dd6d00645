#pragma once
// The paper's probe step (docs/probe.md, "The exact step") as a linear complementarity
// problem, and its exact solution by complementary pivoting for small packings.
//
// One contact-dynamics step from the static packing (velocities zero, pressure bath on)
// in which the probed contact must open by g. With q the generalised displacement over the
// step (u_x, u_y, R theta per grain; lambda dt of the cell), masses M = (m, m, m/2; 2 V
// M_lambda), f the contact forces (fn_k, ft_k) and A, b the balance rows of
// contact/equilibrium_matrix, implicit Euler gives
//     M q = dt^2 (A f - b),           u = A^T q + g_eff  (relative displacements),
// where g_eff is 0 for touching pairs (gap < touch_gap), the gap otherwise, and -g on the
// normal of the probed contact. Every contact obeys Signorini and Coulomb's law with
// non-associated (non-dilatant) sliding:
//     fn >= 0,  u_n >= 0,  fn u_n = 0;   |ft| <= mu fn;
//     |ft| < mu fn  =>  u_t = 0;         u_t != 0  =>  ft = -mu fn sign(u_t).
// In Siconos' local form (a 2D frictional contact problem) that is U = W f + q_loc with
//     W = A^T M^-1 A,   q_loc = -A^T M^-1 b + g_eff / dt^2,   U = u / dt^2.
// The static network f0 solves the step with g = 0 (A f0 = b gives U = 0).
#include <filesystem>

#include <Eigen/Core>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/nlgs_probe.hpp"
#include "unjam/probe/probe_result.hpp"

namespace unjam {

struct CdStepProblem {
  EquilibriumSystem system;     // every contact of the packing; columns (fn_k, ft_k)
  int probed = -1;              // position of the probed contact in system.contacts
  double g = 0.0, dt = 0.0;     // prescribed opening (length), time step
  Eigen::VectorXd inverse_mass; // 1 / M per row of A
  Eigen::VectorXd g_eff;        // per contact (length)

  int num_contacts() const { return system.num_contacts(); }
  Eigen::MatrixXd delassus() const;     // W (dense, 2 nc x 2 nc)
  Eigen::VectorXd local_free() const;   // q_loc
  // q = dt^2 M^-1 (A f - b) of forces f = (fn_0, ft_0, fn_1, ...).
  Eigen::VectorXd generalized_displacement(const Eigen::VectorXd& f) const;
  // u = A^T q + g_eff (normal entries) of forces f.
  Eigen::VectorXd relative_displacement(const Eigen::VectorXd& f) const;
};

// The step of probing packing.contacts[contact] with settings.g, dt, touch_gap and bath
// mass (settings.bath.M_lambda). Throws unjam::Error for a contact that does not exist.
CdStepProblem build_cd_step(const Packing& packing, int contact, const ProbeSettings& settings);

// How far forces f are from solving the step. Displacements in units of g, forces in units
// of F0; every entry is 0 for an exact solution.
struct CdStepResidual {
  double penetration = 0.0;      // max(-u_n) over all contacts
  double complementarity = 0.0;  // max min(u_n / g, fn / F0): a pair both open and loaded
  double coulomb = 0.0;          // max(|ft| - mu fn, -fn) / F0
  double sticking_slip = 0.0;    // max min(|u_t| / g, (mu fn - |ft|) / F0): slip inside the cone
  double sliding_direction = 0.0;  // max min(|u_t| / g, |ft| / F0) where ft u_t > 0
  double max() const;
};
CdStepResidual cd_step_residual(const CdStepProblem& problem, const Eigen::VectorXd& f);

// A step counts as solved exactly when every residual entry is at most this (g, F0): the
// issue's 1e-6 g / dt in velocities is 1e-6 g in displacements over the step.
inline constexpr double kExactStepTolerance = 1e-6;

// Writes the step in Siconos numerics' frictional contact problem file format (dimension 2,
// number of contacts, W dense, q_loc, mu per contact), readable by
// frictionContact_newFromFile / siconos.numerics.frictionContact_new_from_filename.
void write_siconos_problem(const CdStepProblem& problem, const std::filesystem::path& file);

struct CdStepSolution {
  ProbeResult result;       // F_crit, field; residual = CdStepResidual::max(), sweeps = pivots
  Eigen::VectorXd f;        // forces (fn_0, ft_0, fn_1, ...) in the order of system.contacts
  CdStepResidual residual;
};

// Solves the step exactly by Lemke's method on its Stewart-Trinkle LCP (core/lemke.hpp):
// dense, meant for packings of up to ~1000 contacts; throws unjam::Error beyond
// kMaxLemkeContacts. Lemke's path starts from zero forces, not from the static network, so
// where the step has several exact solutions (docs/probe.md) it returns one of them.
inline constexpr int kMaxLemkeContacts = 1200;
inline constexpr int kLemkeRetries = 4;
CdStepSolution probe_cd_lemke(const Packing& packing, int contact, const ProbeSettings& settings);

// F_crit (the probed contact's fn), the field q and the residual of forces f of the step;
// f empty: a probe without a solution (residual kNoSolution).
ProbeResult cd_step_result(const CdStepProblem& problem, const Packing& packing,
                           const ProbeSettings& settings, const Eigen::VectorXd& f);

// The forces of a probe as a table a, b, fn, ft (every contact of the packing).
std::string step_forces_csv(const CdStepProblem& problem, const Packing& packing,
                            const Eigen::VectorXd& f);

}  // namespace unjam
