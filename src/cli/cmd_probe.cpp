// `unjam probe DIR`: the local perturbation probe (docs/probe.md, "The probe"). One contact
// (--contact K: F_crit and the displacement of every grain) or every force-carrying contact
// (--all, or --sample K of them), each from the same static packing, with the averages of
// the paper's Figs. 1 and 2 and the decay exponent alpha.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "cli/shards.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/campaign/distributor.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/rank_loads_json.hpp"
#include "unjam/core/version.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/packing/csv_table.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/cd_step.hpp"
#include "unjam/probe/campaign_run.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam::cli {
namespace {

namespace fs = std::filesystem;

struct ProbeOptions {
  std::string dir, out, method = "lp", displacement = "peculiar", export_problem, cd_start = "static";
  int contact = -1;
  bool all = false;
  int sample = 0;
  std::uint64_t seed = 1;
  double g = 1e-9, velocity_tol = 1e-6;
  double lp_tol = KinematicProbeSettings{}.lp_tolerance;  // --lp-tol: lp only (validate)
  double dt = 0.0;                 // 0: default_probe_dt(method, g)
  double max_inertia = 0.0;        // > 0: CampaignSettings::max_inertia (F0)
  double window = 0.0;             // > 0: ProbeSettings::window (mean diameters)
  long long max_sweeps = 10'000'000;
  int threads = 0;
  double checkpoint_s = 30.0;
  double running_every = kRunningEverySeconds;  // --running-every (s)
  std::vector<double> fit_window;  // [r_lo, r_hi], empty: the default rule
  bool quiet = false;
  std::string shard;               // "i/K": this job's share of a job array (campaign/distributor.hpp)
  int stop_after = 0;              // > 0: stop (checkpoint saved) after this many new probes
  std::string partial;             // --partial DIR: the outputs of the checkpoint's probes, to DIR
  CdPathSettings cd;               // the --cd-* options bind its fields; its start comes from cd_start
};

// The probe settings follow the packing: its contact tolerance and bath mass.
CampaignSettings campaign_settings(const ProbeOptions& o, const Packing& p) {
  CampaignSettings s = campaign_settings_for(p);
  if (o.displacement != "peculiar" && o.displacement != "total")
    throw Error("--displacement must be peculiar or total");
  s.method = method_from_name(o.method);
  s.cd = o.cd;
  s.cd.start = cd_start_from_name(o.cd_start);
  s.total_displacement = o.displacement == "total";
  s.sample = o.sample;
  s.seed = o.seed;
  s.nlgs.g = s.kinematic.g = o.g;
  s.kinematic.lp_tolerance = o.lp_tol;
  s.nlgs.dt = o.dt > 0.0 ? o.dt : default_probe_dt(s.method, o.g);
  s.nlgs.velocity_tol = o.velocity_tol;
  s.nlgs.max_sweeps = o.max_sweeps;
  s.max_inertia = o.max_inertia;
  s.nlgs.window = o.window;
  validate(s);
  return s;
}

void write_single(const fs::path& out, const Packing& p, const ProbeResult& r) {
  CsvWriter w({"id", "x", "y", "radius", "ux", "uy", "rot", "ux_g", "uy_g"});
  for (std::size_t i = 0; i < p.size(); ++i) {
    w.cell(static_cast<std::int64_t>(i)).cell(p.particles.x[i]).cell(p.particles.y[i]);
    w.cell(p.particles.radius[i]).cell(r.u[i].x()).cell(r.u[i].y()).cell(r.u_rot[i]);
    w.cell(r.u[i].x() / r.g).cell(r.u[i].y() / r.g);
    w.end_row();
  }
  write_file_atomic(out / ("probe-" + std::to_string(r.contact) + ".csv"), w.str());
}

std::string rows_csv(const CampaignState& state, const std::string& method) {
  CsvWriter w({"contact", "a", "b", "f_cont", "f_crit", "method", "converged", "sweeps",
               "residual", "violations", "lambda_dt", "f_inertia", "opened", "sliding"});
  for (const ProbeRow& r : state.rows) {
    w.cell(r.contact).cell(r.a).cell(r.b).cell(r.f_cont).cell(r.f_crit).cell(method);
    w.cell(r.converged ? 1 : 0).cell(static_cast<std::int64_t>(r.sweeps)).cell(r.residual);
    w.cell(r.violations).cell(r.lambda_dt);
    if (std::isnan(r.f_inertia)) w.cell(std::string_view());  // lp, no solution, older checkpoint
    else w.cell(r.f_inertia);
    for (const int n : {r.opened, r.sliding}) {  // lp, nlgs, no solution, older checkpoint: empty
      if (n < 0) w.cell(std::string_view());
      else w.cell(n);
    }
    w.end_row();
  }
  return w.str();
}

// probe_cpu.csv: the CPU each probe took (ProbeRow::cpu_seconds), one row per probe that
// records it, in contact order. A measurement, not a result: unlike probes.csv, its bytes differ
// from run to run.
std::string probe_cpu_csv(const CampaignState& state) {
  CsvWriter w({"contact", "cpu_seconds"});
  for (const ProbeRow& r : state.rows) {
    if (!(r.cpu_seconds >= 0.0)) continue;
    w.cell(r.contact).cell(r.cpu_seconds);
    w.end_row();
  }
  return w.str();
}

// The exact step also writes its contact forces, displacements and states
// (probe-K-forces.csv), so that the solution can be checked by anyone, and says which
// contacts it changes (`changes`, where it has forces).
ProbeResult probe_exact_with_forces(const Packing& p, const CampaignSettings& s, int contact,
                                    const fs::path& out, CdPathStats& stats,
                                    std::optional<StepStateChanges>& changes) {
  const CdStepSolution sol = s.method == ProbeMethod::kLemke ? probe_cd_lemke(p, contact, s.nlgs)
                                                             : probe_cd_path(p, contact, s.nlgs, s.cd, &stats);
  if (sol.f.size() > 0) {
    const CdStepProblem step = build_cd_step(p, contact, s.nlgs);
    write_file_atomic(out / ("probe-" + std::to_string(contact) + "-forces.csv"), step_forces_csv(step, p, sol.f));
    changes = step_state_changes(step, p, step_states(step, sol.f));
  }
  return sol.result;
}

// Why the cd path found no solution, where it knows (stats of its first attempt).
std::string cd_failure_hint(const CdPathStats& stats, const CdPathSettings& cd) {
  const std::string why_fails = "; docs/probe.md, \"Why a path fails\"";
  const CdPathStart start = cd.start;
  if (stats.budget_spent)
    return "its paths spent the budget of --cd-max-pieces (" + std::to_string(cd.max_probe_pieces) +
           " pieces) before an exact solution; docs/probe.md, \"A budget of pieces per probe\"";
  if (stats.failure == "share")
    return "the interior-point start spent its share of the budget (--cd-interior-share of --cd-max-pieces) before "
           "an exact solution, and the continuation in dt ended short of the probe's dt with the rest unspent "
           "(a fold it did not pass: --cd-inertial-jumps, --cd-inertial-halvings); docs/probe.md, \"The interior "
           "start first, the continuation in dt where it fails\"";
  if (start == CdPathStart::compliant && !stats.paths.empty()) {
    // The continuation: either every path from the static network stopped short of the full
    // opening, or a lowering stopped at a fold and the restarts below it found nothing better.
    const CdPathAttempt& last = stats.paths.back();
    bool none_opened = true;
    for (const CdPathAttempt& a : stats.paths) none_opened = none_opened && a.lambda_max < 1.0;
    char buf[160];
    if (none_opened) {
      std::snprintf(buf, sizeof buf, "%.3g of the opening at compliance %.3g", last.lambda_max, last.compliance);
      return std::string("every path from the static network closes on itself or cycles before the full opening, "
                         "at an opening in proportion to its compliance (") + buf +
             "): no solution is connected to the static network at any stiffness tried" + why_fails;
    }
    double stopped = 0.0;  // where the first lowering stopped: the continuation's fold
    for (const CdPathAttempt& a : stats.paths)
      if (stopped == 0.0 && a.compliance_end > 0.0) stopped = a.compliance_end;
    if (stopped > 0.0) {
      std::snprintf(buf, sizeof buf, "%.3g", stopped);
      return std::string("the compliance's lowering stopped at ") + buf +
             " (the branch of soft solutions turns back there), and the other paths listed below found no "
             "exact solution; --cd-compliant-start below " + buf +
             " starts the continuation past that fold; docs/probe.md, \"Where the path starts\", \"Where the "
             "continuation starts\"";
    }
  }
  if (stats.failure == "loop" && stats.lambda_max < 1.0) {
    char turn[32];
    std::snprintf(turn, sizeof turn, "%.3g", stats.lambda_max);
    return std::string("the branch of solutions through the ") +
           (start == CdPathStart::lp_optimum       ? "lp optimum"
            : start == CdPathStart::interior_point ? "interior-point iterate"
                                                   : "static network") +
           " closes on itself, turning back at " + turn +
           " of the opening: no solution is connected to it (--cd-start compliant takes the rigid limit of "
           "stiff contacts instead)" + why_fails;
  }
  if (stats.failure == "loop" || stats.failure == "cycle")
    return std::string("a path at the full opening ") +
           (stats.failure == "loop" ? "closes on itself" : "cycles at a degenerate point") + why_fails;
  char tol[32];
  std::snprintf(tol, sizeof tol, "%g", kExactStepTolerance);
  return std::string("the path found none within ") + tol + " g" + (stats.failure.empty() ? "" : ": ") +
         stats.failure + "; docs/probe.md, \"What limits it\"";
}

// One line per path the cd probe followed (CdPathStats::paths): where it started, how far it
// got and how it ended, so that a user sees why a probe is or is not exact.
void print_cd_paths(const CdPathStats& stats, CdPathStart start) {
  if (stats.interior_iterations > 0)
    std::printf("  interior-point start: %d iterations, natural residual %.2e (F0, g / dt^2); %s of CPU\n",
                stats.interior_iterations, stats.interior_residual,
                format_duration(stats.interior_cpu_seconds).c_str());
  if (stats.interior_again_iterations > 0)
    std::printf("  again in the wide neighbourhood: %d iterations (%d by plain Newton steps), natural residual %.2e; "
                "%s\n",
                stats.interior_again_iterations, stats.interior_again_short_steps, stats.interior_again_residual,
                stats.interior_again_kept ? "its iterate is the start" : "the first iterate is the start");
  // interior-inertial: the continuation in dt ran after the interior-point start at the probe's
  // dt, which is the result unless the continuation got there exactly.
  const bool first = start == CdPathStart::interior_inertial;
  const char* prefix = first ? "  the interior-point start not exact within its share of the budget; then the " : "  ";
  const char* after = !stats.inertial_fallback ? ""
                      : first                  ? "; the interior-point start's result kept"
                                               : "; then the interior-point start at the probe's dt";
  if (stats.inertial_dt_start > 0.0 && stats.inertial_dt_reached == 0.0)
    std::printf("%sinertial start: the step at dt %.3g (the last tried) not solved exactly%s\n", prefix,
                stats.inertial_dt_start, after);
  else if (stats.inertial_dt_start > 0.0)
    std::printf("%sinertial start: the step at dt %.3g, continued in dt to %.3g in %d stages (%d interior-point "
                "starts past folds in dt)%s\n",
                prefix, stats.inertial_dt_start, stats.inertial_dt_reached, stats.inertial_stages,
                stats.inertial_jumps, after);
  for (std::size_t i = 0; i < stats.paths.size(); ++i) {
    const CdPathAttempt& a = stats.paths[i];
    const char* from = a.other_iterate ? (a.iterate_states ? "from the other iterate's states "
                                                           : "from the other iterate's forces' states ")
                                       : (a.iterate_states ? "from the interior point's states " : "");
    std::printf("  path %zu %sat compliance %.3g", i + 1, from, a.compliance);
    if (a.dt > 0.0) std::printf(" (the step at dt %.4g)", a.dt);
    std::printf(": ");
    if (a.lambda_max < 1.0)
      std::printf("stopped at %.3g of the opening (%s)", a.lambda_max, a.failure.c_str());
    else if (a.compliance_end > 0.0)
      std::printf("full opening; %d lowerings, stopped at compliance %.3g (%s)", a.lowerings, a.compliance_end,
                  a.failure.c_str());
    else if (a.failure == "lost")
      std::printf("full opening, its forces' digits lost (--cd-lost-factor)");
    else if (a.compliance_settled > 0.0)
      std::printf("full opening; %d lowerings, settled at compliance %.3g (--cd-settle-compliance)", a.lowerings,
                  a.compliance_settled);
    else
      std::printf("full opening%s", a.lowerings > 0 ? "; lowered to the rigid step" : "");
    if (a.residual == kNoSolution)
      std::printf("; no solution");
    else
      std::printf("; residual %.2e g", a.residual);
    std::printf("; %d pieces, %d factorisations, %s of CPU\n", a.pieces, a.factorizations,
                format_duration(a.cpu_seconds).c_str());
  }
}

// Why a single probe is not a solution, and what the user can do about it.
std::string not_converged_message(const ProbeResult& r, const std::string& method, const std::string& cd_hint) {
  char residual[64];
  std::snprintf(residual, sizeof residual, "residual %.3g g", r.residual);
  const std::string hint = method == "nlgs"    ? "raise --max-sweeps"
                           : method == "cd"    ? cd_hint
                           : method == "lemke" ? "Lemke's path ended on a ray"
                                               : "docs/probe.md";
  return "the probe of contact " + std::to_string(r.contact) + " did not converge (method " + method + ", " +
         (r.residual == kNoSolution ? std::string("no solution") : std::string(residual)) +
         "): its F_crit and field are not a solution (" + hint + ")";
}

// The prefix of a rank's lines under mpirun; "" for one process.
std::string rank_prefix(const WorkDistributor& dist) {
  return dist.ranks() > 1 ? "rank " + std::to_string(dist.rank()) + ": " : "";
}

// A sign of life of probes that run for minutes to hours (cd at 2000 disks and more), every
// --running-every seconds of a probe on stderr, with its work so far (cd: its polls are its
// pieces, over all its paths; nlgs: 16 sweeps each); none with --quiet. `rank`: the line's
// prefix under mpirun, "" otherwise.
std::function<void(int, double, long long)> running_printer(const ProbeOptions& o, const std::string& rank) {
  if (o.quiet) return {};
  const std::string method = o.method;
  return [rank, method](int contact, double seconds, long long polls) {
    const std::string work = method == "cd"     ? " (" + std::to_string(polls) + " pieces so far)"
                             : method == "nlgs" ? " (~" + std::to_string(16 * polls) + " sweeps so far)"
                                                : "";
    std::fprintf(stderr, "  %scontact %d: probing for %s%s\n", rank.c_str(), contact,
                 format_duration(seconds).c_str(), work.c_str());
  };
}

void run_single(const ProbeOptions& o, const Packing& p, const CampaignSettings& s, const fs::path& out) {
  if (!o.export_problem.empty()) {
    write_siconos_problem(build_cd_step(p, o.contact, s.nlgs), o.export_problem);
    std::printf("step problem of contact %d written to %s (Siconos frictional contact format)\n",
                o.contact, o.export_problem.c_str());
  }
  const auto t0 = std::chrono::steady_clock::now();
  const bool exact = s.method == ProbeMethod::kLemke || s.method == ProbeMethod::kCd;
  if (s.nlgs.window > 0.0) {  // said before the probe runs, which may take long
    const CdStepProblem w = build_cd_step(p, o.contact, s.nlgs);
    std::printf("contact %d: a window of %g mean diameters, %zu grains and %d contacts of %zu and %zu; every "
                "other grain clamped to the cell (not the whole packing's step; docs/probe.md, \"A window around "
                "the probed pair\")\n",
                o.contact, s.nlgs.window, w.system.grains.size(), w.num_contacts(), p.size(), p.contacts.size());
    std::fflush(stdout);
  }
  CdPathStats stats;
  std::optional<StepStateChanges> changes;
  const CampaignSettings st = with_running(s, o.contact, running_printer(o, ""), o.running_every);
  const ProbeResult r =
      exact ? probe_exact_with_forces(p, st, o.contact, out, stats, changes) : probe_contact(p, st, o.contact);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_single(out, p, r);
  const double F0 = p.force_unit();
  std::printf("contact %d (grains %d-%d), method %s%s%s\n", r.contact, r.a, r.b, o.method.c_str(),
              s.cd.start == CdPathStart::static_network ? "" : ", cd start ",
              s.cd.start == CdPathStart::static_network ? "" : cd_start_name(s.cd.start));
  std::printf("  F_cont / F0 %.6f   F_crit / F0 %.6f   F_crit / F_cont %.4f\n", r.f_cont / F0,
              r.f_crit / F0, r.f_crit / r.f_cont);
  std::printf("  converged %s  sweeps/pivots %lld  residual %.2e  violations %d  lambda dt / g %.3e\n",
              r.converged ? "yes" : "NO", r.sweeps, r.residual, r.violations, r.lambda_dt / r.g);
  if (!std::isnan(r.f_inertia))
    std::printf("  inertia of the step (largest net force on a grain) / F0 %.3e\n", r.f_inertia / F0);
  std::printf("  %s, displacement field written to %s\n", format_duration(wall).c_str(),
              (out / ("probe-" + std::to_string(r.contact) + ".csv")).c_str());
  if (changes)
    std::printf("  of the %d other contacts loaded in the packing the step opens %d and slides %d (|u_t| > %g g), "
                "and %d of the %d without force close; forces, displacements and states in %s\n",
                changes->loaded, changes->opened, changes->sliding, kExactStepTolerance, changes->closed,
                changes->unloaded,
                (out / ("probe-" + std::to_string(r.contact) + "-forces.csv")).c_str());
  print_cd_paths(stats, s.cd.start);
  // Near-exact within the residual the user accepts: a result, as asked, not an error.
  if (stats.accepted) {
    std::printf("  near-exact: the search stopped at the first solution within --cd-accept-residual %g g "
                "(docs/probe.md, \"Accepting a near-exact solution\")\n",
                s.cd.accept_residual);
    return;
  }
  if (!r.converged) throw Error(not_converged_message(r, o.method, cd_failure_hint(stats, s.cd)));
}

std::optional<FitWindow> fit_window(const ProbeOptions& o) {
  if (o.fit_window.empty()) return std::nullopt;
  if (o.fit_window.size() != 2 || !(o.fit_window[0] > 0.0) || !(o.fit_window[1] > o.fit_window[0]))
    throw Error("--fit-window takes two distances 0 < r_lo < r_hi");
  return FitWindow{o.fit_window[0], o.fit_window[1]};
}

// The time of a campaign's run for its summary: this run's wall time and ranks, and every
// run's (CampaignTime, core/campaign_time).
struct RunTime {
  double wall = 0.0;
  std::vector<RankLoad> loads;
  CampaignTime all_runs;
};

void finish_campaign(const ProbeOptions& o, const Packing& p, const CampaignSettings& s,
                     const CampaignState& state, const RunTime& time, const fs::path& out, int planned = 0);
void write_shard(const ProbeOptions& o, const std::string& fingerprint, const nlohmann::json& settings_json,
                 const CampaignState& state, const RunTime& time, const fs::path& file);

// An MPI rank other than 0: probes what rank 0 hands out, writes nothing.
void run_worker(const Packing& p, const CampaignSettings& s, WorkDistributor& dist,
                const std::function<void(int, double, long long)>& running, double running_every_s) {
  CampaignState unused = empty_campaign_state(p);
  CampaignHooks hooks;
  hooks.running = running;
  hooks.running_every_s = running_every_s;
  hooks.should_stop = InterruptGuard::requested;
  hooks.cancel = InterruptGuard::requested;  // this rank's own signal (mpirun forwards SIGTERM to every rank)
  const InterruptGuard interrupts;
  run_campaign(p, s, unused, hooks, dist);
}

// The state a stopped run saved to `checkpoint`, or an empty one (probe/campaign_run), and
// the time of the runs that made it (`earlier`).
CampaignState start_state(const fs::path& checkpoint, const Packing& p, const nlohmann::json& settings_json,
                          CampaignTime& earlier) {
  SavedCampaign saved = load_campaign_checkpoint(checkpoint, p, settings_json);
  earlier = saved.time;
  if (!saved.set_aside.empty())
    std::fprintf(stderr, "warning: %s was saved from another packing (or an older unjam); set aside as %s, "
                 "starting over\n", checkpoint.c_str(), saved.set_aside.c_str());
  if (!saved.state) return empty_campaign_state(p);
  std::fprintf(stderr, "resuming: %zu probes already done\n", saved.state->rows.size());
  return std::move(*saved.state);
}

// A shard's checkpoint holds only the shard's own contacts (`mine`, sorted). One that holds
// others was written by a version that split the targets by contact number (k mod K) instead of
// by their place in the list: finishing it would probe some contacts twice and leave others out.
void refuse_other_shards_probes(const CampaignState& state, const std::vector<int>& mine, const fs::path& checkpoint,
                                const std::string& shard) {
  for (const ProbeRow& r : state.rows)
    if (!std::binary_search(mine.begin(), mine.end(), r.contact))
      throw Error(checkpoint.string() + " holds contact " + std::to_string(r.contact) + ", which is not in shard " +
                  shard + " (it was written by an unjam that split the targets by contact number); finish the job array "
                  "with that unjam, or remove its probe_checkpoint-shard-* and probe_shard-* files to start again");
}

// Progress and ETA on stderr, at most every 2 s and at the end (none with --quiet).
std::function<void(int, int, double, double)> progress_printer(const ProbeOptions& o) {
  if (o.quiet) return {};
  return [last = 0.0](int done, int all, double elapsed, double eta) mutable {
    if (elapsed - last < 2.0 && done < all) return;
    last = elapsed;
    std::fprintf(stderr, "probes %d / %d (%.1f %%)  elapsed %s  ETA ~%s\n", done, all,
                 100.0 * done / std::max(all, 1), format_duration(elapsed).c_str(), format_duration(eta).c_str());
  };
}

// --partial DIR: the outputs of the probes the campaign's checkpoint holds (a campaign still
// running, or stopped), written to DIR as a finished campaign writes them, with
// probe_summary.json's `partial` saying how many of how many. Reads the checkpoint only: the
// campaign itself, running or not, is left as it is, and resumes as before.
void write_partial(const ProbeOptions& o, const Packing& p, const fs::path& checkpoint, const CampaignSettings& s,
                   int planned, const fs::path& out) {
  const fs::path dir = o.partial;
  if (launched_by_mpi()) throw Error("--partial reads a checkpoint: run it as one process, not under mpirun");
  std::error_code ec;
  if (fs::exists(dir) && fs::equivalent(dir, out, ec))
    throw Error("--partial " + o.partial + " is the campaign's output directory; give another directory "
                "(the campaign writes its own outputs there when it finishes)");
  if (!fs::exists(checkpoint))
    throw Error("no checkpoint of this campaign in " + out.string() + " (" + checkpoint.filename().string() +
                "): it has not started, or it has finished and written its outputs there");
  RunTime time;  // this run's: none; the runs' so far: the checkpoint's record
  const std::optional<CampaignState> state =
      read_campaign_checkpoint(read_file(checkpoint), checkpoint.string(), p, to_json(s), &time.all_runs);
  if (!state) throw Error(checkpoint.string() + " was saved from another packing than " + o.dir);
  const DirLock lock(dir, command_line());
  finish_campaign(o, p, s, *state, time, dir, planned);
}

void run_all(const ProbeOptions& o, const Packing& p, const CampaignSettings& s, const fs::path& out) {
  fit_window(o);  // refuse a bad window before any probe runs
  const std::vector<int> targets = campaign_targets(p, s);
  const int total = static_cast<int>(targets.size());
  if (total == 0)
    throw Error(o.dir + " has no force-carrying contact (fn > " + nlohmann::json(s.force_threshold).dump() +
                " F0): nothing to probe");
  const auto [shard, shards] = o.shard.empty() ? std::pair{0, 1} : parse_shard(o.shard);
  const std::string part = shards > 1 ? "-shard-" + std::to_string(shard) + "-of-" + std::to_string(shards) : "";
  CheckpointedCampaignOptions run;
  run.checkpoint = out / ("probe_checkpoint" + part + ".json");
  run.settings = to_json(s);
  run.fingerprint = packing_fingerprint(p);
  if (!o.partial.empty()) {
    const auto planned = shard_targets(targets, shard, shards).size();
    return write_partial(o, p, run.checkpoint, s, static_cast<int>(planned), out);
  }
  const std::unique_ptr<WorkDistributor> dist = make_distributor(shard, shards);
  if (!dist->gathers()) return run_worker(p, s, *dist, running_printer(o, rank_prefix(*dist)), o.running_every);
  const auto lock = lock_output(out, shard, shards);
  run.checkpoint_s = o.checkpoint_s;
  run.stop_after = o.stop_after;
  run.interrupted = InterruptGuard::requested;
  run.progress = progress_printer(o);
  run.running = running_printer(o, rank_prefix(*dist));
  run.running_every_s = o.running_every;
  CampaignState state = start_state(run.checkpoint, p, run.settings, run.earlier);
  if (shards > 1) refuse_other_shards_probes(state, shard_targets(targets, shard, shards), run.checkpoint, o.shard);
  const std::string spread = dist->ranks() > 1 ? " x " + std::to_string(dist->ranks()) + " MPI ranks"
                             : shards > 1       ? ", shard " + o.shard : "";
  char window[96] = "";
  if (s.nlgs.window > 0.0)
    std::snprintf(window, sizeof window, ", in windows of %g mean diameters (clamped)", s.nlgs.window);
  char budget[96] = "", accept[64] = "", settle[64] = "", lost[80] = "";
  if (s.cd.max_probe_pieces > 0)  // cd only (validate)
    std::snprintf(budget, sizeof budget, ", at most %lld pieces per probe", s.cd.max_probe_pieces);
  if (s.cd.accept_residual != CdPathSettings{}.accept_residual)  // cd only (validate)
    std::snprintf(accept, sizeof accept, ", stopping at a residual of %g g", s.cd.accept_residual);
  if (s.cd.settle_compliance > 0.0)  // cd only (validate)
    std::snprintf(settle, sizeof settle, ", settling at exact solutions at compliances <= %g", s.cd.settle_compliance);
  if (s.cd.lost_factor > 0.0)  // cd only (validate)
    std::snprintf(lost, sizeof lost, ", dropping paths that lose their digits (factor %g)", s.cd.lost_factor);
  char floor[64] = "";
  if (s.cd.restart_floor > 0.0)  // the continuation only (validate)
    std::snprintf(floor, sizeof floor, ", no restart below compliance %g", s.cd.restart_floor);
  char lp_tol[48] = "";
  if (s.kinematic.lp_tolerance != KinematicProbeSettings{}.lp_tolerance)  // lp only (validate)
    std::snprintf(lp_tol, sizeof lp_tol, ", LP tolerance %g", s.kinematic.lp_tolerance);
  std::fprintf(stderr, "unjam probe: %d contacts of %s, method %s%s%s%s%s%s%s%s, %d threads%s\n", total,
               o.dir.c_str(), o.method.c_str(), lp_tol, window, budget, accept, settle, lost, floor,
               omp_get_max_threads(), spread.c_str());
  CheckpointedCampaignResult r;
  {
    const InterruptGuard interrupts;
    r = run_checkpointed_campaign(p, s, state, *dist, run);
  }
  if (!r.finished)
    throw Interrupted("stopped after " + std::to_string(state.rows.size()) +
                " probes; run the same command again to resume");
  const RunTime time{r.wall_s, dist->loads(), r.time};
  if (shards > 1)
    write_shard(o, run.fingerprint, run.settings, state, time, out / shard_file_name("probe_shard", shard, shards));
  else
    finish_campaign(o, p, s, state, time, out);
  fs::remove(run.checkpoint);
}

// A finished shard: its state, what merge needs to write the outputs, its own run.
void write_shard(const ProbeOptions& o, const std::string& fingerprint, const nlohmann::json& settings_json,
                 const CampaignState& state, const RunTime& time, const fs::path& file) {
  const nlohmann::json j = {{"packing", fingerprint}, {"settings", settings_json}, {"state", to_json(state)},
                            {"options", {{"fit_window", o.fit_window}}},  // the summary's; the rest is in settings
                            {"shard", o.shard}, {"command", command_line()}, {"program_version", kVersion},
                            {"wall_seconds", time.wall}, {"ranks", rank_loads_json<nlohmann::json>(time.loads, "probes")},
                            {"all_runs", to_json(time.all_runs)}, {"probe_cpu", probe_cpu_json(state)}};
  write_file_atomic(file, j.dump());
  std::printf("shard %s: %zu probes of %s in %s -> %s (merge the shards with `unjam merge`)\n",
              o.shard.c_str(), state.rows.size(), o.dir.c_str(), format_duration(time.wall).c_str(),
              file.c_str());
}

// The accepted residual of a cd campaign (g; 0: none, only exact probes stop it early).
double accepted_residual(const CampaignSettings& s) {
  return s.method == ProbeMethod::kCd && s.cd.accept_residual != CdPathSettings{}.accept_residual
             ? s.cd.accept_residual
             : 0.0;
}

// The campaign's report on stdout: its means, the probes left out, the inertia and states of
// the steps, the fit of d(r) and the time of its runs.
void print_campaign_report(const ProbeOptions& o, const Packing& p, const CampaignSettings& s,
                           const CampaignSummary& sum, const PackingStats& stats, const OverBudget& over_budget,
                           int accepted, const CampaignState& state, const RunTime& time, const fs::path& out,
                           int planned) {
  const char* method = method_name(s.method);
  if (planned > 0)
    std::printf("%d of %d probes of %s (method %s) so far, from the campaign's checkpoint -> %s (partial)\n",
                sum.probes, planned, o.dir.c_str(), method, out.c_str());
  else
    std::printf("%d probes of %s (method %s) in %s -> %s\n", sum.probes, o.dir.c_str(), method,
                format_duration(time.wall).c_str(), out.c_str());
  std::printf("  N %zu  mu %g  phi %.4f  z %.3f  <F_cont>/F0 %.4f\n", p.size(), p.meta.contact.mu, stats.phi,
              stats.z, sum.F_cont_over_F0);
  std::printf("  <F_crit>/<F_cont> %.4f", sum.F_crit_over_F_cont);
  if (std::isfinite(sum.F_crit_over_F_cont_err)) std::printf(" +- %.4f", sum.F_crit_over_F_cont_err);
  std::printf("   not converged: %d", sum.not_converged);
  if (sum.without_solution > 0)
    std::printf(" (%d without a solution, left out of the means)", sum.without_solution);
  std::printf("\n");
  if (s.cd.max_probe_pieces > 0) {  // cd only (validate)
    std::printf("  stopped by the budget of %lld pieces per probe (--cd-max-pieces): %d probes",
                s.cd.max_probe_pieces, over_budget.probes);
    // Exact all the same: their lowerings went on past an exact solution (at low friction
    // --cd-settle-compliance ends them there).
    if (over_budget.exact > 0)
      std::printf(", %d of them exact (a lowering went on past the solution: docs/probe.md, \"Settling at an "
                  "exact solution\")",
                  over_budget.exact);
    std::printf("\n");
  }
  if (const double accept = accepted_residual(s); accept > 0.0)
    std::printf("  near-exact within the accepted residual of %g g (--cd-accept-residual): %d probes\n", accept,
                accepted);
  if (s.max_inertia > 0.0)
    std::printf("  left out of the means and averages: %d probes with f_inertia above %g F0 (--max-inertia)\n",
                sum.inertial, s.max_inertia);
  if (sum.inertia_probes > 0) {
    std::printf("  inertia of the step (largest net force on a grain) / F0: median %.2e, largest %.2e (contact %d)",
                sum.f_inertia_median_over_F0, sum.f_inertia_max_over_F0, sum.f_inertia_max_contact);
    if (sum.inertia_probes < sum.probes)  // rows of a checkpoint written before f_inertia, or without a solution
      std::printf(", over the %d probes that record it", sum.inertia_probes);
    std::printf("\n");
  }
  if (sum.state_probes > 0)
    std::printf("  contacts loaded in the packing that the step opens / sets sliding: median %g / %g over %d probes\n",
                sum.opened_median, sum.sliding_median, sum.state_probes);
  if (sum.has_fit)
    std::printf("  d(r) ~ r^-alpha: alpha = %.3f +- %.3f  (fit over r in [%.2f, %.2f], %d bins, R2 %.3f)\n",
                sum.fit.alpha, sum.fit.alpha_err, sum.fit.r_lo, sum.fit.r_hi, sum.fit.bins, sum.fit.R2);
  else
    std::printf("  no power-law fit: %s\n", sum.fit_error.c_str());
  // A windowed campaign's fields are zero beyond the window: its d(r) is the clamp's.
  if (s.nlgs.window > 0.0)
    std::printf("  d(r) and alpha are those of windows of %g mean diameters, every grain beyond clamped: not the "
                "whole packing's decay (docs/probe.md, \"A window around the probed pair\")\n",
                s.nlgs.window);
  const CampaignTime& all = time.all_runs;
  if (all.runs > 1 || all.untimed > 0 || planned > 0) {
    std::printf("  over %d run%s: %s of wall time, %s busy", all.runs, all.runs == 1 ? "" : "s",
                format_duration(all.wall_seconds).c_str(), format_duration(all.busy_seconds).c_str());
    const long long timed = static_cast<long long>(sum.probes) - all.untimed;
    if (timed > 0) {
      std::printf(" (%s per probe", format_duration(all.busy_seconds / static_cast<double>(timed)).c_str());
      if (all.untimed > 0) std::printf(" over the %lld timed", timed);
      std::printf(")");
    }
    if (all.untimed > 0)
      std::printf("; %lld probes from a checkpoint that did not record its time", all.untimed);
    std::printf("\n");
  }
  if (const ProbeCpu cpu = probe_cpu(state.rows); cpu.timed > 0) {
    std::printf("  CPU per probe: median %s, 90 %% below %s, largest %s (contact %d)",
                format_seconds(cpu.median).c_str(), format_seconds(cpu.p90).c_str(), format_seconds(cpu.max).c_str(),
                cpu.max_contact);
    if (cpu.exact > 0 && cpu.exact < cpu.timed)
      std::printf("; exact %s, near-exact %s, without a solution %s (medians)",
                  format_seconds(cpu.exact_median).c_str(),
                  cpu.near_exact > 0 ? format_seconds(cpu.near_exact_median).c_str() : "-",
                  cpu.no_solution > 0 ? format_seconds(cpu.no_solution_median).c_str() : "-");
    if (cpu.timed < sum.probes) std::printf("; over the %d probes that record it", cpu.timed);
    std::printf("\n");
  }
  if (time.loads.size() > 1)
    for (const RankLoad& l : time.loads)
      std::printf("  rank %d: %lld probes, %s busy (%d threads)\n", l.rank, l.tasks,
                  format_duration(l.busy_seconds).c_str(), l.threads);
}

// probes.csv, response_field.csv, response_profile.csv, probe_summary.json and the report.
// planned > 0: the outputs of a campaign's checkpoint (--partial), which has not probed all
// `planned` contacts yet; its wall time and ranks are unknown (null, []).
void finish_campaign(const ProbeOptions& o, const Packing& p, const CampaignSettings& s,
                     const CampaignState& state, const RunTime& time, const fs::path& out, int planned) {
  const CampaignSummary sum = summarize(p, state, fit_window(o), s.max_inertia);
  const PackingStats stats = compute_packing_stats(p);
  write_file_atomic(out / "probes.csv", rows_csv(state, method_name(s.method)));
  write_file_atomic(out / "response_field.csv", state.average.field_csv());
  write_file_atomic(out / "response_profile.csv", state.average.profile_csv());
  write_file_atomic(out / "probe_cpu.csv", probe_cpu_csv(state));
  nlohmann::json summary = campaign_summary_json(p, stats, sum);
  // cd with a budget: the probes it stopped, whose sweeps (pieces of all paths) exceed it by
  // the one not taken.
  const long long max_pieces = s.cd.max_probe_pieces;  // > 0: cd only (validate)
  const OverBudget over_budget = probes_over_budget(state, max_pieces);
  if (max_pieces > 0)
    summary["over_budget"] = {{"max_pieces", max_pieces}, {"probes", over_budget.probes}, {"exact", over_budget.exact}};
  // cd with a residual it accepts: the probes near-exact within it.
  const double accept = accepted_residual(s);
  const int accepted = probes_accepted(state, accept);
  if (accept > 0.0) summary["accepted"] = {{"accept_residual", accept}, {"probes", accepted}};
  summary["program_version"] = kVersion;
  summary["command"] = command_line();
  summary["packing"] = o.dir;
  summary["settings"] = to_json(s);
  summary["method"] = method_name(s.method);
  summary["g"] = s.nlgs.g;
  summary["wall_seconds"] = planned > 0 ? nlohmann::json(nullptr) : nlohmann::json(time.wall);
  summary["ranks"] = rank_loads_json<nlohmann::json>(time.loads, "probes");
  summary["all_runs"] = to_json(time.all_runs);
  summary["cpu_per_probe"] = to_json(probe_cpu(state.rows));
  if (planned > 0) summary["partial"] = {{"probes_done", sum.probes}, {"probes_planned", planned}};
  write_file_atomic(out / "probe_summary.json", summary.dump(2));
  print_campaign_report(o, p, s, sum, stats, over_budget, accepted, state, time, out, planned);
}

void run(const ProbeOptions& o) {
  const int modes = (o.contact >= 0) + o.all + (o.sample > 0);
  if (modes != 1) throw Error("give exactly one of --contact K, --all, --sample K");
  if (!o.export_problem.empty() && o.contact < 0) throw Error("--export-problem goes with --contact K");
  if (!o.partial.empty() && o.contact >= 0) throw Error("--partial goes with --all or --sample K (a campaign)");
  const Packing p = read_packing(o.dir);
  if (!p.state.is_static)
    std::fprintf(stderr, "warning: %s is not marked static (its compaction did not finish)\n", o.dir.c_str());
  if (o.threads > 0) omp_set_num_threads(o.threads);
  const CampaignSettings s = campaign_settings(o, p);
  const fs::path out = o.out.empty() ? fs::path(o.dir) : fs::path(o.out);
  if (o.contact >= 0) {
    if (o.contact >= static_cast<int>(p.contacts.size()))
      throw Error("--contact " + std::to_string(o.contact) + ": the packing has " +
                  std::to_string(p.contacts.size()) + " contacts");
    const DirLock lock(out, command_line());
    run_single(o, p, s, out);
  } else {
    run_all(o, p, s, out);
  }
}

}  // namespace

