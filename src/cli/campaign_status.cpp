// `unjam merge DIR --out D --status`: how far the probe campaign and the force bounds in D have
// got, whole or as the shards of a job array, read from their files alone (README, "On a
// cluster").
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cli/run_info.hpp"
#include "cli/shards.hpp"
#include "unjam/campaign/bounds_checkpoint.hpp"
#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/campaign_time.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/core/work_source.hpp"
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
  long long done = 0;  // tasks done: probes, or the force bounds' LP values
  CampaignTime runs;
  double saved_ago_s = 0.0;  // the checkpoint's age
  std::string why;           // kUnreadable: the reason
  std::vector<ProbeRow> rows;  // a probe job's rows (their cpu_seconds), empty for the force bounds
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
      CampaignState state = campaign_state_from_json(j.at("state"), p);
      set_probe_cpu(state, j.value("probe_cpu", nlohmann::json()));
      st.done = static_cast<long long>(state.rows.size());
      st.rows = std::move(state.rows);
      st.runs = campaign_time_from_json(j.value("all_runs", nlohmann::json()), st.done);
      st.kind = JobStatus::Kind::kFinished;
    } else if (f.checkpoint) {
      const std::optional<CampaignState> state =
          read_campaign_checkpoint(read_file(*f.checkpoint), f.checkpoint->filename().string(), p, settings, &st.runs);
      if (!state) throw Error("saved from another packing");
      st.done = static_cast<long long>(state->rows.size());
      st.rows = state->rows;
      st.saved_ago_s = age_seconds(*f.checkpoint);
      st.kind = JobStatus::Kind::kStarted;
    }
  } catch (const std::exception& e) {  // unjam::Error, nlohmann's exceptions
    st = {JobStatus::Kind::kUnreadable, 0, {}, 0.0, e.what(), {}};
  }
  return st;
}

// The jobs whose files are in `out`: K shards (K from the names `finished_prefix`-i-of-K.json and
// `checkpoint_prefix`-i-of-K.json), or the whole run (K = 1: its checkpoint `whole`). Throws
// unjam::Error for shards of two different K.
std::vector<JobFiles> find_jobs(const fs::path& out, const std::string& finished_prefix,
                                const std::string& checkpoint_prefix, const std::string& whole) {
  int shards = 0;
  const std::map<int, fs::path> finished = find_shard_files(out, finished_prefix, shards);
  const std::map<int, fs::path> started = find_shard_files(out, checkpoint_prefix, shards);
  std::map<int, JobFiles> found;
  // files numbered beyond the job array are not shards of it (merge refuses them by name)
  for (const auto& [i, file] : finished)
    if (i < shards) found[i].finished = file;
  for (const auto& [i, file] : started)
    if (i < shards) found[i].checkpoint = file;
  std::vector<JobFiles> jobs;
  if (shards > 0) {
    for (int i = 0; i < shards; ++i) jobs.push_back(found[i]);
  } else if (fs::exists(out / whole)) {
    jobs.push_back({std::nullopt, out / whole});
  }
  return jobs;
}

// What `read` gives for the first job with a file it reads (the run's settings); throws
// unjam::Error naming `what` and the last reason where there is none.
template <class T, class Read>
T first_readable(const std::vector<JobFiles>& jobs, Read read, const std::string& what) {
  std::string why;
  for (const JobFiles& f : jobs) {
    if (!f.finished && !f.checkpoint) continue;
    try {
      return read(f);
    } catch (const std::exception& e) {  // unjam::Error, nlohmann's exceptions
      why = e.what();
    }
  }
  throw Error("no readable " + what + " (" + why + ")");
}

