// `unjam bounds DIR`: the exact interval [fn_min, fn_max] of every contact's normal force over
// the admissible force networks (docs/ensemble.md), by LP.
// Writes DIR/bounds.csv (a,b,fn,fn_min,fn_max; 17 significant digits, force units of the
// packing) and DIR/bounds.json (dimension, rank, contacts, timings, parameters, version).
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "cli/shards.hpp"
#include "unjam/campaign/bounds_checkpoint.hpp"
#include "unjam/campaign/distributor.hpp"
#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/campaign_time.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/core/rank_loads_json.hpp"
#include "unjam/core/version.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/lp/rank.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::cli {

namespace {

struct BoundsOptions {
  std::string dir;
  std::string out;          // CSV path; default DIR/bounds.csv, JSON beside it
  double gap_tol = 1e-9;    // touching: gap < gap_tol (units of R_max)
  double fn_tol = 1e-9;     // force-carrying: fn > fn_tol F0
  int threads = 0;          // 0: all cores
  std::string method = "barrier";
  double lp_tol = ForceBoundsOptions{}.tolerance;      // CLP's feasibility tolerance
  double open_tol = ForceBoundsOptions{}.open_tol_F0;  // open: fn <= open_tol F0
  std::string shard;        // "i/K": this job's share of a job array
  double checkpoint_s = 30.0;  // seconds between checkpoints
  int stop_after = 0;       // > 0: stop (checkpoint saved) after this many new LPs
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// What bounds.json records of how the intervals were computed.
struct BoundsRun {
  double t_build = 0.0, t_rank = 0.0, t_total = 0.0;
  std::vector<RankLoad> loads;
  CampaignTime all_runs;  // every run that made the bounds (stopped and resumed), this one's included
};

ForceBoundsOptions lp_options(const BoundsOptions& opt, int Nc) {
  ForceBoundsOptions lp;
  lp.threads = thread_count(opt.threads);
  lp.method = opt.method == "simplex" ? LpMethod::simplex : LpMethod::barrier;
  lp.tolerance = opt.lp_tol;
  lp.open_tol_F0 = opt.open_tol;
  if (Nc >= 500) {
    int next_report = 0;
    lp.progress = [next_report, t_lp = std::chrono::steady_clock::now()](int done, int total) mutable {
      if (done < next_report && done < total) return;
      next_report = done + std::max(1, total / 20);
      const double t = seconds_since(t_lp);
      std::fprintf(stderr, "bounds: %d / %d LPs, %s elapsed, ETA %s\n", done, total,
                   format_duration(t).c_str(),
                   done > 0 ? format_duration(t * (total - done) / done).c_str() : "?");
    };
  }
  return lp;
}

// bounds.csv: one row per contact of the system (17 significant digits, force units).
// Also returns sum(fn_max - fn_min) / sum(fn) over those contacts (0 without force).
std::string bounds_csv(const Packing& packing, const EquilibriumSystem& sys, const ForceBounds& bounds,
                       double& width_over_fn) {
  std::string csv = "a,b,fn,fn_min,fn_max\n";
  double sum_width = 0.0, sum_fn = 0.0;
  char line[160];
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const Contact& c = packing.contacts[sys.contacts[k]];
    std::snprintf(line, sizeof line, "%d,%d,%.17g,%.17g,%.17g\n", c.a, c.b, c.fn,
                  bounds.fn_min[k], bounds.fn_max[k]);
    csv += line;
    sum_width += bounds.fn_max[k] - bounds.fn_min[k];
    sum_fn += c.fn;
  }
  width_over_fn = sum_fn > 0.0 ? sum_width / sum_fn : 0.0;
  return csv;
}

nlohmann::ordered_json bounds_json(const BoundsOptions& opt, const Packing& packing,
                                   const EquilibriumSystem& sys, const RankInfo& rank,
                                   const ForceBounds& bounds, const ForceBoundsOptions& lp,
                                   const BoundsRun& run, double width_over_fn) {
  const int Nc = sys.num_contacts();
  return {
      {"program_version", kVersion},
      {"command", command_line()},
      {"packing", opt.dir},
      {"N", packing.size()},
      {"mu", sys.mu},
      {"P_ext", packing.meta.contact.P_ext},
      {"F0", sys.F0},
      {"contacts_listed", packing.contacts.size()},
      {"contacts_used", Nc},
      {"grains_with_contacts", sys.grains.size()},
      {"rows", rank.rows},
      {"cone_columns", rank.columns},
      {"rank", rank.rank},
      {"rank_threshold", rank.threshold},
      {"dimension", rank.dimension},
      {"mean_width_over_mean_fn", width_over_fn},
      {"parameters",
       {{"gap_tol", opt.gap_tol}, {"fn_tol_F0", opt.fn_tol}, {"threads", lp.threads},
        {"method", opt.method}, {"lp_tolerance", lp.tolerance}, {"open_tol_F0", lp.open_tol_F0}}},
      {"min_lps_skipped", bounds.min_lps_skipped},
      {"iterations", bounds.iterations},
      {"lps_at_looser_tolerance", bounds.loosened_solves},
      {"lps_finished_by_simplex", bounds.simplex_finishes},
      {"lps_solved_unscaled", bounds.unscaled_solves},
      {"timings_s",
       {{"read_and_build", run.t_build}, {"rank", run.t_rank}, {"lp", bounds.seconds},
        {"lp_per_contact", Nc > 0 ? bounds.seconds / Nc : 0.0}, {"total", run.t_total}}},
      {"ranks", rank_loads_json<nlohmann::ordered_json>(run.loads, "lps")},
      {"all_runs", to_json(run.all_runs)},
  };
}

// bounds.csv, bounds.json and the report.
void write_bounds(const BoundsOptions& opt, const Packing& packing, const EquilibriumSystem& sys,
                  const RankInfo& rank, const ForceBounds& bounds, const ForceBoundsOptions& lp,
                  const BoundsRun& run) {
  const int Nc = sys.num_contacts();
  double width_over_fn = 0.0;
  const std::string csv = bounds_csv(packing, sys, bounds, width_over_fn);
  const std::filesystem::path csv_path =
      opt.out.empty() ? std::filesystem::path(opt.dir) / "bounds.csv" : std::filesystem::path(opt.out);
  std::filesystem::path json_path = csv_path;
  json_path.replace_extension(".json");
  write_file_atomic(csv_path, csv);
  write_file_atomic(json_path, bounds_json(opt, packing, sys, rank, bounds, lp, run, width_over_fn).dump(2) + "\n");

  std::printf("contacts used      %d of %zu (grains with contacts %zu)\n", Nc,
              packing.contacts.size(), sys.grains.size());
  std::printf("dimension          %d (cone columns %d, rank %d)\n", rank.dimension, rank.columns,
              rank.rank);
  std::printf("mean width / <fn>  %.6g\n", width_over_fn);
  std::printf("fn_min = 0 without own LP  %d contacts\n", bounds.min_lps_skipped);
  if (bounds.loosened_solves > 0)
    std::printf("barrier stalls     %lld LPs solved again at 10-100x the tolerance\n",
                bounds.loosened_solves);
  if (bounds.simplex_finishes > 0)
    std::printf("simplex finishes   %lld LPs whose barrier point failed the row check\n", bounds.simplex_finishes);
  if (bounds.unscaled_solves > 0)
    std::printf("unscaled solves    %lld LPs whose scaled simplex optimum failed the row check\n",
                bounds.unscaled_solves);
  std::printf("time per contact   %.3g s (LP %.3g s, %s, %d threads)\n",
              Nc > 0 ? bounds.seconds / Nc : 0.0, bounds.seconds, opt.method.c_str(), lp.threads);
  if (run.all_runs.runs > 1 || run.all_runs.untimed > 0) {
    std::printf("over %d run%s       %s of wall time, %s busy", run.all_runs.runs, run.all_runs.runs == 1 ? " " : "s",
                format_duration(run.all_runs.wall_seconds).c_str(), format_duration(run.all_runs.busy_seconds).c_str());
    if (run.all_runs.untimed > 0)
      std::printf(" (%lld LP values from a checkpoint that did not record its time)", run.all_runs.untimed);
    std::printf("\n");
  }
  if (run.loads.size() > 1)
    for (const RankLoad& l : run.loads)
      std::printf("  rank %d: %lld LPs, %s busy (%d threads)\n", l.rank, l.tasks,
                  format_duration(l.busy_seconds).c_str(), l.threads);
  std::printf("wrote              %s, %s\n", csv_path.string().c_str(), json_path.string().c_str());
}

// The directory of the outputs and checkpoints: DIR, or that of --out.
std::filesystem::path output_dir(const BoundsOptions& opt) {
  if (opt.out.empty()) return opt.dir;
  const std::filesystem::path parent = std::filesystem::path(opt.out).parent_path();
  return parent.empty() ? "." : parent;
}

// A finished shard: the intervals of its contacts (k mod K = i) and its counts.
void write_bounds_shard(const BoundsOptions& opt, const ForceBoundsOptions& lp, int shard, int shards,
                        const ForceBounds& b, const BoundsRun& run) {
  nlohmann::json contacts = nlohmann::json::array(), fn_min = contacts, fn_max = contacts;
  for (Eigen::Index k = shard; k < b.fn_max.size(); k += shards) {
    contacts.push_back(k);
    fn_min.push_back(b.fn_min[k]);
    fn_max.push_back(b.fn_max[k]);
  }
  nlohmann::json options = {{"gap_tol", opt.gap_tol}, {"fn_tol", opt.fn_tol}, {"method", opt.method}, {"out", opt.out}};
  put_lp_tolerances(options, lp);
  nlohmann::json j = {
      {"options", options},
      {"contacts", contacts}, {"fn_min", fn_min}, {"fn_max", fn_max}, {"lp_seconds", b.seconds},
      {"busy_seconds", run.loads.at(0).busy_seconds}, {"all_runs", to_json(run.all_runs)},
      {"command", command_line()}};
  put_bounds_counts(j, b);
  const std::filesystem::path file = output_dir(opt) / shard_file_name("bounds_shard", shard, shards);
  write_file_atomic(file, j.dump());
  std::printf("shard %d/%d: %zu contacts -> %s (merge the shards with `unjam merge`)\n", shard,
              shards, contacts.size(), file.c_str());
}

// The checkpoint of a run (or of shard i/K): OUT's directory, bounds_checkpoint[-shard-i-of-K].json.
std::filesystem::path checkpoint_path(const BoundsOptions& opt, int shard, int shards) {
  return output_dir(opt) / (shards > 1 ? shard_file_name("bounds_checkpoint-shard", shard, shards) : "bounds_checkpoint.json");
}

void run_bounds(const BoundsOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const auto [shard, shards] = opt.shard.empty() ? std::pair{0, 1} : parse_shard(opt.shard);
  omp_set_num_threads(thread_count(opt.threads));
  const std::unique_ptr<WorkDistributor> dist = make_distributor(shard, shards);
  const Packing packing = read_packing(opt.dir);
  // Only the gathering rank of an MPI job writes.
  const std::unique_ptr<DirLock> lock = dist->gathers() ? lock_output(output_dir(opt), shard, shards) : nullptr;
  const EquilibriumSystem sys = admissible_system(packing, opt.gap_tol, opt.fn_tol);
  BoundsRun run;
  run.t_build = seconds_since(t_start);
  ForceBoundsOptions lp = lp_options(opt, dist->gathers() ? sys.num_contacts() : 0);
  // Only the gathering process reads, saves and removes the checkpoint.
  std::optional<BoundsCheckpoint> checkpoint;
  if (dist->gathers())
    checkpoint.emplace(checkpoint_path(opt, shard, shards),
                       bounds_checkpoint_settings(opt.dir, packing, opt.gap_tol, opt.fn_tol, lp, opt.shard,
                                                  sys.num_contacts()));
  const CampaignTime earlier = checkpoint ? checkpoint->earlier() : CampaignTime{};
  // The runs' time so far: the earlier runs' and this one's (its busy seconds as the
  // distributor has them; the checkpoint hook runs within the gathering, under its lock).
  const auto time_so_far = [&] { return earlier + one_run(seconds_since(t_start), dist->loads()); };
  if (checkpoint) {
    if (checkpoint->resumed()) std::fprintf(stderr, "resuming from %s\n", checkpoint->file().c_str());
    checkpoint->attach(lp, opt.checkpoint_s, opt.stop_after, InterruptGuard::requested, time_so_far);
  } else {
    lp.should_stop = InterruptGuard::requested;
  }
  ForceBounds bounds;
  {
    const InterruptGuard interrupts;
    bounds = compute_force_bounds(sys, lp, *dist);
  }
  if (!dist->gathers()) return;
  if (!bounds.complete) {
    checkpoint->save(bounds, time_so_far());
    throw Interrupted("stopped (" + checkpoint->file().string() + " saved); run the same command again to resume");
  }
  checkpoint->remove();
  run.loads = dist->loads();
  run.all_runs = time_so_far();
  if (shards > 1) return write_bounds_shard(opt, lp, shard, shards, bounds, run);
  const auto t_rank = std::chrono::steady_clock::now();
  const RankInfo rank = equilibrium_rank(sys);
  run.t_rank = seconds_since(t_rank);
  run.t_total = seconds_since(t_start);
  write_bounds(opt, packing, sys, rank, bounds, lp, run);
}

}  // namespace

