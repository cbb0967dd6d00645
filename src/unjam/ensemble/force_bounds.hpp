#pragma once
// Exact per-contact intervals of the normal force over the admissible force networks
// (PHYSICS.md section 7):
//   [fn_min_k, fn_max_k] = [min, max] fn_k  over  { A x = rhs, fn >= 0, |ft| <= mu fn }
// with A the balance and pressure rows of equilibrium_matrix.hpp. Each end is a linear
// program, solved with COIN-OR CLP in Coulomb-cone coordinates y >= 0 (the Coulomb cone and
// fn >= 0 become plain column bounds, the only rows are the equalities). The model is built
// once; each further LP changes only the objective (LpMethod says how it is re-solved).
// fn_max_k is the bound on the critical force F_crit of contact k (PHYSICS.md section 6).
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/ensemble/lp_barrier.hpp"

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

// Loads the admissible set into `model` in cone coordinates: columns y >= 0 (the Coulomb
// cone and fn >= 0), rows A_y y = rhs (Ay = cone_matrix(system)), a zero objective, no log,
// primal and dual tolerance `tolerance` (see ForceLP). The model ForceLP solves.
void load_admissible_set(ClpSimplex& model, const Eigen::SparseMatrix<double>& Ay,
                         const Eigen::VectorXd& rhs, double tolerance);

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

  // min / max of fn_k over the admissible set (k: position in system.contacts).
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

 private:
  double optimize(int k, double direction);

  const EquilibriumSystem* system_;
  LpMethod method_;
  BarrierSolver barrier_;  // keeps the Cholesky analysis of A_y across solves
  std::unique_ptr<ClpSimplex> min_model_, max_model_;  // the same LP, one basis per sense
  ClpSimplex* last_ = nullptr;                         // model of the last solve
  int per_contact_;  // cone columns per contact (2 if mu > 0, else 1)
  // The contact whose fn is each model's current objective (-1: none, zero objective).
  int min_objective_ = -1, max_objective_ = -1;
  long long iterations_ = 0;
  long long loosened_solves_ = 0;
  bool last_loosened_ = false;
};

struct ForceBounds;

struct ForceBoundsOptions {
  int threads = 1;                  // OpenMP threads, one ForceLP copy each
  LpMethod method = LpMethod::barrier;
  double tolerance = 1e-9;          // CLP feasibility tolerance, see ForceLP
  bool keep_networks_at_max = false;  // store the argmax network of every contact
  // A contact with fn <= open_tol_F0 F0 in an admissible network can open: its fn_min is 0.
  // Minima at or below this are reported as 0 (the LP's own accuracy is ~tolerance).
  double open_tol_F0 = 1e-9;
  // Called with (LPs done, total = 2 N_c) after every LP, one call at a time; may be empty.
  std::function<void(int, int)> progress;
  // Polled before LPs are handed out; once true no more are, and the result is incomplete
  // (ForceBounds::complete false). May be empty.
  std::function<bool()> should_stop;
  // Called after every LP with what is known so far (see ForceBounds::complete); may be empty.
  std::function<void(const ForceBounds&)> checkpoint;
  // A partial result to resume from (a checkpoint's; not with keep_networks_at_max): its
  // known values are kept, the LPs of the others are solved.
  const ForceBounds* resume = nullptr;
};

struct ForceBounds {
  Eigen::VectorXd fn_min, fn_max;            // per contact of the system
  std::vector<ForceNetwork> network_at_max;  // per contact, if keep_networks_at_max
  int min_lps_skipped = 0;  // minima certified 0 by another LP's network, without their own
  long long iterations = 0;                  // solver iterations over all LPs
  long long loosened_solves = 0;  // LPs solved at looser tolerances (ForceLP::loosened_solves)
  double seconds = 0.0;                      // wall time of all LPs (model build included)
  // false if should_stop stopped the LPs: then NaN marks the values not known yet, and
  // fn_min = 0 every contact some optimal network opened (what a resume needs).
  bool complete = true;
};

// Both ends of every contact's interval. Every optimal network is admissible, so a contact
// it leaves open (fn <= open_tol) can open: fn_min = 0 with no LP of its own. Hence:
//   1. fn_max of every contact (one LP each); the contacts its argmax networks open get
//      fn_min = 0;
//   2. fn_min by LP for the rest, skipping any contact an earlier minimum's network opened.
// On a 2000-disk mu = 0.1 packing about a third of the contacts can open, and this saves
// 86 % of their min LPs (docs/ensemble.md).
// The LPs are handed out one at a time (the simplex: in contiguous chunks of 16) to the
// threads; each barrier LP starts from scratch, so its optimum does not depend on which thread
// solves it, nor on what it solved before.
ForceBounds compute_force_bounds(const EquilibriumSystem& system,
                                 const ForceBoundsOptions& options = {});

// The same over the processes of `distributor` (core/work_source.hpp), `options.threads` each:
// the result, progress and counts are those of the gathering process (rank 0); elsewhere
// the returned bounds are incomplete.
ForceBounds compute_force_bounds(const EquilibriumSystem& system, const ForceBoundsOptions& options,
                                 WorkDistributor& distributor);

}  // namespace unjam