bool merge_probe_shards(const std::string& dir, const std::string& out_dir) {
  const fs::path out = out_dir.empty() ? fs::path(dir) : fs::path(out_dir);
  const Packing p = read_packing(dir);
  const std::vector<ShardFile> shards = read_shards(out, "probe_shard");
  if (shards.empty()) return false;
  ProbeOptions o;
  o.dir = dir;
  const ShardFile& first = shards.front();
  // The settings the shards' campaign records, read back (campaign_settings_from_json refuses
  // a record it would not have written on p).
  CampaignSettings s;
  read_shard(first, [&] {
    s = campaign_settings_from_json(first.json.at("settings"), p, "the settings of the shards in " + out.string());
    o.fit_window = first.json.at("options").at("fit_window").get<std::vector<double>>();
  });
  CampaignState state = empty_campaign_state(p);
  RunTime time;
  const std::string fingerprint = packing_fingerprint(p);
  const std::vector<int> targets = campaign_targets(p, s);
  const std::string whole = "the campaign's " + std::to_string(targets.size()) + " probed contacts";
  std::vector<bool> seen;
  for (const ShardFile& shard : shards) {
    const nlohmann::json& j = shard.json;
    if (j.value("packing", std::string()) != fingerprint)
      throw Error("the shards in " + out.string() + " were probed on another packing than " + dir);
    if (j.value("settings", nlohmann::json()) != first.json.at("settings") ||
        j.value("options", nlohmann::json()) != first.json.at("options"))
      throw Error("the shards in " + out.string() + " come from runs with other settings");
    read_shard(shard, [&] {
      CampaignState part = campaign_state_from_json(j.at("state"), p);
      set_probe_cpu(part, j.value("probe_cpu", nlohmann::json()));
      std::vector<int> contacts;
      for (const ProbeRow& r : part.rows) contacts.push_back(r.contact);
      claim_shard_contacts(shard, contacts, targets, whole, seen);
      for (const ProbeRow& r : part.rows) state.rows.push_back(r);
      state.average.merge(part.average);
      time.wall = std::max(time.wall, non_negative_number(j, "wall_seconds"));
      RankLoad load;
      load.rank = static_cast<int>(time.loads.size());
      load.tasks = static_cast<long long>(part.rows.size());
      if (!j.at("ranks").is_array()) throw Error("ranks is not an array");
      for (const auto& l : j.at("ranks")) load.busy_seconds += non_negative_number(l, "busy_seconds");
      time.loads.push_back(load);
      // every shard's runs (a shard written before they were recorded: its probes untimed)
      time.all_runs = time.all_runs + campaign_time_from_json(j.value("all_runs", nlohmann::json()),
                                                              static_cast<long long>(part.rows.size()));
    });
  }
  const auto missing = std::find(seen.begin(), seen.end(), false);
  if (missing != seen.end())
    throw Error("the probe shards in " + out.string() + " do not cover every probed contact of " + dir +
                " (contact " + std::to_string(targets[static_cast<std::size_t>(missing - seen.begin())]) +
                " is in none)");
  std::sort(state.rows.begin(), state.rows.end(),
            [](const ProbeRow& x, const ProbeRow& y) { return x.contact < y.contact; });
  finish_campaign(o, p, s, state, time, out);
  return true;
}

