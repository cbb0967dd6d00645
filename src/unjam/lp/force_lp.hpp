#pragma once
// The linear programs over the admissible force networks of one contact geometry
// (docs/ensemble.md, "The LP"):
//   min or max fn_k  over  { A x = rhs, fn >= 0, |ft| <= mu fn }
// with A the balance and pressure rows of contact/equilibrium_matrix.hpp, solved with COIN-OR
// CLP in Coulomb-cone coordinates y >= 0 (the Coulomb cone and fn >= 0 become plain column
// bounds, the only rows are the equalities). The model is built once; each further LP changes
// only the objective (LpMethod says how it is re-solved). The force bounds
// (ensemble/force_bounds) and the fast probe (probe/kinematic_probe: F_crit = max fn_k,
// docs/probe.md, "The fast method") both solve them.
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/lp/lp_barrier.hpp"

class ClpSimplex;

namespace unjam {

// One admissible force network, per contact of the system (force units of the packing).
struct ForceNetwork {
  Eigen::VectorXd fn, ft;
};

// Classifies every contact of a network by contact_state (packing/contact.hpp).
std::vector<ContactState> contact_states(const ForceNetwork& network, double mu, double tol);

// How each LP is solved (timings in docs/ensemble.md):
//   barrier  CLP's interior-point method without crossover, every LP from scratch with one
//            shared symbolic analysis (lp_barrier.hpp, normal_equations.hpp). Its cost grows
//            like one sparse Cholesky per iteration; the fastest at every size measured.
//            The optimal network it returns lies inside the optimal face.
//   simplex  primal simplex warm-started from the previous optimal basis (one model for the
//            minima, one for the maxima; dual simplex measured no faster: CLP falls back to
//            primal because a changed objective leaves the basis dual infeasible). The
//            optimal network is a vertex. Pivots per LP grow with the system size (the
//            optimal bases of two contacts differ over the whole packing), so the time per
//            contact grows about like N^2.
enum class LpMethod { barrier, simplex };

// A barrier point is admissible where y >= -tolerance and every row of A_y y = rhs holds to this
// fraction of its own scale, (|A_y| |y| + |rhs|)_i but at least the mean |y| (force_lp.cpp,
// admissible_point). Measured: the barrier's optima on admissible sets at most 4e-9; the points
// it calls optimal on empty sets 2e-5 to 3e-3 (docs/ensemble.md, "The LP"). A point that fails
// is finished by simplex, which decides.
inline constexpr double kAdmissibleRowResidual = 1e-6;

// Loads the admissible set into `model` in cone coordinates: columns y >= 0 (the Coulomb
// cone and fn >= 0), rows A_y y = rhs (Ay = cone_matrix(system)), a zero objective, no log,
// primal and dual tolerance `tolerance` (see ForceLP). The model ForceLP solves.
void load_admissible_set(ClpSimplex& model, const Eigen::SparseMatrix<double>& Ay,
                         const Eigen::VectorXd& rhs, double tolerance);

// Whether the admissible set of `system` has a point: dual simplex on a zero objective, the test
// ForceLP's constructor falls back on (docs/ensemble.md, "Why each row is checked on its own
// scale"). CLP decides on its scaled model; each verdict is checked in the model's own units (the
// point by the row check of kAdmissibleRowResidual and y >= -tolerance, emptiness by
// proves_no_admissible_network on CLP's ray); where the check fails the model is solved again
// without scaling from the basis reached, and then by the elastic LP (docs/ensemble.md, "The
// friction threshold").
// `tolerance` as for ForceLP. false for a system without contacts; throws unjam::Error where
// neither verdict checks out or CLP ends neither optimal nor infeasible.
bool has_admissible_network(const EquilibriumSystem& system, double tolerance = 1e-9);

// Whether w (one number per row) is a certificate that { A_y y = rhs, y >= 0 } is empty (Farkas:
// w . rhs < 0 while A_y^T w >= 0, up to what the bounds of y that the pressure row implies allow),
// checked in the model's own units. Ay = cone_matrix(system), rhs = system.rhs (the pressure row
// last). has_admissible_network checks CLP's infeasibility ray so before it calls a set empty.
bool proves_no_admissible_network(const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs,
                                  const Eigen::Ref<const Eigen::VectorXd>& w);

// The simplex basis of a solved admissible-set LP: CLP's status of every column, then every row
// (empty: none yet), and the dual simplex iterations of the solve that left it.
struct SimplexBasis {
  std::vector<unsigned char> status;
  long long iterations = 0;
};

// has_admissible_network warm-started from `basis` where it fits (the same numbers of columns
// and rows: the same contacts and, for mu > 0 or mu = 0 alike, as many cone columns), and
// leaving the final basis in it. A zero objective makes every basis dual feasible, so the dual
// simplex may start from any: for systems that differ only in mu (the friction threshold's
// bisection) the last one's basis is close, and its LPs take a fraction of the pivots from
// scratch (docs/ensemble.md, "The friction threshold"). The verdict is the set's, whatever the
// start.
bool has_admissible_network(const EquilibriumSystem& system, double tolerance, SimplexBasis& basis);

// The range of ForceLP's tolerance the commands accept, the range measured (docs/ensemble.md,
// "The LP's tolerances"): below it CLP's barrier ends LPs "optimal" at wrong points (at 1e-13
// on p50).
inline constexpr double kMinLpTolerance = 1e-12, kMaxLpTolerance = 1e-6;
// Throws unjam::Error(prefix + "the LP tolerance must be in [1e-12, 1e-06] (got T)") for a
// tolerance outside that range (NaN included).
void check_lp_tolerance(double tolerance, const std::string& prefix = "");

// The LP over the admissible set of one system, re-solved for one objective after another.
// Copyable: each copy owns its own CLP models and bases (one per thread).
class ForceLP {
 public:
  // Builds the model and finds a first admissible network (barrier, or dual simplex). Throws
  // unjam::Error ("no admissible force network: ...") when the set is empty.
  // `tolerance`: CLP's primal and dual feasibility tolerance (absolute, on the scaled model).
  // 1e-9 is the tested value; far below it (1e-13 on p50) CLP's barrier ends some LPs
  // "optimal" at wrong points.
  explicit ForceLP(const EquilibriumSystem& system, LpMethod method = LpMethod::barrier,
                   double tolerance = 1e-9);
  ForceLP(const ForceLP& other);
  ForceLP& operator=(const ForceLP&) = delete;
  ~ForceLP();

