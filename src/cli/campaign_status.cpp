// `unjam merge DIR --out D --status`: how far the probe campaign in D has got, whole or as the
// shards of a job array, read from its files alone (README, "On a cluster").
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cli/run_info.hpp"
#include "cli/shards.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/campaign_time.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam::cli {

namespace fs = std::filesystem;

namespace {

// One job's files: its finished shard (or, for a whole campaign, nothing: its outputs are the
// campaign's), its checkpoint.
struct JobFiles {
  std::optional<fs::path> finished, checkpoint;
};

// Where one job stands.
struct JobStatus {
  enum class Kind { kNotStarted, kStarted, kFinished, kUnreadable } kind = Kind::kNotStarted;
  int done = 0;
  CampaignTime runs;
  double saved_ago_s = 0.0;  // the checkpoint's age
  std::string why;           // kUnreadable: the reason
};

double age_seconds(const fs::path& file) {
  return std::chrono::duration<double>(fs::file_time_type::clock::now() - fs::last_write_time(file)).count();
}

// The JSON object of `file`; throws unjam::Error if it is not one.
nlohmann::json read_object(const fs::path& file) {
  auto j = nlohmann::json::parse(read_file(file), nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw Error("not a JSON object");
  return j;
}

// The settings a job's file records (both kinds keep them under "settings").
nlohmann::json recorded_settings(const JobFiles& f) {
  const nlohmann::json j = read_object(f.finished ? *f.finished : *f.checkpoint);
  if (!j.contains("settings")) throw Error("it records no settings");
  return j.at("settings");
}

JobStatus job_status(const JobFiles& f, const Packing& p, const nlohmann::json& settings) {
  JobStatus st;
  try {
    if (f.finished) {
      const nlohmann::json j = read_object(*f.finished);
      if (j.value("settings", nlohmann::json()) != settings) throw Error("other settings than the first job's");
      st.done = static_cast<int>(campaign_state_from_json(j.at("state"), p).rows.size());
      st.runs = campaign_time_from_json(j.value("all_runs", nlohmann::json()), st.done);
      st.kind = JobStatus::Kind::kFinished;
    } else if (f.checkpoint) {
      const std::optional<CampaignState> state =
          read_campaign_checkpoint(read_file(*f.checkpoint), f.checkpoint->filename().string(), p, settings, &st.runs);
      if (!state) throw Error("saved from another packing");
      st.done = static_cast<int>(state->rows.size());
      st.saved_ago_s = age_seconds(*f.checkpoint);
      st.kind = JobStatus::Kind::kStarted;
    }
  } catch (const std::exception& e) {  // unjam::Error, nlohmann's exceptions
    st = {JobStatus::Kind::kUnreadable, 0, {}, 0.0, e.what()};
  }
  return st;
}

// The jobs whose files are in `out`: K shards (K from the names), or the whole campaign
// (K = 1: its checkpoint). Throws unjam::Error for shards of two different K.
std::vector<JobFiles> find_jobs(const fs::path& out) {
  int shards = 0;
  const std::map<int, fs::path> finished = find_shard_files(out, "probe_shard", shards);
  const std::map<int, fs::path> started = find_shard_files(out, "probe_checkpoint-shard", shards);
  std::map<int, JobFiles> found;
  // files numbered beyond the job array are not shards of it (merge refuses them by name)
  for (const auto& [i, file] : finished)
    if (i < shards) found[i].finished = file;
  for (const auto& [i, file] : started)
    if (i < shards) found[i].checkpoint = file;
  std::vector<JobFiles> jobs;
  if (shards > 0) {
    for (int i = 0; i < shards; ++i) jobs.push_back(found[i]);
  } else if (fs::exists(out / "probe_checkpoint.json")) {
    jobs.push_back({std::nullopt, out / "probe_checkpoint.json"});
  }
  return jobs;
}

}  // namespace

bool print_probe_status(const std::string& dir, const std::string& out_dir) {
  const fs::path out = out_dir.empty() ? fs::path(dir) : fs::path(out_dir);
  const std::vector<JobFiles> jobs = find_jobs(out);
  if (jobs.empty()) {
    if (!fs::exists(out / "probe_summary.json")) return false;
    std::printf("the probe campaign in %s has finished: its outputs are there (probe_summary.json)\n", out.c_str());
    return true;
  }
  const Packing p = read_packing(dir);
  const int K = static_cast<int>(jobs.size());
  // The campaign's settings: those of the first job that has a readable file.
  std::optional<nlohmann::json> settings;
  std::string settings_error;
  for (const JobFiles& f : jobs) {
    if (!f.finished && !f.checkpoint) continue;
    try {
      settings = recorded_settings(f);
      break;
    } catch (const std::exception& e) {
      settings_error = e.what();
    }
  }
  if (!settings) throw Error("no readable probe campaign file in " + out.string() + " (" + settings_error + ")");
  const CampaignSettings s = campaign_settings_from_json(*settings, p, "the settings recorded in " + out.string());
  const std::vector<int> targets = campaign_targets(p, s);
  std::printf("probe campaign of %s in %s: %zu probes (method %s)%s\n", dir.c_str(), out.c_str(), targets.size(),
              method_name(s.method), K > 1 ? (", " + std::to_string(K) + " shards").c_str() : "");
  int done = 0, finished = 0, started = 0, unreadable = 0;
  CampaignTime all;
  for (int i = 0; i < K; ++i) {
    const int planned = static_cast<int>(shard_targets(targets, i, K).size());
    const JobStatus st = job_status(jobs[static_cast<std::size_t>(i)], p, *settings);
    const std::string who = K > 1 ? "shard " + std::to_string(i) + "/" + std::to_string(K) : "campaign";
    switch (st.kind) {
      case JobStatus::Kind::kNotStarted:
        std::printf("  %s: not started (%d probes)\n", who.c_str(), planned);
        break;
      case JobStatus::Kind::kUnreadable:
        ++unreadable;
        std::printf("  %s: unreadable (%s)\n", who.c_str(), st.why.c_str());
        break;
      case JobStatus::Kind::kStarted:
      case JobStatus::Kind::kFinished: {
        const bool ended = st.kind == JobStatus::Kind::kFinished;
        ended ? ++finished : ++started;
        done += st.done;
        all = all + st.runs;
        std::printf("  %s: %s%d of %d probes, %d run%s, %s busy", who.c_str(), ended ? "finished, " : "", st.done,
                    planned, st.runs.runs, st.runs.runs == 1 ? "" : "s", format_duration(st.runs.busy_seconds).c_str());
        if (!ended) std::printf(" (checkpoint saved %s ago)", format_duration(st.saved_ago_s).c_str());
        std::printf("\n");
        break;
      }
    }
  }
  const int total = static_cast<int>(targets.size());
  std::printf("  done %d of %d probes (%.1f %%)", done, total, 100.0 * done / std::max(total, 1));
  if (K > 1)
    std::printf("; %d shard%s finished, %d started, %d not started", finished, finished == 1 ? "" : "s", started,
                K - finished - started - unreadable);
  if (unreadable > 0) std::printf(", %d unreadable", unreadable);
  std::printf("\n");
  const long long timed = static_cast<long long>(done) - all.untimed;
  if (timed > 0) {
    const double pace = all.busy_seconds / static_cast<double>(timed);
    std::printf("  busy %s over %d run%s (%s per probe)", format_duration(all.busy_seconds).c_str(), all.runs,
                all.runs == 1 ? "" : "s", format_duration(pace).c_str());
    if (done < total)
      std::printf("; the %d left: ~%s of busy time at that pace (divide by the threads working on them)",
                  total - done, format_duration(pace * (total - done)).c_str());
    std::printf("\n");
  }
  if (K > 1 && finished == K)
    std::printf("  every shard has finished: `unjam merge %s --out %s` writes the campaign's outputs\n", dir.c_str(),
                out.c_str());
  return true;
}

}  // namespace unjam::cli