void add_probe_command(CLI::App& app) {
  auto o = std::make_shared<ProbeOptions>();
  CLI::App* cmd = app.add_subcommand("probe", "open contacts by a tiny gap: critical force and displacement field");
  cmd->add_option("dir", o->dir, "static packing directory")->required();
  cmd->add_option("--contact", o->contact, "probe this contact (row of contacts.csv, from 0)")
      ->check(non_negative_number());
  cmd->add_flag("--all", o->all, "probe every force-carrying contact");
  cmd->add_option("--sample", o->sample, "probe a seeded random subset of this many force-carrying contacts")
      ->check(non_negative_number());
  cmd->add_option("--seed", o->seed, "seed of --sample")->capture_default_str()->check(seed_value());
  cmd->add_option("--method", o->method,
                  "lp: F_crit as the LP maximum and the kinematic field at its optimum (fast); "
                  "nlgs: the paper's contact-dynamics probe (reference, slow); "
                  "lemke: the same step solved exactly by Lemke's method (dense, up to ~1200 contacts); "
                  "cd: the same step solved exactly along its path from the static network (sparse; each probe's residual says whether it is exact, docs/probe.md)")
      ->capture_default_str();
  add_cd_path_options(cmd, o->cd, o->cd_start);
  cmd->add_option("--window", o->window,
                  "lemke, cd: solve the step on the grains within this many mean diameters of the probed pair only, "
                  "every other grain clamped to the cell. Not the paper's probe: F_crit of the clamped window, the "
                  "whole packing's only where the window covers the cell (at 500 disks and 10 diameters, 15-80 % above "
                  "it; docs/probe.md, \"A window around the probed pair\"; default: the whole packing)")
      ->check(positive_number());
  cmd->add_option("--export-problem", o->export_problem,
                  "with --contact: write the probe step in Siconos' frictional contact problem format");
  cmd->add_option("--out", o->out, "output directory (default: the packing directory)");
  cmd->add_option("--g", o->g, "opening gap g (R_max)")->capture_default_str()->check(positive_number());
  add_lp_tol_option(cmd, o->lp_tol, "lp: ");
  cmd->add_option("--dt", o->dt,
                  "nlgs, lemke, cd: time step of the probe (default: lemke, cd sqrt(g / 1e-5), the "
                  "quasi-static limit, 1e-2 at g = 1e-9; nlgs 1e-3)")
      ->check(positive_number());
  cmd->add_option("--max-inertia", o->max_inertia,
                  "nlgs, lemke, cd: leave out of the averages and means the probes whose step's largest net force on "
                  "a grain, f_inertia, exceeds this many F0 (a region sliding away: no quasi-static field; their rows "
                  "stay; docs/probe.md, \"The inertia of the step\"; default: none)")
      ->check(positive_number());
  cmd->add_option("--velocity-tol", o->velocity_tol, "nlgs: converged when max |dU| per sweep < tol g/dt")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--max-sweeps", o->max_sweeps, "nlgs: sweeps at most per probe")->capture_default_str()->check(positive_number());
  cmd->add_option("--displacement", o->displacement,
                  "displacement in the averages: peculiar, or total (with the affine part of the cell)")->capture_default_str();
  cmd->add_option("--threads", o->threads, "OpenMP threads (0: all cores); results do not depend on it")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--checkpoint", o->checkpoint_s, "seconds between checkpoints of --all / --sample")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--fit-window", o->fit_window,
                  "r_lo r_hi of the power-law fit of d(r) (R_max; default [<2R>, min(10 <2R>, L/2)])")
      ->expected(2);
  cmd->add_option("--running-every", o->running_every,
                  "seconds of a probe between its 'probing for' lines (cd, nlgs, lemke; 0: at every poll)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_flag("--quiet", o->quiet, "no progress lines");
  cmd->add_option("--shard", o->shard,
                  "i/K: probe only every K-th target from the i-th (the targets at places p with p mod K = i in the "
                  "sorted list of contacts to probe, so a sample too is shared evenly; one job of a job array; "
                  "`unjam merge` joins the K shards into the outputs of one run)");
  cmd->add_option("--stop-after", o->stop_after,
                  "stop after this many new probes, saving the checkpoint (as Ctrl-C; rerun to resume)")
      ->check(non_negative_number());
  cmd->add_option("--partial", o->partial,
                  "with --all / --sample: write the outputs of the probes the campaign has finished so far "
                  "(its checkpoint in --out, while it runs or after it stopped) to this other directory, "
                  "probing nothing; probe_summary.json records them as partial");
  cmd->callback([o] { run(*o); });
}

}  // namespace unjam::cli
