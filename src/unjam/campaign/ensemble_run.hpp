#pragma once
// One packing's ensemble of admissible force networks (docs/ensemble.md; `unjam ensemble`):
// the exact LP interval [fn_min, fn_max] of every contact of the admissible set, the
// per-contact statistics of the samplers (hit-and-run, uniform on the admissible polytope;
// the paper's random walk of kicks relaxed by the static solve) and the critical force F_crit
// of every force-carrying contact, probed over the threads by probe/probe_campaign's loop
// (probe_contacts). Above ensemble/ and probe/, below the tool.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/quantile.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/ensemble/hit_and_run.hpp"
#include "unjam/ensemble/random_walk.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/probe_campaign.hpp"
#include "unjam/probe/probe_result.hpp"

namespace unjam {

struct EnsembleSettings {
  bool hit_and_run = true, walk = true;  // the samplers to run
  // a probe method's name (probe/probe_campaign: method_from_name) or none; empty: cd up to
  // 200 contacts, else lp. cd: the exact step from the static network (probe/cd_path,
  // docs/probe.md), the paper's probe without NLGS's sweeps (1.3 s for the 81 contacts of
  // the 50-disk fixture, where NLGS takes minutes).
  std::string probe;
  int samples = 20000;            // networks per sampler (walk: steps)
  std::uint64_t seed = 1;         // of both samplers
  int thin = 0, burn_in = 0;      // hit-and-run (HitAndRunOptions)
  double kick = 1.0;              // walk kick amplitude / <F_n>
  double walk_tol = 1e-10;        // walk relaxation residual / F0
  double probe_g = 1e-9;          // probe opening (R_max)
  // Probe time step (t0); 0: the method's own default, default_probe_dt (nlgs 1e-3, cd the
  // quasi-static sqrt(g / kQuasiStaticInertia)).
  double probe_dt = 0.0;
  double probe_velocity_tol = 1e-6;  // nlgs probe: max |dU| per sweep < this g / dt
  // The cd probe's settings, its start included (`--cd-*`, probe/cd_path.hpp; docs/probe.md);
  // other than the defaults only with the cd probe (validate(CampaignSettings) refuses them else).
  CdPathSettings probe_cd;
  double gap_tol = 1e-9;          // admissible set: touching, gap < gap_tol (R_max) ...
  double fn_tol = 1e-9;           // ... or force-carrying, fn > fn_tol F0
  // The LP intervals' tolerances, ForceBoundsOptions::tolerance and ::open_tol_F0 (F0), with
  // their ranges (lp/force_lp.hpp, ensemble/force_bounds.hpp; docs/ensemble.md, "The LP's
  // tolerances"); the samplers and F_crit's place t read those intervals, and the lp probe's
  // LP takes lp_tol too.
  double lp_tol = ForceBoundsOptions{}.tolerance;
  double open_tol = ForceBoundsOptions{}.open_tol_F0;
  int threads = 0;                // LP bounds and probes; 0: omp_get_max_threads()
  std::function<void(const ForceNetwork&)> on_sample;  // every hit-and-run sample; may be empty
  // Polled by the LPs (ForceBoundsOptions::should_stop), after every sample of either sampler
  // and by the probes (CampaignSettings' cancel, before and inside each); true: compute_ensemble
  // throws Cancelled (nothing is kept). May be empty.
  std::function<bool()> should_stop;
  // (what, done, total) as the walk and the probes go on; may be empty.
  std::function<void(const std::string&, int, int)> progress;
};

// Per-contact statistics of one sampler, and its mean sampled width / LP width.
struct SamplerReport {
  Eigen::VectorXd min, max, mean, std;  // per contact of the system
  double coverage = 0.0;  // mean over contacts with LP width > 1e-9 F0 of sampled / LP width
  double seconds = 0.0;
};

struct EnsembleReport {
  EquilibriumSystem system;           // the admissible set
  ForceBounds bounds;                 // per contact of the system
  std::optional<HitAndRunResult> hit_and_run;
  std::optional<RandomWalkResult> walk;
  std::optional<SamplerReport> hr_columns, walk_columns;
  std::string probe;                  // the probe method used: nlgs, lp, cd or none
  std::optional<CampaignSettings> probe_settings;  // its settings (ensemble_probe_settings); none: empty
  double probe_dt = 0.0;              // the time step the probes used (t0; lp: none, 0)
  std::vector<std::optional<ProbeResult>> probes;  // per contact of the system (force-carrying)
  std::vector<double> f_crit_over_fn_max;          // over the probed contacts, in system order
  // t = (F_crit - fn_min) / (fn_max - fn_min), F_crit's place in the contact's interval (1: its
  // top, the paper's finding), over the probed contacts whose interval is wider than 1e-6 F0
  // (docs/probe.md, "Where F_crit lies in the admissible interval").
  std::vector<double> f_crit_position;
  int below_f_cont = 0;               // probes with F_crit < f_cont
  int unconverged = 0;                // probes that did not converge
  double probe_seconds = 0.0;
};

// The model that selects the ensemble's admissible set: the packing's own (meta.contact) with
// touch_gap = settings.gap_tol. The set is admissible_system(packing, this model,
// settings.fn_tol) (contact/contact_problem.hpp).
ContactModel ensemble_contact_model(const Packing& packing, const EnsembleSettings& settings);

// Every part of the ensemble of `packing` with `settings`. Throws unjam::Error as the
// samplers and probes do (the probes' errors name the contact), and for an unknown probe
// name or LP tolerances out of their ranges (check_force_bounds_options) before any LP.
EnsembleReport compute_ensemble(const Packing& packing, const EnsembleSettings& settings);

// The probe method compute_ensemble runs: settings.probe, or where it is empty cd up to 200
// contacts of the admissible set, else lp.
std::string ensemble_probe_method(const Packing& packing, const EnsembleSettings& settings);

// The probes' settings: the packing's own contact model (touch gap and bath mass from its
// metadata, as `unjam probe` takes them: campaign_settings_for) with the ensemble's opening
// g, time step (0: the method's default_probe_dt), NLGS tolerance, cd settings (probe_cd) and,
// for lp, LP tolerance (lp_tol), and `method` (a name of method_from_name); validated
// (validate(CampaignSettings): throws unjam::Error naming a setting that does not apply).
CampaignSettings ensemble_probe_settings(const Packing& packing, const EnsembleSettings& settings,
                                         const std::string& method);

// F_crit / fn_max over the probed contacts (EnsembleReport::f_crit_over_fn_max): its min,
// median and max (quantile), and how many ratios lie within 1, 2 and 5 % of 1 (|x - 1| <= f).
struct CriticalForceRatio {
  double min = 0.0, median = 0.0, max = 0.0;
  int within_1_percent = 0, within_2_percent = 0, within_5_percent = 0;
};
CriticalForceRatio critical_force_ratio(const std::vector<double>& ratio);  // ratio non-empty

// ensemble.json's "methods" (docs/ensemble.md): per sampler run, its eta = <dF>/<|F|>, mean fn,
// mean sampled / LP width and counts, with the settings that made it.
nlohmann::ordered_json ensemble_methods_json(const EnsembleSettings& settings, const EnsembleReport& report);
// ensemble.json's "probe": the method and, if one ran, its settings, F_crit / fn_max
// (critical_force_ratio), F_crit's place t in its interval and the time.
nlohmann::ordered_json ensemble_probe_json(const EnsembleSettings& settings, const EnsembleReport& report);
// ensemble.json's "parameters": the admissible set's gap_tol and fn_tol_F0 and the LP's
// lp_tolerance and open_tol_F0.
nlohmann::ordered_json ensemble_parameters_json(const EnsembleSettings& settings);

}  // namespace unjam
