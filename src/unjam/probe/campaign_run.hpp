#pragma once
// One run of a campaign as `unjam probe --all` / `--sample` makes it (docs/probe.md,
// "Campaigns"). On the gathering process its state is saved to a checkpoint file every few
// seconds and when it stops, and a later run with the same packing and settings resumes from
// that file; at the end its summary goes into probe_summary.json.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/analysis/packing_stats.hpp"
#include "unjam/core/campaign_time.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam {

// A campaign's state before any probe: no rows, averages on the packing's grid
// (ResponseGrid::for_cell(cell, 2 <R>)).
CampaignState empty_campaign_state(const Packing& packing);

struct SavedCampaign {
  std::optional<CampaignState> state;  // the saved state, if the file belongs to this run
  std::filesystem::path set_aside;     // where a checkpoint of another packing went; empty if none
  CampaignTime time;                   // of the runs that made `state` (empty if none)
};

// The state saved in `checkpoint`, if it exists and was saved from this packing (its
// fingerprint) with these settings (read_campaign_checkpoint). One saved from another packing
// (or by a version that did not record it) is renamed to `checkpoint`.stale: its probes do not
// belong to this packing. Throws unjam::Error as read_campaign_checkpoint does.
SavedCampaign load_campaign_checkpoint(const std::filesystem::path& checkpoint, const Packing& packing,
                                       const nlohmann::json& settings);

struct CheckpointedCampaignOptions {
  std::filesystem::path checkpoint;   // the file the state is saved to
  nlohmann::json settings;            // to_json(CampaignSettings), recorded in the checkpoint
  std::string fingerprint;            // packing_fingerprint of the packing
  double checkpoint_s = 30.0;         // seconds between checkpoints
  int stop_after = 0;                 // > 0: stop after this many new probes
  // Stops the run, abandons the running probes (CampaignHooks::cancel: polled from the
  // probes' threads, so thread safe) and forces a checkpoint; may be empty.
  std::function<bool()> interrupted;
  // After every gathered probe: (done, total, elapsed s, ETA s; -1 unknown). May be empty.
  std::function<void(int, int, double, double)> progress;
  // CampaignHooks::running and its interval: a sign of life of long probes. May be empty.
  std::function<void(int contact, double seconds, long long polls)> running;
  double running_every_s = kRunningEverySeconds;
  CampaignTime earlier;  // of the runs before this one (SavedCampaign::time)
};

struct CheckpointedCampaignResult {
  bool finished = false;  // false: stopped, the state saved to the checkpoint
  double wall_s = 0.0;
  CampaignTime time;  // options.earlier and this run
};

// Probes every target not yet in `state` (run_campaign over `distributor`), saving the state
// to options.checkpoint at most every checkpoint_s seconds (and at every probe once
// interrupted), and once more if it stops early: the finished probes only, those abandoned
// on an interrupt are probed again on resume. Each save records the time of the runs so far
// (options.earlier and this run: its wall time and the distributor's busy seconds, read at
// the save). The checkpoint is left in place: remove it once the outputs are written.
CheckpointedCampaignResult run_checkpointed_campaign(const Packing& packing,
                                                     const CampaignSettings& settings,
                                                     CampaignState& state,
                                                     WorkDistributor& distributor,
                                                     const CheckpointedCampaignOptions& options);

// The measurements of probe_summary.json: the packing (seed, N, mu, phi, z, F0 in simulation
// units), the probes (count, not converged, of them without a solution, <F_cont> / F0,
// <F_crit> / <F_cont> over the probes with one) and the fit of
// d(r) ~ r^-alpha (alpha, alpha_err and the fit's window, bins, R2, log_A and bootstrap
// samples), or fit_error when there is none.
nlohmann::json campaign_summary_json(const Packing& packing, const PackingStats& stats,
                                     const CampaignSummary& summary);

}  // namespace unjam
