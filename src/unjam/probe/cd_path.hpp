#pragma once
// The paper's probe step solved exactly along a path from the static packing
// (docs/probe.md, "The exact step followed from the static network: `--method cd`").
//
// The step of probe/cd_step.hpp is followed as the prescribed opening grows from 0 to g:
// lambda in [0, 1] scales the probed contact's opening, g_eff = gap - lambda g e_probed,
// and moves the load from the static network's own balance A f0 to b. At lambda = 0 the
// static network itself is the solution (q = 0, f = f0). On each piece of the path every
// contact keeps one state:
//     open    fn = ft = 0
//     stick   u_n = 0, u_t = 0                 (force anywhere in the cone)
//     slide s u_n = 0, ft = -s mu fn           (slip along s = +1 or -1; mu = 0: ft = 0)
// so the step is one sparse linear system in (q / dt^2, f), linear in lambda; the piece
// ends where the first contact would break its state's inequalities (a force leaves the
// cone or turns tensile, a slip reverses, an open pair closes), that contact changes state
// and the path goes on. This is a parametric principal pivoting method; it reaches the
// solution connected to the static network, the one a step started from rest follows, where
// that branch reaches the full opening. With friction the branch can instead be a closed
// curve: it turns back at a fold at lambda_max < 1 and returns to the static network through
// lambda < 0 (a "loop", docs/probe.md, "Why a path fails"); the step then has no solution
// connected to the static network.
//
// A hyperstatic set of sticking contacts leaves forces undetermined; the path therefore
// carries a small compliance kappa (u + kappa dt^2 (f - f_ref) = 0 on closed contacts,
// kappa a fraction `compliance` of g / (dt^2 F0)), and at lambda = 1 proximal steps move
// f_ref to the solution, which removes the compliance's displacement (the rigid step). Where
// that is not exact, the path is followed again at ten times and a tenth of the compliance
// (`retry`), and the lowest residual kept. The compliant continuation (CdPathStart::compliant)
// follows the path at a soft compliance instead, where the step has few folds, and lowers the
// compliance by a factor per proximal step down to the rigid one (docs/probe.md, "Where the
// path starts"): the rigid limit of the step with stiff contacts, which may be another of the
// step's solutions than the branch from the static network.
//
// Each piece solves the system with the grains' rows eliminated (M is diagonal): a sparse
// matrix of size 2 N_c + 1 (the Delassus operator W = A^T M^-1 A on the kinematic rows,
// bordered by the pressure row), factorised by SuiteSparse's KLU and updated by Woodbury's
// formula between factorisations; every solve is refined with residuals in extended
// precision, since the compliance leaves cond(S) ~ 1e7-1e10 (docs/probe.md, "The method").
#include <string>
#include <vector>

#include "unjam/packing/packing.hpp"
#include "unjam/probe/cd_step.hpp"
#include "unjam/probe/nlgs_probe.hpp"