void add_bounds_command(CLI::App& app) {
  auto opt = std::make_shared<BoundsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bounds", "exact interval [fn_min, fn_max] of every contact's normal force over the "
                "admissible force networks (LP)");
  cmd->add_option("DIR", opt->dir, "packing directory")->required();
  cmd->add_option("--out", opt->out, "CSV output (default DIR/bounds.csv; JSON beside it)");
  add_contact_selection_options(cmd, opt->gap_tol, opt->fn_tol);
  cmd->add_option("--threads", opt->threads, "OpenMP threads (0: all cores)")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--method", opt->method, "LP method: barrier or simplex")
      ->capture_default_str()->check(CLI::IsMember({"barrier", "simplex"}));
  add_lp_tolerance_options(cmd, opt->lp_tol, opt->open_tol);
  cmd->add_option("--shard", opt->shard,
                  "i/K: only the contacts k with k mod K = i (one job of a job array; `unjam merge` "
                  "joins the K shards into bounds.csv and bounds.json)");
  cmd->add_option("--checkpoint", opt->checkpoint_s, "seconds between checkpoints (bounds_checkpoint.json beside OUT)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--stop-after", opt->stop_after,
                  "stop after this many new LPs, saving the checkpoint (as Ctrl-C; rerun to resume)")
      ->check(non_negative_number());
  cmd->callback([opt] { run_bounds(*opt); });
}

