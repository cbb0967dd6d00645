#pragma once
// The time of a campaign made over several runs (stopped and resumed): `unjam probe` and
// `unjam bounds` record it in their checkpoints and outputs.
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/work_source.hpp"

namespace unjam {

// The time a campaign's tasks (probes, LPs) took over the runs that made them (docs/probe.md,
// "Campaigns"), as its checkpoint records it ("runs"): how many runs, their wall time and their
// busy seconds (RankLoad::busy_seconds summed over ranks), each run counted to its last save
// (a run killed without its final save, to its last periodic one). untimed: tasks of a
// checkpoint that did not record it (written before it was, or with the record damaged).
struct CampaignTime {
  int runs = 0;
  double wall_seconds = 0.0;
  double busy_seconds = 0.0;
  long long untimed = 0;
};
CampaignTime operator+(const CampaignTime& a, const CampaignTime& b);
// One run so far: `wall` seconds since it started and its ranks' busy seconds (their loads as
// the distributor has them).
CampaignTime one_run(double wall, const std::vector<RankLoad>& loads);
nlohmann::json to_json(const CampaignTime& t);
// The seconds left (-1: unknown) for `remaining` tasks at the busy seconds per task of every
// run so far (`so_far`, over the `done` tasks it holds, its untimed ones left out) on `workers`
// threads: so a resumed campaign's first ETA is its earlier runs' pace, not that of the one or
// two tasks this run has finished. Unknown before any timed task.
double campaign_eta(const CampaignTime& so_far, long long done, long long remaining, int workers);
// A record as to_json writes it (a checkpoint's "runs", a summary's or shard's "all_runs") of
// a campaign of `tasks` tasks; a missing (null) or invalid one leaves them all untimed. Never
// throws: the record is not part of a checkpoint's state.
CampaignTime campaign_time_from_json(const nlohmann::json& record, long long tasks);

}  // namespace unjam