namespace unjam {

// Where the path starts (docs/probe.md, "Where the path starts"): the static network (the
// solution connected to it, which the step's dynamics from rest reach), or the LP optimum's
// network and kinematic field (probe/kinematic_probe), itself an exact solution of the
// quasi-static step, from which the path reaches the solution of the step nearest to it.
// Or the static network at a soft compliance (compliant_start), then the compliance lowered
// step by step to the rigid step's: the rigid limit of the step with stiff contacts.
// Or the iterate of an interior-point method on the step (solver/interior_point), where the
// path starts at interior_compliance (docs/probe.md, "An interior-point start").
// Or the step's quasi-static limit followed from a step with more inertia (inertial): solved by
// the interior-point start at a smaller dt, then continued in dt to the probe's own
// (docs/probe.md, "The quasi-static step as the limit of vanishing inertia"). Or the
// interior-point start first, and that continuation where it is not exact (interior_inertial).
enum class CdPathStart { static_network, lp_optimum, compliant, interior_point, inertial, interior_inertial };

struct CdPathSettings {
  CdPathStart start = CdPathStart::static_network;
  double guess_margin = 1e-6;  // start from a guess: displacement conditions strict by this (g)
  // CdPathStart::interior_point (docs/probe.md, "An interior-point start"): paths from the
  // iterate at interior_compliance, lowered to interior_rigid. The first starts from the
  // iterate's own states (InteriorPointResult::closed, sliding) and is cut after
  // interior_states_pieces x (number of contacts) pieces (0: not followed); the next from the
  // states of its forces, and the last as that at 10 x both compliances, each cut after
  // interior_path_pieces x (number of contacts) pieces unless max_pieces is set. Where none
  // is exact, the compliant continuation follows. interior_max_iterations: the interior-point
  // method's cap (its velocity_scale is the step's g / dt^2); the method's own tests end it at
  // 40-50 iterations at 500-2000 disks, and a cap of 40 cut it short there at 2000 disks, where
  // its states then sent the first path astray (docs/probe.md, "The interior-point method's
  // iterations"). The path from the iterate's own states
  // is also cut where lambda has not passed the largest value it reached for
  // interior_states_stall pieces (0: no such cut): where it is exact it gains ground on nearly
  // every piece, where it fails it turns back early and wanders there (docs/probe.md, "The
  // iterate's own states"). Where that path is not exact it is followed again at 10 times
  // interior_compliance (still lowered to interior_rigid), interior_states_retries times, each
  // at 10 times the last, before the paths from the forces' states. Where the interior-point
  // method (plain Mehrotra) ends at a natural residual above interior_again_above, it runs again
  // in the wide neighbourhood interior_neighbourhood (InteriorPointSettings::neighbourhood), and
  // the iterate with the lower natural residual is the start; where no path from it is exact,
  // the paths from the other iterate follow, before the compliant continuation (0, the default:
  // no second run; it helps at 1000-8000 disks and costs 1.5 times the pieces at 500 disks, mu = 1;
  // docs/probe.md, "Keeping the iterates centred").
  double interior_compliance = 1e-3;
  double interior_rigid = 1e-5;
  double interior_states_pieces = 0.1;
  int interior_states_stall = 20;
  int interior_states_retries = 2;
  int interior_path_pieces = 1;
  int interior_max_iterations = 100;
  double interior_neighbourhood = 0.0;  // e.g. 1e-3
  double interior_again_above = 1e-3;
  double compliance = 1e-7;   // kappa F0 dt^2 / g: closing displacement per F0 of force change
  int max_pieces = 0;         // 0: 50 (number of contacts) + 1000
  int refinements = 4;        // proximal steps at lambda = 1 (the compliance's displacement removed)
  int max_updated_rows = 48;  // rows of S changed before it is factorised afresh (0: every piece)
  bool retry = true;          // where not exact: again at 10 x and 0.1 x the compliance
                              // (compliant: restarted below where the lowering stopped)
  // CdPathStart::compliant (and the continuation that follows the interior-point start): the
  // first path's compliance (`--cd-compliant-start`; at or below `compliance` the continuation
  // is the static start's paths; docs/probe.md, "Where the continuation starts"), then its
  // factor per proximal step down to `compliance`; where the lowering stops at a compliance c
  // (the solution it follows ends there), the path is followed afresh from the static network
  // at c / restart_divisor, up to max_restarts times (docs/probe.md, "Where the path starts").
  // A lowering whose proximal path fails is retried from the latest solution with the
  // factor's square root, up to lowering_retries times in a row, before the restart.
  double compliant_start = 0.1;
  double compliance_factor = 0.5;
  int lowering_retries = 4;
  double restart_divisor = 10.0;
  int max_restarts = 6;
  // No restart below restart_floor (a compliance, as `compliance`): where the next restart
  // would be stiffer, the next softer start is followed instead (`--cd-restart-floor`; 0, the
  // default: every restart). At 2000 disks the static network's branch does not carry to the
  // full opening at compliances ~1e-6, and a restart there spends pieces at a factorisation
  // every few (docs/probe.md, "Restarts below a floor").
  double restart_floor = 0.0;
  // CdPathStart::compliant (and the interior start's fallback): where the continuation from
  // compliant_start (with its restarts) ends without an exact solution, it is followed again
  // from softer_factor times that compliance, up to softer_starts times (the lowest residual
  // over all paths is kept), and a start's restarts end once two in a row stop short of the
  // full opening at the same lambda_max / compliance (the ones below would repeat them
  // scaled). 0: one start, and every restart followed; none without `retry` (docs/probe.md,
  // "Where the path starts").
  int softer_starts = 2;
  double softer_factor = 10.0;
  // The pieces one probe may take over all its paths (the first, the proximal paths of its
  // lowerings and refinements, the retries, restarts and softer starts); 0: no limit. Where
  // they are spent, the probe stops with the best solution met so far, if any (failure
  // "budget"; CdPathStats::pieces_all is then max_probe_pieces + 1). Deterministic, unlike
  // a limit in seconds (docs/probe.md, "A budget of pieces per probe").
  long long max_probe_pieces = 0;
  // The residual (g) at which a probe stops following further paths (`--cd-accept-residual`):
  // by default kExactStepTolerance, so only an exact solution ends the search before the
  // budget; raised (at most kMaxPathResidual), the first path whose solution is within it ends
  // the probe, which is then near-exact (not converged) where that solution is not exact. The
  // paths after a near-exact solution mostly fail and cost most of a near-exact probe's pieces
  // at 1000 disks (docs/probe.md, "Accepting a near-exact solution").
  double accept_residual = kExactStepTolerance;
  // The compliance (as `compliance`) at or below which a path's lowering, and its proximal
  // steps at its rigid compliance, end at the path's first exact solution (residual at most
  // kExactStepTolerance; `--cd-settle-compliance`), instead of going on to 1e-3 of that
  // residual or down to the rigid compliance. 0 (the default): never, so a path returns the
  // limit it follows. At low friction the forces have settled there: 2000 disks, mu = 0.05,
  // F_crit within 4e-5 and half the pieces of the probes whose last lowerings spend the
  // budget; at mu = 1 a path stopped at 1e-5 returns another of the step's exact solutions on
  // some probes (docs/probe.md, "Settling at an exact solution").
  double settle_compliance = 0.0;
  // A path whose forces at the full opening have a residual above lost_factor x max(its
  // compliance, 1e-3) g has lost its digits: its solves went through nearly singular state
  // sets (a path that has not shows the compliance's own displacement, ~0.1-1.3 g per unit of
  // compliance). It is then no solution and is not lowered (failure "lost"), and the compliant
  // continuation does not restart below it (a stiffer restart loses more) but goes on to its
  // next softer start (`--cd-lost-factor`; docs/probe.md, "Paths that lose their digits").
  // 0 (the default): off, such a path is lowered and restarted below as any other.
  double lost_factor = 0.0;
  // CdPathStart::inertial (docs/probe.md, "The quasi-static step as the limit of vanishing
  // inertia"). The step depends on dt only through g / dt^2 (the inertia m g / dt^2 of its
  // grains). It is solved first at dt / inertial_factor (inertial_factor^2 times the inertia)
  // by the interior-point start's paths (with its settings above, but not the compliant
  // continuation that follows them: it may spend most of a budget), where that is not exact again at
  // sqrt(10) times less dt, up to inertial_retries times; then continued in dt up to the
  // probe's own: each stage is the path from the last stage's solution (as the static start's,
  // at `compliance` and its retries), with log dt advanced by at most log(inertial_factor) /
  // inertial_stages (1.5 times the last step after a stage that is exact), halved where a stage
  // is not exact, up to inertial_halvings times in a row. Past them the branch of solutions
  // turns back in dt (a fold), and the interior-point start's paths at the next dt jump to another
  // branch, up to inertial_jumps times (near some folds the branches it jumps to fold again at
  // once). Where the continuation ends short of the probe's dt, the interior-point start at the
  // probe's dt follows, with its compliant continuation. Every stage shares max_probe_pieces.
  double inertial_factor = 10.0;
  int inertial_stages = 4;
  int inertial_halvings = 3;
  int inertial_retries = 1;
  int inertial_jumps = 8;
  // CdPathStart::interior_inertial: the interior-point start (with its compliant continuation)
  // at the probe's dt first, within interior_share x max_probe_pieces; where it is not exact,
  // the inertial start's continuation in dt within what is left of max_probe_pieces (without
  // its fallback: the interior-point start has run), and where that does not reach the probe's
  // dt exactly, the interior-point start's result (docs/probe.md, "The quasi-static step as the
  // limit of vanishing inertia").
  double interior_share = 0.5;
};

// One path followed by probe_cd_path (the first, a retry or a restart of the continuation):
// where it started and ended, for the user to see why a probe is or is not exact.
struct CdPathAttempt {
  double compliance = 0.0;      // compliance of its path from the start (as CdPathSettings::compliance)
  double compliance_end = 0.0;  // compliant: where its lowering stopped (0: it did not stop)
  double lambda_max = 0.0;      // the largest lambda its path reached (fraction of g; 1: the full opening)
  double residual = 0.0;        // of its best forces (g, F0); kNoSolution where it has none
  int pieces = 0;
  int lowerings = 0;
  std::string failure;          // as CdPathStats::failure ("" where it reached its end)
  bool iterate_states = false;  // interior: started from the iterate's own states (else from its forces')
  bool other_iterate = false;   // interior: from the interior-point method's other iterate (of its two runs,
                                // the one with the higher natural residual; CdPathSettings::interior_neighbourhood)
  double compliance_settled = 0.0;  // where its lowering ended at an exact solution by
                                    // CdPathSettings::settle_compliance (0: it did not)
  int factorizations = 0;           // of the reduced system along it, its lowerings included
  double cpu_seconds = 0.0;         // CPU time of the thread that followed it (s); for the
                                    // user to see where a probe's time went, never a result
  double dt = 0.0;  // inertial start: the time step of the step it solved (t0; 0: the probe's own)
};

struct CdPathStats {
  int pieces = 0;             // linear pieces of the returned path (state changes)
  long long pieces_all = 0;   // pieces of every path of the probe together (ProbeResult::sweeps)
  bool budget_spent = false;  // the probe stopped at CdPathSettings::max_probe_pieces
  bool accepted = false;      // it stopped at a solution within CdPathSettings::accept_residual that
                              // is not exact (before the budget was spent)
  int degenerate = 0;         // of them, zero-length (ties broken at one lambda)
  int refinements = 0;
  int lowerings = 0;          // of them, with the compliance lowered (CdPathStart::compliant)
  int factorizations = 0;     // of the reduced system (the others are updates of its factors)
  int attempts = 0;           // paths followed (1 + retries)
  int open = 0, sliding = 0;  // final states (the probed contact not counted as open)
  double lambda_max = 0.0;    // the largest lambda the first path reached (1: its end)
  double compliance_end = 0.0;  // compliant: the compliance (as `compliance`) where the
                                // lowering of the returned attempt stopped; 0 if it did not
  double compliance_settled = 0.0;  // the compliance where the returned attempt's lowering ended at
                                    // an exact solution by CdPathSettings::settle_compliance; 0 if not
  int interior_iterations = 0;  // interior_point: iterations of the interior-point method
  double interior_cpu_seconds = 0.0;  // interior_point: CPU time of its run(s) (s; never a result)
  double interior_residual = 0.0;  // interior_point: its natural residual at the end (F0, g / dt^2)
  // interior_point, where it ran again in the neighbourhood: that run's iterations, plain Newton
  // steps among them (InteriorPointResult::short_steps) and natural residual, and whether its
  // iterate is the start; 0 iterations where it did not run
  int interior_again_iterations = 0, interior_again_short_steps = 0;
  double interior_again_residual = 0.0;
  bool interior_again_kept = false;
  // inertial: the time steps of the continuation in dt (t0): where it started, the last it
  // solved exactly (the probe's own where it got there), and its stages (each a path from the
  // last stage's solution, or an interior-point start past a fold in dt: inertial_jumps)
  double inertial_dt_start = 0.0, inertial_dt_reached = 0.0;
  int inertial_stages = 0, inertial_jumps = 0;
  bool inertial_fallback = false;  // the continuation ended short: the interior-point start at the probe's dt
                                   // (interior_inertial: its result from before the continuation)
  int restarts = 0;           // compliant: paths followed after the first (restarts below where a
                              // lowering stopped, and the softer starts)
  std::string failure;        // why there is no solution: "loop" (the branch through the
                              // start is closed), "cycle" (at a degenerate point), "ray",
                              // "pieces", "singular", "inexact" (residual above kMaxPathResidual),
                              // "budget" (max_probe_pieces spent), "share" (interior_inertial:
                              // the interior-point start's share of it spent, and the continuation
                              // in dt ended short with the rest unspent), "stall" (the path from the
                              // interior point's states stopped gaining ground), "lost" (its
                              // forces at the full opening lost their digits; lost_factor)
  std::vector<CdPathAttempt> paths;  // every path followed, in order (paths.size() == attempts)
};

// Forces whose residual (g, F0) exceeds this are no solution; between kExactStepTolerance
// and this, the probe is kept but not converged.
inline constexpr double kMaxPathResidual = 1e-3;

// A start of the path other than the static network: forces (fn_0, ft_0, ...) and the
// generalised displacement q over the step, in the order of the step's system.
struct CdStepGuess {
  Eigen::VectorXd f, q;
  // Optional (empty: read from f by tolerances), per contact: closed, and sliding on the
  // cone's edge (the interior-point iterate's own reading, InteriorPointResult).
  std::vector<bool> closed, sliding;
};

// The LP optimum of the probed contact (F_crit = fn_max) and its kinematic field, as a guess.
CdStepGuess lp_optimum_guess(const Packing& packing, const CdStepProblem& step, const ProbeSettings& settings);

// Solves the step of probing packing.contacts[contact] (build_cd_step: settings.g, dt, model).
// result.sweeps = pieces of all its paths; result.converged = residual <= kExactStepTolerance.
// A path that exceeds max_pieces, comes back to a state set it left (its start's: a closed
// branch; another: cycling at a degenerate point), ends on a ray or returns forces with a
// residual above kMaxPathResidual returns residual kNoSolution. Polls settings.cancel before
// every piece of every path (the first path, the proximal steps, the lowerings and restarts
// of the continuation) and throws Cancelled once it returns true.
CdStepSolution probe_cd_path(const Packing& packing, int contact, const ProbeSettings& settings,
                             const CdPathSettings& path = {}, CdPathStats* stats = nullptr);

}  // namespace unjam