// Prints one line per job (`planned[i]` tasks of `unit`, e.g. "probes", each; a job that is the
// whole run is named `whole`), the totals and the busy time left at the jobs' pace; `merge`
// says how to join the shards once all have finished.
void print_jobs(const std::vector<long long>& planned, const std::vector<JobStatus>& jobs, const char* whole,
                const char* unit, const char* unit_one, const std::string& merge) {
  const int K = static_cast<int>(jobs.size());
  long long done = 0, total = 0;
  int finished = 0, started = 0, unreadable = 0;
  CampaignTime all;
  for (int i = 0; i < K; ++i) {
    const long long plan = planned[static_cast<std::size_t>(i)];
    const JobStatus& st = jobs[static_cast<std::size_t>(i)];
    total += plan;
    const std::string who = K > 1 ? "shard " + std::to_string(i) + "/" + std::to_string(K) : whole;
    switch (st.kind) {
      case JobStatus::Kind::kNotStarted:
        std::printf("  %s: not started (%lld %s)\n", who.c_str(), plan, unit);
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
        std::printf("  %s: %s%lld of %lld %s, %d run%s, %s busy", who.c_str(), ended ? "finished, " : "", st.done,
                    plan, unit, st.runs.runs, st.runs.runs == 1 ? "" : "s", format_duration(st.runs.busy_seconds).c_str());
        if (!ended) std::printf(" (checkpoint saved %s ago)", format_duration(st.saved_ago_s).c_str());
        std::printf("\n");
        break;
      }
    }
  }
  std::printf("  done %lld of %lld %s (%.1f %%)", done, total, unit, 100.0 * static_cast<double>(done) /
                                                                        static_cast<double>(std::max(total, 1LL)));
  if (K > 1)
    std::printf("; %d shard%s finished, %d started, %d not started", finished, finished == 1 ? "" : "s", started,
                K - finished - started - unreadable);
  if (unreadable > 0) std::printf(", %d unreadable", unreadable);
  std::printf("\n");
  const long long timed = done - all.untimed;
  if (timed > 0) {
    const double pace = all.busy_seconds / static_cast<double>(timed);
    std::printf("  busy %s over %d run%s (%s per %s)", format_duration(all.busy_seconds).c_str(), all.runs,
                all.runs == 1 ? "" : "s", format_duration(pace).c_str(), unit_one);
    if (done < total)
      std::printf("; the %lld left: ~%s of busy time at that pace (divide by the threads working on them)",
                  total - done, format_duration(pace * static_cast<double>(total - done)).c_str());
    std::printf("\n");
  }
  if (K > 1 && finished == K) std::printf("  every shard has finished: %s\n", merge.c_str());
}

}  // namespace

bool print_probe_status(const std::string& dir, const std::string& out_dir) {
  const fs::path out = out_dir.empty() ? fs::path(dir) : fs::path(out_dir);
  const std::vector<JobFiles> jobs = find_jobs(out, "probe_shard", "probe_checkpoint-shard", "probe_checkpoint.json");
  if (jobs.empty()) {
    if (!fs::exists(out / "probe_summary.json")) return false;
    std::printf("the probe campaign in %s has finished: its outputs are there (probe_summary.json)\n", out.c_str());
    return true;
  }
  const Packing p = read_packing(dir);
  const int K = static_cast<int>(jobs.size());
  const nlohmann::json settings =
      first_readable<nlohmann::json>(jobs, recorded_settings, "probe campaign file in " + out.string());
  const CampaignSettings s = campaign_settings_from_json(settings, p, "the settings recorded in " + out.string());
  const std::vector<int> targets = campaign_targets(p, s);
  std::printf("probe campaign of %s in %s: %zu probes (method %s)%s\n", dir.c_str(), out.c_str(), targets.size(),
              method_name(s.method), K > 1 ? (", " + std::to_string(K) + " shards").c_str() : "");
  std::vector<long long> planned;
  std::vector<JobStatus> status;
  for (int i = 0; i < K; ++i) {
    planned.push_back(static_cast<long long>(shard_targets(targets, i, K).size()));
    status.push_back(job_status(jobs[static_cast<std::size_t>(i)], p, settings));
  }
  print_jobs(planned, status, "campaign", "probes", "probe",
             "`unjam merge " + dir + " --out " + out.string() + "` writes the campaign's outputs");
  std::vector<ProbeRow> rows;
  for (const JobStatus& st : status) rows.insert(rows.end(), st.rows.begin(), st.rows.end());
  if (const ProbeCpu cpu = probe_cpu(rows); cpu.timed > 0)
    std::printf("  CPU per probe (%d of the %lld done record it): median %s, 90 %% below %s, largest %s (contact %d)\n",
                cpu.timed, static_cast<long long>(rows.size()), format_seconds(cpu.median).c_str(),
                format_seconds(cpu.p90).c_str(), format_seconds(cpu.max).c_str(), cpu.max_contact);
  return true;
}

