#pragma once
// Probing every contact of a packing, one by one, always from the same static packing
// (docs/probe.md, "The probe"; the averages: docs/analysis.md): the probes run in parallel (one
// probe per thread at a time), the per-grain displacement fields go straight into the averages
// (mean field in the contact frame and d(r)), and only one row per probe is kept. A campaign
// can stop and resume: its state (rows and averages) is saved as JSON and finished probes are
// skipped.
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/analysis/power_law_fit.hpp"
#include "unjam/analysis/response_average.hpp"
#include "unjam/core/campaign_time.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/kinematic_probe.hpp"
#include "unjam/probe/nlgs_probe.hpp"

namespace unjam {

enum class ProbeMethod {
  kLp,    // F_crit = LP maximum, field = kinematic problem at the optimum (fast)
  kNlgs,  // the paper's contact-dynamics probe (reference, slow)
  kLemke, // the same step solved exactly by Lemke's method (dense: small packings)
  kCd,    // the same step followed exactly from the static network (sparse: probe/cd_path)
};

// "static", "lp", "compliant", "interior", "inertial", "interior-inertial"; cd_start_from_name throws unjam::Error for any other name.
const char* cd_start_name(CdPathStart start);
CdPathStart cd_start_from_name(const std::string& name);

// "lp", "nlgs", "lemke", "cd"; method_from_name throws unjam::Error for any other name.
const char* method_name(ProbeMethod method);
ProbeMethod method_from_name(const std::string& name);

// The quasi-static limit of the probe step (docs/probe.md, "The quasi-static limit"). The
// step depends on g and dt only through g / dt^2 (R_max / t0^2), the size of its inertial
// term m g / dt^2; at g / dt^2 = kQuasiStaticInertia F_crit lies within ~0.2 % of its limit
// g / dt^2 -> 0 and u / g within ~3e-5 (500 disks, mu = 0, 0.1, 1), against 5-17 % and up
// to 55 % at the nlgs default (g = 1e-9, dt = 1e-3: g / dt^2 = 1e-3).
inline constexpr double kQuasiStaticInertia = 1e-5;

// The probe's time step where none is given: for the exact methods (lemke, cd) the one that
// puts g / dt^2 at kQuasiStaticInertia, dt = sqrt(g / kQuasiStaticInertia) (1e-2 at
// g = 1e-9); for nlgs ProbeSettings::dt (1e-3: its sweeps converge at a small dt only); lp
// has no time step (the same value as nlgs, unused).
double default_probe_dt(ProbeMethod method, double g);

struct CampaignSettings {
  ProbeMethod method = ProbeMethod::kLp;
  ProbeSettings nlgs;                   // g, dt, tolerances, model of the NLGS, Lemke, cd probes
  KinematicProbeSettings kinematic;     // g, LP and state tolerances, model of the fast probe
  CdPathSettings cd;                    // the cd method's path (where it starts, compliance)
  bool total_displacement = false;      // averages with the affine part lambda dt (r - r_c)
  double force_threshold = 1e-9;        // probe contacts with fn > threshold F0
  // > 0 (nlgs, lemke, cd): a probe whose f_inertia exceeds max_inertia F0 (a region that
  // slides away against its inertia: no quasi-static field) keeps its row but stays out of
  // the averages and the means (enters_averages; docs/probe.md, "The inertia of the step").
  double max_inertia = 0.0;
  int sample = 0;                       // > 0: a random subset of this many contacts
  std::uint64_t seed = 1;               // of the subset
};

// One probed contact (forces in simulation units, as contacts.csv).
struct ProbeRow {
  int contact = -1, a = -1, b = -1;
  double f_cont = 0.0, f_crit = 0.0;
  bool converged = false;
  long long sweeps = 0;
  double residual = 0.0;
  int violations = 0;
  double lambda_dt = 0.0;
  double f_inertia = std::numeric_limits<double>::quiet_NaN();  // ProbeResult::f_inertia (NaN: lp, no
                                                                // solution, or an older checkpoint)
  int opened = -1, sliding = -1;  // ProbeResult::opened, sliding (-1: lp, nlgs, no solution, or an
                                  // older checkpoint)
  // ProbeResult::cpu_seconds (NaN: not measured, or from a checkpoint that did not record it).
  // Not part of the state: to_json(CampaignState) leaves it out; the checkpoint keeps it
  // beside the time of the runs (campaign_checkpoint_text, probe_cpu_json).
  double cpu_seconds = std::numeric_limits<double>::quiet_NaN();
};

struct CampaignState {
  std::vector<ProbeRow> rows;  // sorted by contact
  ResponseAverage average;
  explicit CampaignState(const ResponseGrid& grid) : average(grid) {}
};

// The default interval of the running probes' line (CampaignHooks::running, probe
// --running-every), in seconds.
inline constexpr double kRunningEverySeconds = 300.0;

// Whether a probe of this method polls its interrupt (ProbeSettings::cancel) while it runs:
// nlgs, lemke and cd do; an lp probe does not, so it can neither be abandoned nor report that
// it is running.
inline bool probe_polls(ProbeMethod method) { return method != ProbeMethod::kLp; }

struct CampaignHooks {
  std::function<void(int done, int total)> progress;  // after every gathered probe
  std::function<void(const CampaignState&)> checkpoint;  // after every gathered probe
  std::function<bool()> should_stop;
  // Polled by the running probes (ProbeSettings::cancel: nlgs, lemke and cd) from their
  // threads, so it must be thread safe; once it returns true they are abandoned (no row,
  // computed again when the campaign resumes) and no more are handed out. May be empty.
  std::function<bool()> cancel;
  // A sign of life of long probes: called from a running probe's thread (nlgs, lemke and cd,
  // where they poll cancel) each time another `running_every_s` seconds of it have passed,
  // with its contact, its seconds so far (wall time) and its polls so far (cd: one before
  // every piece of every path; nlgs: one per 16 sweeps). Thread safe; may be empty.
  std::function<void(int contact, double seconds, long long polls)> running;
  double running_every_s = kRunningEverySeconds;
};

// s with its probes' interrupt poll (s.nlgs.cancel, which it keeps calling) also calling
// `running(k, seconds, polls)` (CampaignHooks::running) each time another `every` seconds of
// the probe of contact k have passed; every = 0 calls it at every poll. s as it is where
// `running` is empty or the method does not poll (probe_polls). For one probe run outside a
// campaign (`unjam probe --contact K`); the campaigns wrap their probes so. Throws
// unjam::Error for every < 0 or NaN.
CampaignSettings with_running(const CampaignSettings& s, int k,
                              const std::function<void(int contact, double seconds, long long polls)>& running,
                              double every);

struct CampaignSummary {
  int probes = 0;
  int not_converged = 0;             // with the probes that found no solution (not in the means)
  int without_solution = 0;          // of them, those with no solution (residual kNoSolution)
  int inertial = 0;                  // solved, left out for f_inertia > max_inertia F0
  double F_cont_over_F0 = 0.0;       // <F_cont> / F0 over the probes that enter the averages
  double F_crit_over_F_cont = 0.0;   // <F_crit> / <F_cont>
  // Its standard error over the sampled contacts (n >= 2 probes in the averages; NaN below):
  // the delta method for a ratio of means, R = sum f_crit / sum f_cont,
  //   SE = sqrt(sum e^2 / (n (n - 1))) / (sum f_cont / n),  e = f_crit - R f_cont
  // (docs/probe.md, "Campaigns"). Another sample of contacts of the same packing; another
  // packing may differ by more.
  double F_crit_over_F_cont_err = std::numeric_limits<double>::quiet_NaN();
  // ProbeRow::f_inertia / F0 over the probes that have it (none for lp): how many, the
  // median, the largest and its contact (-1 if none).
  int inertia_probes = 0;
  double f_inertia_median_over_F0 = 0.0, f_inertia_max_over_F0 = 0.0;
  int f_inertia_max_contact = -1;
  // ProbeRow::opened and sliding over the probes that have them (lemke, cd): how many, and
  // their medians.
  int state_probes = 0;
  double opened_median = 0.0, sliding_median = 0.0;
  bool has_fit = false;
  PowerLawFit fit;
  std::string fit_error;             // why there is no fit (e.g. cell too small)
};

// The settings `unjam probe` starts from: the defaults, with nlgs.model = kinematic.model =
// packing.meta.contact (mu, P_ext, the touch gap of its static solve, its bath mass M_lambda).
// Throws unjam::Error for recorded settings (meta.settings) of the wrong type or range.
CampaignSettings campaign_settings_for(const Packing& packing);

// Throws unjam::Error unless g, dt and velocity_tol are positive and finite and max_inertia is
// finite and >= 0, for a cd start other than the static network with a method other than cd,
// and for max_inertia > 0 with lp (which has no time step).
void validate(const CampaignSettings& settings);
// The range checks of the cd method's own settings (those `unjam probe --cd-*` sets), which do
// not depend on the method or start: validate(CampaignSettings) makes them too, and the
// Python module's unjam.CdSettings on every assignment. Throws unjam::Error naming the option.
void validate(const CdPathSettings& cd);

// The one rule for which probes enter a campaign's averages and means: those with a solution
// and, where max_inertia (CampaignSettings::max_inertia) > 0, with f_inertia at most
// max_inertia F0 (f0: the packing's F0; a row without f_inertia, NaN, enters).
bool enters_averages(const ProbeRow& row, double max_inertia, double f0);

// The contacts a campaign probes: force-carrying ones, or a seeded subset of them.
std::vector<int> campaign_targets(const Packing& packing, const CampaignSettings& settings);

// The contacts of shard `shard` of `shards` (`--shard i/K`) among `targets` (campaign_targets):
// those at places p with p mod K == i (core/work_source's in_shard), so the K shards probe
// the targets evenly, a sample as well as all. Sorted, as `targets` is.
std::vector<int> shard_targets(const std::vector<int>& targets, int shard, int shards);

// Probes every target not yet in `state`; returns false if should_stop or cancel ended it
// early (a cancelled probe leaves no row in `state`).
bool run_campaign(const Packing& packing, const CampaignSettings& settings, CampaignState& state,
                  const CampaignHooks& hooks = {});

// The same over the processes of `distributor` (core/work_source.hpp): every process probes
// the contacts handed to it, one per thread at a time; `state` and the hooks are those of the
// gathering process (rank 0), which receives every probe's row and field and keeps `state`
// exactly as one process would (rows sorted by contact, fixed-point averages). Elsewhere
// `state` stays as it is and the return value is meaningless.
bool run_campaign(const Packing& packing, const CampaignSettings& settings, CampaignState& state,
                  const CampaignHooks& hooks, WorkDistributor& distributor);

// Probes one contact with the campaign's method (throws Cancelled once settings.nlgs.cancel
// returns true).
ProbeResult probe_contact(const Packing& packing, const CampaignSettings& settings, int contact);

// One finished probe of probe_contacts.
struct FinishedProbe {
  int index = 0;  // position in `contacts`
  const ProbeResult* result = nullptr;
  int done = 0;   // probes finished so far, this one included
  int total = 0;  // contacts.size()
};

struct ProbeListHooks {
  // Polled before every probe is handed out; may be empty.
  std::function<bool()> should_stop;
  // Called once per finished probe, as results arrive (in the order they finish, which
  // depends on the thread count), one call at a time, from whichever thread gathers it; may
  // be empty.
  std::function<void(const FinishedProbe&)> progress;
  // A sign of life of long probes, as CampaignHooks::running (from the probe's thread, with
  // its contact, seconds and polls so far, every running_every_s seconds of it); may be empty.
  std::function<void(int contact, double seconds, long long polls)> running;
  double running_every_s = kRunningEverySeconds;
};

// Probes every contact of `contacts` (indices into packing.contacts, any order, repeats
// allowed) with the campaign's method, on omp_get_max_threads() threads as run_campaign does
// (one probe per thread at a time; each thread keeps its LP model): the results in the order
// of `contacts`, the same bytes for any thread count. hooks.should_stop and
// settings.nlgs.cancel (may be empty, thread safe) are polled before every probe is handed
// out, and the cancel by the running probes too, which it abandons. Once either returns true,
// the results of the probes finished before the first one not finished (a prefix of
// `contacts`) are returned. Throws unjam::Error for an index out of range or a negative
// running_every_s, and the first error of a probe (naming its contact).
std::vector<ProbeResult> probe_contacts(const Packing& packing, const CampaignSettings& settings,
                                        const std::vector<int>& contacts, const ProbeListHooks& hooks = {});

// The cd probes of `state` stopped by a budget of max_pieces pieces per probe
// (CdPathSettings::max_probe_pieces; their sweeps are max_pieces + 1), and those of them that
// are exact all the same (an exact solution met before the budget ended a lowering that went
// on: docs/probe.md, "Settling at an exact solution"); 0 where max_pieces <= 0.
struct OverBudget {
  int probes = 0;
  int exact = 0;
};
OverBudget probes_over_budget(const CampaignState& state, long long max_pieces);

// The cd probes of `state` that are near-exact within accept_residual (CdPathSettings::
// accept_residual, in g: not converged, residual at most it); 0 where it is the default.
int probes_accepted(const CampaignState& state, double accept_residual);

// The CPU the probes of `rows` took (ProbeRow::cpu_seconds; docs/probe.md, "Campaigns"):
// over the rows that record it, how many, the total, the median, the 90th percentile and the
// largest with its contact (-1 if none); and the medians of the exact probes (converged), the
// near-exact ones (a solution, not converged) and those without a solution (0 where none).
// Measured per probe on its own thread, so it does not depend on the other threads' load as
// a campaign's wall or busy time does; still a measurement, never a result.
struct ProbeCpu {
  int timed = 0;
  double total = 0.0, median = 0.0, p90 = 0.0, max = 0.0;
  int max_contact = -1;
  int exact = 0, near_exact = 0, no_solution = 0;  // timed probes of each kind
  double exact_median = 0.0, near_exact_median = 0.0, no_solution_median = 0.0;
};
ProbeCpu probe_cpu(const std::vector<ProbeRow>& rows);
nlohmann::json to_json(const ProbeCpu& cpu);

// The per-probe CPU of `state` as a checkpoint or shard keeps it ("probe_cpu"): [[contact,
// seconds], ...] over the rows that record it, in contact order.
nlohmann::json probe_cpu_json(const CampaignState& state);
// Sets the rows' cpu_seconds from such a record (rows of contacts it does not list: NaN).
// Never throws: a missing or damaged record (not an array, an entry that is not [integer,
// number >= 0]) leaves the rows it cannot read unmeasured, as the time of the runs is read
// (campaign_time_from_json); it is not part of the state.
void set_probe_cpu(CampaignState& state, const nlohmann::json& record);

// The fit of d(r) uses `window`, or default_fit_window (analysis/power_law_fit.hpp) if empty.
// The means take the probes that enter_averages with max_inertia (the campaign's setting).
CampaignSummary summarize(const Packing& packing, const CampaignState& state,
                          std::optional<FitWindow> window = std::nullopt, double max_inertia = 0.0,
                          int bootstrap_samples = 200, std::uint64_t seed = 1);

// The settings of a campaign (touch_gap and M_lambda: those of the method's contact model).
// Throws unjam::Error if that model is not set.
nlohmann::json to_json(const CampaignSettings& settings);
nlohmann::json to_json(const CampaignState& state);

// The settings a campaign on `packing` was run with, read back from their record (to_json above:
// the "settings" of probe_summary.json and of probe_checkpoint.json): its inverse. What the
// record leaves out is what to_json leaves out: the contact model and the tolerances the record
// does not name come from campaign_settings_for(packing), a cd setting absent from the record
// takes the value at which to_json omits it (e.g. cd_softer_starts 0, cd_compliant_start 0.1,
// cd_interior_iterations 40), a setting that does not apply to the method or start keeps its
// default. Throws unjam::Error naming `name` for a key to_json does not write, a value of the
// wrong type or out of range (validate), or a record that to_json of the result does not
// reproduce exactly (e.g. the touch_gap or M_lambda of another packing's contact model).
CampaignSettings campaign_settings_from_json(const nlohmann::json& j, const Packing& packing,
                                             const std::string& name = "the campaign's settings");

// A state saved from `packing` (to_json): throws unjam::Error unless it is one run_campaign
// could have made on it: the averages on the packing's grid
// (ResponseGrid::for_cell(cell, 2 <R>)), rows in strictly increasing contact order with the
// packing's grains a-b, probe ids of the averages among the rows' contacts.
CampaignState campaign_state_from_json(const nlohmann::json& j, const Packing& packing);

// A probe checkpoint as `unjam probe --all` saves it: the packing's fingerprint
// (packing_fingerprint, passed in as computing it costs O(N)), the settings (to_json), the state and the FNV-1a hash of its dump.
// `runs`, if given, is stored beside them as "runs": the time the runs so far took
// (CampaignTime, core/campaign_time), with each probe's CPU as "probe_cpu" (probe_cpu_json);
// both are outside the hashed state.
std::string campaign_checkpoint_text(const std::string& fingerprint, const nlohmann::json& settings,
                                     const CampaignState& state, const CampaignTime* runs = nullptr);

// The state of a checkpoint's text, if it was saved from `packing` (nullopt if from another
// packing, or without a fingerprint). Throws unjam::Error (naming `name`) if the text is not a
// JSON object, the settings differ, the state does not match its hash, or the state does not
// fit the packing (campaign_state_from_json). `runs` (may be null): set to the time of the
// runs that made the state, from the same parse (campaign_time_from_json of its "runs"). The
// rows' cpu_seconds are read from its "probe_cpu" (set_probe_cpu), whether or not `runs` is given.
std::optional<CampaignState> read_campaign_checkpoint(const std::string& text, const std::string& name,
                                                      const Packing& packing, const nlohmann::json& settings,
                                                      CampaignTime* runs = nullptr);

}  // namespace unjam