bool merge_bounds_shards(const std::string& dir, const std::string& out) {
  BoundsOptions opt;
  opt.dir = dir;
  const std::vector<ShardFile> shards = read_shards(out.empty() ? dir : out, "bounds_shard");
  if (shards.empty()) return false;
  const ShardFile& first = shards.front();
  read_shard(first, [&] {
    const nlohmann::json& o = first.json.at("options");
    opt.gap_tol = o.at("gap_tol").get<double>();
    opt.fn_tol = o.at("fn_tol").get<double>();
    opt.method = o.at("method").get<std::string>();
    opt.out = o.at("out").get<std::string>();
    ForceBoundsOptions tolerances;
    get_lp_tolerances(o, tolerances);
    check_force_bounds_options(tolerances);
    opt.lp_tol = tolerances.tolerance;
    opt.open_tol = tolerances.open_tol_F0;
  });
  const auto t_start = std::chrono::steady_clock::now();
  const Packing packing = read_packing(dir);
  const EquilibriumSystem sys = admissible_system(packing, opt.gap_tol, opt.fn_tol);
  ForceBounds bounds;
  bounds.fn_min = bounds.fn_max = Eigen::VectorXd::Constant(sys.num_contacts(), std::nan(""));
  BoundsRun run;
  std::vector<int> every(static_cast<std::size_t>(sys.num_contacts()));
  std::iota(every.begin(), every.end(), 0);  // the LPs' tasks: every contact, in order
  const std::string whole = "the packing's " + std::to_string(sys.num_contacts());
  std::vector<bool> seen;
  for (const ShardFile& shard : shards) {
    const nlohmann::json& j = shard.json;
    if (j.value("options", nlohmann::json()) != first.json.at("options"))
      throw Error("the bounds shards in " + shard.file.parent_path().string() + " come from runs with other settings");
    read_shard(shard, [&] {
      const std::vector<int> contacts = json_integers<int>(j.at("contacts"), "contacts");
      claim_shard_contacts(shard, contacts, every, whole, seen);
      const nlohmann::json &fn_min = j.at("fn_min"), &fn_max = j.at("fn_max");
      if (fn_min.size() != contacts.size() || fn_max.size() != contacts.size())
        throw Error(std::to_string(contacts.size()) + " contacts, " + std::to_string(fn_min.size()) + " minima and " +
                    std::to_string(fn_max.size()) + " maxima");
      for (std::size_t i = 0; i < contacts.size(); ++i) {
        bounds.fn_min[contacts[i]] = fn_min.at(i).get<double>();
        bounds.fn_max[contacts[i]] = fn_max.at(i).get<double>();
        if (!(bounds.fn_min[contacts[i]] >= 0.0)) throw Error("a negative fn_min");
      }
      ForceBounds counts;
      get_bounds_counts(j, counts);
      bounds.min_lps_skipped += counts.min_lps_skipped;
      bounds.iterations += counts.iterations;
      bounds.loosened_solves += counts.loosened_solves;
      bounds.simplex_finishes += counts.simplex_finishes;
      bounds.unscaled_solves += counts.unscaled_solves;
      bounds.seconds = std::max(bounds.seconds, non_negative_number(j, "lp_seconds"));
      run.loads.push_back({static_cast<int>(run.loads.size()), 0, static_cast<long long>(contacts.size()),
                           non_negative_number(j, "busy_seconds")});
      // every shard's runs (a shard written before they were recorded: its 2 x contacts LP values untimed)
      run.all_runs = run.all_runs + campaign_time_from_json(j.value("all_runs", nlohmann::json()),
                                                            2 * static_cast<long long>(contacts.size()));
    });
  }
  if (bounds.fn_max.hasNaN())
    throw Error("the bounds shards in " + first.file.parent_path().string() + " do not cover every contact of " + dir);
  const auto t_rank = std::chrono::steady_clock::now();
  const RankInfo rank = equilibrium_rank(sys);
  run.t_rank = seconds_since(t_rank);
  run.t_total = seconds_since(t_start);
  write_bounds(opt, packing, sys, rank, bounds, lp_options(opt, 0), run);
  return true;
}

}  // namespace unjam::cli
