#pragma once
// Least-norm solution of an underdetermined sparse linear system in a diagonal metric:
//     x = argmin x^T D^{-1} x  subject to  B x = d   =>   x = D B^T (B D B^T)^{-1} d.
// Used for the polish of a static network (D = 1: the smallest force change that restores
// balance) and for the kinematic probe (D = M^{-1}: the displacement of least kinetic
// energy compatible with the contact constraints). B D B^T is singular when rows of B are
// dependent (self-stresses, floppy modes); it is regularised by eps I, eps = 1e-14 times
// its mean diagonal, and the solution refined, which converges to the least-norm solution
// when d lies in the range of B.
//
// solve_active_set is the loop both callers run around it: the least-norm problem of an active
// set, solved, checked against the conditions the set does not impose, the set updated, until
// a round changes nothing.
#include <optional>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace unjam {

// Empty when the factorisation fails. `refinements`: iterative refinement steps.
std::optional<Eigen::VectorXd> least_norm_solution(const Eigen::SparseMatrix<double>& B,
                                                   const Eigen::VectorXd& D,
                                                   const Eigen::VectorXd& d,
                                                   int refinements = 3);

// The arguments of least_norm_solution: B x = d in the metric D (diagonal, one entry per
// column of B).
struct LeastNormSystem {
  Eigen::SparseMatrix<double> B;
  Eigen::VectorXd D;
  Eigen::VectorXd d;
};

// How an active-set loop (solve_active_set) ended.
struct ActiveSetRounds {
  int rounds = 0;           // least-norm solves made
  int changes = 0;          // changes of the active set after the last solve; 0: settled
  bool factorised = true;   // false: the last solve's factorisation failed (loop stopped there)
  bool settled() const { return factorised && changes == 0; }
};

// Rounds of
//     sys = system();   x = least_norm_solution(sys.B, sys.D, sys.d);   changes = update(sys, x);
// until a round makes no change, max_rounds solves have been made, or a factorisation fails.
// `system` builds the least-norm problem of the caller's current active set; `update` checks
// the solution x against the conditions the set does not impose, changes the set where they
// fail and returns the number of changes (int). The caller's updates must be monotone (a
// contact moves only one way through its states) for the loop to settle. Callers:
//   solver/force_polish:    forces of the free components, D = 1, states closed -> sliding
//                           -> open (packing/contact.hpp, contact_state);
//   probe/kinematic_probe:  displacements, D = M^-1, relative displacements held at zero
//                           (a contact's normal or tangential one, once held, stays held).
template <class System, class Update>
ActiveSetRounds solve_active_set(int max_rounds, System&& system, Update&& update) {
  ActiveSetRounds out;
  while (out.rounds < max_rounds) {
    const LeastNormSystem sys = system();
    const std::optional<Eigen::VectorXd> x = least_norm_solution(sys.B, sys.D, sys.d);
    ++out.rounds;
    if (!x) {
      out.factorised = false;
      break;
    }
    out.changes = update(sys, *x);
    if (out.changes == 0) break;
  }
  return out;
}

}  // namespace unjam