  // min / max of fn_k over the admissible set (k: position in system.contacts). Every optimum's
  // point is checked in the model's own units (kAdmissibleRowResidual, y >= -tolerance): the
  // barrier's, else primal simplex's, else that of a primal simplex without scaling. Throws
  // unjam::Error where none passes.
  double min_fn(int k);
  double max_fn(int k);

  // The optimal network of the last solve (an argmin / argmax of the last objective).
  ForceNetwork network() const;

  // Simplex and barrier iterations summed over every solve of this object (a copy starts
  // from 0).
  long long iterations() const { return iterations_; }
  // Barrier solves that stalled and ended optimal at looser tolerances (BarrierEnd), over
  // every solve of this object (a copy starts from 0), and whether the last one did.
  long long loosened_solves() const { return loosened_solves_; }
  bool last_solve_loosened() const { return last_loosened_; }
  // Barrier solves whose point was not admissible (or that failed) and were finished by primal
  // simplex, over every solve of this object after the first (a copy starts from 0).
  long long simplex_finishes() const { return simplex_finishes_; }
  // Simplex solves of the min / max LPs whose optimum on CLP's scaled model failed the row
  // check (or that CLP called infeasible) and were solved again without scaling, over every
  // solve of this object after the first (a copy starts from 0).
  long long unscaled_solves() const { return unscaled_solves_; }

 private:
  double optimize(int k, double direction);

  const EquilibriumSystem* system_;
  LpMethod method_;
  double tolerance_;
  Eigen::SparseMatrix<double> Ay_;  // cone_matrix(*system_): the rows A_y y = rhs
  BarrierSolver barrier_;  // keeps the Cholesky analysis of A_y across solves
  std::unique_ptr<ClpSimplex> min_model_, max_model_;  // the same LP, one basis per sense
  ClpSimplex* last_ = nullptr;                         // model of the last solve
  int per_contact_;  // cone columns per contact (2 if mu > 0, else 1)
  // The contact whose fn is each model's current objective (-1: none, zero objective).
  int min_objective_ = -1, max_objective_ = -1;
  long long iterations_ = 0;
  long long loosened_solves_ = 0;
  long long simplex_finishes_ = 0;
  long long unscaled_solves_ = 0;
  bool last_loosened_ = false;
};

}  // namespace unjam
