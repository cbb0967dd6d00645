#pragma once
// The paper's probe step (docs/probe.md, "The exact step") and its exact solution by
// complementary pivoting for small packings.
//
// The step is the packing's contact problem (contact/contact_problem.hpp: every contact, its
// g_eff, masses, dt, the bath) in which the probed contact must open by g: its g_eff is -g.
// The static network f0 solves the step with g = 0 (A f0 = b gives U = 0).
#include <cstdint>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/nlgs_probe.hpp"
#include "unjam/probe/probe_result.hpp"

namespace unjam {

struct CdStepProblem : ContactProblem {
  int probed = -1;              // position of the probed contact in system.contacts
  double g = 0.0;               // prescribed opening (length); g_eff[probed] = -g
};

// The step of probing packing.contacts[contact]: build_contact_problem under
// contact_model_of(packing, settings.model), time step settings.dt, and g_eff = -settings.g on
// the probed contact; where settings.window > 0, restricted to that window (window_step).
// Throws unjam::Error for a contact that does not exist or a window that is negative or not
// finite.
CdStepProblem build_cd_step(const Packing& packing, int contact, const ProbeSettings& settings);

// The step restricted to a window around the probed pair (docs/probe.md, "A window around the
// probed pair"). The window's grains are those whose centre lies within radius * 2 R_avg of
// the probed pair's midpoint (minimum image), and the probed pair's own. They keep their rows;
// every other grain is clamped to the cell (its rows are dropped: it moves only with the
// cell's affine strain). The contacts kept are those with at least one grain in the window,
// in the order of `step.system.contacts`; a contact with a clamped grain acts on the window's
// grain alone. The pressure row is kept over the kept contacts with the window's share of the
// bath's load, 2 V P_ext times the static network's virial over the kept contacts against its
// virial over all: so the static network f0 still solves the unshifted window, the prestress
// keeps its level (without the row, c f0 would balance the window's grains for every c), and
// a window that covers the cell is the whole step. Every method of the whole step applies to
// it; F_crit is that of the clamped window, not of the packing.
CdStepProblem window_step(const CdStepProblem& step, const Packing& packing, double radius);

// How far forces f are from solving the step: step_residual with displacements in units of g.
using CdStepResidual = StepResidual;
inline CdStepResidual cd_step_residual(const CdStepProblem& problem, const Eigen::VectorXd& f) {
  return step_residual(problem, f, problem.g);
}

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
// settings.cancel is polled between Lemke's paths only (a path is not interrupted).
inline constexpr int kMaxLemkeContacts = 1200;
inline constexpr int kLemkeRetries = 4;
CdStepSolution probe_cd_lemke(const Packing& packing, int contact, const ProbeSettings& settings);

// F_crit (the probed contact's fn), the field q and the residual of forces f of the step;
// f empty: a probe without a solution (residual kNoSolution).
ProbeResult cd_step_result(const CdStepProblem& problem, const Packing& packing,
                           const ProbeSettings& settings, const Eigen::VectorXd& f);

// A contact's state in a step's solution f, read with the tolerance of the exactness verdict
// (kExactStepTolerance, in F0 and in g): open where fn <= tol F0, sliding where it carries a
// force and slips, |u_t| > tol g, sticking otherwise (docs/probe.md, "Which contacts the step
// opens and sets sliding"). The probed contact is loaded by F_crit and its state is stick or
// slide like any other's.
enum class StepState : std::int8_t { open, stick, slide };
const char* step_state_name(StepState state);
std::vector<StepState> step_states(const CdStepProblem& problem, const Eigen::VectorXd& f);

// What a step's solution (its step_states) changes against the static network, over every
// contact but the probed one: `loaded` contacts carry a force in the packing (fn > tol F0, tol
// as above); of them `opened` are open in the step, `sliding` slide; of the `unloaded` others
// `closed` carry a force in the step.
struct StepStateChanges {
  int loaded = 0, opened = 0, sliding = 0, unloaded = 0, closed = 0;
};
StepStateChanges step_state_changes(const CdStepProblem& problem, const Packing& packing,
                                    const std::vector<StepState>& states);

// The forces of a probe as a table (every contact of the step, in its order): contact, a, b;
// fn0, the static network's normal force (the packing's); fn, ft, the step's forces; un, ut,
// the step's displacements u = A^T q + g_eff in units of g (un: the pair's gap after the step
// as Signorini reads it, 0 where closed; the probed pair's is its opening minus g, 0); state,
// as step_states.
std::string step_forces_csv(const CdStepProblem& problem, const Packing& packing,
                            const Eigen::VectorXd& f);

}  // namespace unjam
