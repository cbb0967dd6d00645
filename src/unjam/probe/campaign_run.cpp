#include "unjam/probe/campaign_run.hpp"

#include <chrono>
#include <cmath>

#include "unjam/core/atomic_file.hpp"

namespace unjam {

CampaignState empty_campaign_state(const Packing& packing) {
  return CampaignState(ResponseGrid::for_cell(packing.cell, 2.0 * packing.mean_radius()));
}

SavedCampaign load_campaign_checkpoint(const std::filesystem::path& checkpoint, const Packing& packing,
                                       const nlohmann::json& settings) {
  SavedCampaign saved;
  if (!std::filesystem::exists(checkpoint)) return saved;
  saved.state = read_campaign_checkpoint(read_file(checkpoint), checkpoint.string(), packing, settings, &saved.time);
  if (saved.state) return saved;
  saved.set_aside = checkpoint.string() + ".stale";
  rename_file(checkpoint, saved.set_aside);
  return saved;
}

CheckpointedCampaignResult run_checkpointed_campaign(const Packing& packing,
                                                     const CampaignSettings& settings,
                                                     CampaignState& state,
                                                     WorkDistributor& distributor,
                                                     const CheckpointedCampaignOptions& options) {
  using clock = std::chrono::steady_clock;
  const auto seconds = [](clock::time_point from) {
    return std::chrono::duration<double>(clock::now() - from).count();
  };
  const auto interrupted = [&] { return options.interrupted && options.interrupted(); };
  const auto t0 = clock::now();
  auto last_checkpoint = t0;
  const std::size_t done_before = state.rows.size();
  // The runs' time so far: the earlier runs' and this one's (its busy seconds as the
  // distributor has them: within the gathering, where every rank's load is updated).
  const auto time_so_far = [&] { return options.earlier + one_run(seconds(t0), distributor.loads()); };
  const auto save = [&](const CampaignState& st, const CampaignTime& runs) {
    write_file_atomic(options.checkpoint, campaign_checkpoint_text(options.fingerprint, options.settings, st, &runs));
  };
  CampaignHooks hooks;
  if (options.progress)
    hooks.progress = [&](int done, int all) {  // within the gathering, as the checkpoint hook
      int workers = 0;
      for (const RankLoad& l : distributor.loads()) workers += l.threads;
      options.progress(done, all, seconds(t0), campaign_eta(time_so_far(), done, all - done, workers));
    };
  hooks.checkpoint = [&](const CampaignState& st) {
    if (seconds(last_checkpoint) < options.checkpoint_s && !interrupted()) return;
    last_checkpoint = clock::now();
    save(st, time_so_far());
  };
  hooks.cancel = options.interrupted;
  hooks.running = options.running;
  hooks.running_every_s = options.running_every_s;
  hooks.should_stop = [&] {
    return interrupted() ||
           (options.stop_after > 0 && state.rows.size() >= done_before + options.stop_after);
  };
  CheckpointedCampaignResult result;
  result.finished = run_campaign(packing, settings, state, hooks, distributor);
  result.wall_s = seconds(t0);
  result.time = time_so_far();
  if (!result.finished) save(state, result.time);
  return result;
}

nlohmann::json campaign_summary_json(const Packing& p, const PackingStats& stats,
                                     const CampaignSummary& sum) {
  nlohmann::json j = {
      {"seed", p.meta.seed},
      {"N", p.size()},
      {"mu", p.meta.contact.mu},
      {"phi", stats.phi},
      {"z", stats.z},
      {"F0", p.force_unit()},
      {"probes", sum.probes},
      {"not_converged", sum.not_converged},
      {"without_solution", sum.without_solution},
      {"inertial", sum.inertial},
      {"F_cont_over_F0", sum.F_cont_over_F0},
      {"F_crit_over_F_cont", sum.F_crit_over_F_cont},
  };
  if (std::isfinite(sum.F_crit_over_F_cont_err)) j["F_crit_over_F_cont_err"] = sum.F_crit_over_F_cont_err;
  if (sum.inertia_probes > 0)
    j["f_inertia_over_F0"] = {{"probes", sum.inertia_probes},
                              {"median", sum.f_inertia_median_over_F0},
                              {"max", sum.f_inertia_max_over_F0},
                              {"max_contact", sum.f_inertia_max_contact}};
  if (sum.state_probes > 0)
    j["step_states"] = {{"probes", sum.state_probes},
                        {"opened_median", sum.opened_median},
                        {"sliding_median", sum.sliding_median}};
  if (sum.has_fit) {
    j["alpha"] = sum.fit.alpha;
    j["alpha_err"] = sum.fit.alpha_err;
    j["fit"] = {{"r_lo", sum.fit.r_lo}, {"r_hi", sum.fit.r_hi}, {"bins", sum.fit.bins},
                {"R2", sum.fit.R2}, {"log_A", sum.fit.log_A},
                {"bootstrap_samples", sum.fit.bootstrap_samples}};
  } else {
    j["fit_error"] = sum.fit_error;
  }
  return j;
}

}  // namespace unjam