namespace {

// The force bounds' tolerances and LP method as a job's file records them: a checkpoint under
// "settings" (bounds_checkpoint_settings), a finished shard under "options"; the LP's
// tolerances are there only where they are not the defaults.
struct BoundsRecord {
  double gap_tol = 0.0, fn_tol = 0.0;
  std::string method;
  double lp_tolerance = 0.0, open_tol_F0 = 0.0;
  bool operator==(const BoundsRecord&) const = default;
};

// From the parsed file `j`: a finished shard's "options" or a checkpoint's "settings".
BoundsRecord bounds_record(const nlohmann::json& j, bool finished) {
  const nlohmann::json& r = j.at(finished ? "options" : "settings");
  ForceBoundsOptions lp;
  get_lp_tolerances(r, lp);
  return {r.at("gap_tol").get<double>(), r.at("fn_tol").get<double>(), r.at("method").get<std::string>(),
          lp.tolerance, lp.open_tol_F0};
}

BoundsRecord job_bounds_record(const JobFiles& f) {
  return bounds_record(read_object(f.finished ? *f.finished : *f.checkpoint), f.finished.has_value());
}

// Where one job of the force bounds stands, in LP values (fn_min and fn_max of each contact).
// `shard` is the "i/K" its checkpoint records ("" for the whole run), `contacts` the
// admissible set's size under `record`.
JobStatus bounds_job_status(const JobFiles& f, const std::string& fingerprint, const BoundsRecord& record,
                            const std::string& shard, int contacts) {
  JobStatus st;
  try {
    if (f.finished) {
      const nlohmann::json j = read_object(*f.finished);
      if (!(bounds_record(j, true) == record)) throw Error("other settings than the first job's");
      st.done = 2 * static_cast<long long>(json_integers<int>(j.at("contacts"), "contacts").size());
      st.runs = campaign_time_from_json(j.value("all_runs", nlohmann::json()), st.done);
      st.kind = JobStatus::Kind::kFinished;
    } else if (f.checkpoint) {
      const nlohmann::json j = read_object(*f.checkpoint);
      const nlohmann::json& settings = j.at("settings");
      if (settings.value("packing_fingerprint", "") != fingerprint) throw Error("saved from another packing");
      if (!(bounds_record(j, false) == record)) throw Error("other settings than the first job's");
      if (settings.value("shard", "?") != shard)
        throw Error("saved by shard " + settings.value("shard", std::string("?")) + ", not " + shard);
      if (settings.value("contacts", -1) != contacts)
        throw Error("saved for " + std::to_string(settings.value("contacts", -1)) + " contacts, not the " +
                    std::to_string(contacts) + " of the admissible set");
      const std::optional<ForceBounds> b = read_bounds_checkpoint(*f.checkpoint, settings, &st.runs);
      st.done = b ? known_values(*b) : 0;
      st.saved_ago_s = age_seconds(*f.checkpoint);
      st.kind = JobStatus::Kind::kStarted;
    }
  } catch (const std::exception& e) {  // unjam::Error, nlohmann's exceptions
    st = {JobStatus::Kind::kUnreadable, 0, {}, 0.0, e.what(), {}};
  }
  return st;
}

}  // namespace

bool print_bounds_status(const std::string& dir, const std::string& out_dir) {
  const fs::path out = out_dir.empty() ? fs::path(dir) : fs::path(out_dir);
  const std::vector<JobFiles> jobs = find_jobs(out, "bounds_shard", "bounds_checkpoint-shard", "bounds_checkpoint.json");
  if (jobs.empty()) {
    if (!fs::exists(out / "bounds.json")) return false;
    std::printf("the force bounds in %s have finished: their outputs are there (bounds.json)\n", out.c_str());
    return true;
  }
  const Packing p = read_packing(dir);
  const int K = static_cast<int>(jobs.size());
  const BoundsRecord record = first_readable<BoundsRecord>(jobs, job_bounds_record, "force bounds file in " + out.string());
  const int contacts = admissible_system(p, record.gap_tol, record.fn_tol).num_contacts();
  std::printf("force bounds of %s in %s: %d contacts, %d LP values (method %s)%s\n", dir.c_str(), out.c_str(),
              contacts, 2 * contacts, record.method.c_str(),
              K > 1 ? (", " + std::to_string(K) + " shards").c_str() : "");
  const std::string fingerprint = packing_fingerprint(p);
  std::vector<long long> planned;
  std::vector<JobStatus> status;
  for (int i = 0; i < K; ++i) {
    // shard i/K: the contacts in_shard of it (core/work_source; a contact's place is its number)
    long long share = 0;
    for (int k = 0; k < contacts; ++k) share += in_shard(k, i, K);
    planned.push_back(2 * share);
    const std::string shard = K > 1 ? std::to_string(i) + "/" + std::to_string(K) : "";
    status.push_back(bounds_job_status(jobs[static_cast<std::size_t>(i)], fingerprint, record, shard, contacts));
  }
  print_jobs(planned, status, "run", "LP values", "LP value",
             "`unjam merge " + dir + " --out " + out.string() + "` writes bounds.csv and bounds.json");
  return true;
}

}  // namespace unjam::cli
