#pragma once
// The fast probe (docs/probe.md, "The fast method"; the admissible set: docs/ensemble.md, "The
// admissible force networks"). In the small-g, negligible-inertia limit the forces at the end
// of the probe are statically admissible, so the critical force is the largest admissible
// normal force of the contact:
//     F_crit(c) = max fn_c over { A f = rhs, fn >= 0, |ft| <= mu fn }    (a linear program).
// At that optimum the contacts that are open (fn = 0) and sliding (|ft| = mu fn) are known;
// every other contact keeps its surfaces together. The displacement field is then the
// kinematic problem of the step with that active set: the displacement q of least kinetic
// energy (as the contact-dynamics step selects it) such that
//     sticking contacts:  U_n = 0, U_t = 0;    sliding contacts:  U_n = 0 (slip free);
//     open contacts:      free;                the probed contact: U_n = g (its tangential
//                                              condition as its state at the optimum),
// with U = A^T q the relative displacements (A the balance rows: virtual work) and the
// generalised coordinates q = (u_x, u_y, R theta per grain; lambda dt of the cell), of masses
// (m, m, I/R^2; 2 V M_lambda). The LP is solved by barrier, whose optimum lies inside the
// optimal face: a contact that carries force in some optimal network is constrained
// (strict complementarity). The field's unilateral conditions (open contacts do not close,
// sliding contacts slip against their friction force) are checked, not imposed.
#include <optional>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/lp/force_lp.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/probe_result.hpp"

namespace unjam {

struct KinematicProbeSettings {
  double g = 1e-9;            // prescribed opening (R_max)
  double state_tol = 1e-7;    // (units of F0) open: fn <= tol; sliding: mu fn - |ft| <= tol
  LpMethod method = LpMethod::barrier;
  // ForceLP's tolerance (CLP's primal and dual feasibility tolerance), in [kMinLpTolerance,
  // kMaxLpTolerance] (lp/force_lp.hpp; docs/ensemble.md, "The LP's tolerances"): the same LP
  // as `unjam bounds --lp-tol`, so F_crit is its fn_max at the same tolerance.
  double lp_tolerance = 1e-9;
  // Active-set updates after the first solve (solve_active_set, core/least_norm.hpp).
  int max_rounds = 50;
  // mu, P_ext, M_lambda (weight of the cell strain in the kinetic energy) and touch_gap (pairs
  // closer than this enter the admissible set); empty: the packing's own (packing.meta.contact)
  std::optional<ContactModel> model;
};

// Holds the admissible set of one packing and its LP; probes one contact after another. The
// set and the masses are those of model = contact_model_of(packing, settings.model)
// (contact/contact_problem.hpp): system() = admissible_system(packing, model), the contacts
// classify_contact marks touching (gap < model.touch_gap) or loaded (fn > 1e-9 F0), and the
// cell's mass 2 V model.M_lambda. Not thread-safe: give each thread its own copy.
class KinematicProbe {
 public:
  KinematicProbe(const Packing& packing, const KinematicProbeSettings& settings);
  // Probes packing.contacts[contact]; throws unjam::Error if it is not in the admissible
  // set (not touching and carrying no force).
  ProbeResult probe(int contact);
  const EquilibriumSystem& system() const { return system_; }
  // The optimal network of the last probe, in the order of system().contacts.
  ForceNetwork network() const { return lp_.network(); }

 private:
  const Packing* packing_;
  KinematicProbeSettings settings_;
  ContactModel model_;
  EquilibriumSystem system_;
  ForceLP lp_;
  std::vector<int> system_index_;  // packing contact -> position in system_.contacts, or -1
  Eigen::VectorXd inverse_mass_;   // per row of A (generalised coordinate)
};

}  // namespace unjam
