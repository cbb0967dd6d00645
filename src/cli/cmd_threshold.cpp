// `unjam threshold DIR`: the friction threshold mu_s of the packing, the smallest Coulomb
// coefficient at which its contacts still admit a force network (docs/ensemble.md, "The
// friction threshold"), by bisection on the LP's feasibility (ensemble/friction_threshold).
// Writes DIR/friction_threshold.json (or --out): the bracket, mu_s / mu, the LPs, the
// parameters, the version and the command. A stopped run (Ctrl-C, SIGTERM, --stop-after) keeps
// its bracket in friction_threshold_checkpoint.json beside it (campaign/threshold_checkpoint),
// and the same command resumes from it.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "unjam/campaign/threshold_checkpoint.hpp"
#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/ensemble/friction_threshold.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::cli {

namespace {

struct ThresholdOptions {
  std::string dir;
  std::string out;         // JSON path; default DIR/friction_threshold.json
  double rel_tol = 1e-3;   // the bracket's width, relative to the packing's mu
  double gap_tol = 1e-9;   // touching contacts: gap < gap_tol (R_max)
  double fn_tol = 1e-9;    // force-carrying contacts: fn > fn_tol F0
  std::vector<double> between;  // LO HI: a bracket to start from
  int stop_after = 0;           // stop after this many LPs of this run (0: never), as Ctrl-C
  bool quiet = false;
};

std::string bracket_text(double lo, double hi) {
  char buf[96];
  if (hi == 0.0) return "mu_s = 0 (an admissible network without friction)";
  std::snprintf(buf, sizeof buf, "mu_s in (%.6g, %.6g]", lo, hi);
  return buf;
}

// friction_threshold.json: the bracket, the parameters, the LPs, the version and the command.
// `resumed`: the checkpoint's progress this run started from, if any; r holds every run's LPs.
nlohmann::ordered_json threshold_json(const ThresholdOptions& opt, const Packing& packing, const EquilibriumSystem& sys,
                                      const FrictionThresholdOptions& o, const FrictionThreshold& r, double total_s,
                                      const std::optional<ThresholdProgress>& resumed) {
  return {
      {"program_version", kVersion},
      {"command", command_line()},
      {"packing", opt.dir},
      {"N", packing.size()},
      {"mu", r.mu},
      {"mu_s_low", r.mu_low},
      {"mu_s_high", r.mu_high},
      {"mu_s_over_mu", r.mu > 0.0 ? r.mu_high / r.mu : 0.0},
      {"contacts_listed", packing.contacts.size()},
      {"contacts_used", sys.num_contacts()},
      {"grains_with_contacts", sys.grains.size()},
      {"parameters",
       {{"rel_tol", opt.rel_tol}, {"gap_tol", opt.gap_tol}, {"fn_tol_F0", opt.fn_tol},
        {"between", opt.between.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(opt.between)},
        {"lp_tolerance", o.tolerance}, {"lp_method", "dual simplex"}}},
      {"lps", r.lps},
      {"simplex_iterations", r.iterations},
      {"runs", resumed ? resumed->runs + 1 : 1},
      {"resumed_from",
       resumed ? nlohmann::ordered_json{resumed->so_far.mu_low, resumed->so_far.mu_high} : nlohmann::ordered_json()},
      {"timings_s", {{"lp", r.seconds}, {"total", total_s}}},
  };
}

// The bisection with a progress line per LP (stderr), stopped by Ctrl-C, SIGTERM or --stop-after
// between two LPs: then Interrupted (exit code 3) with the bracket reached. The checkpoint
// resumes it and keeps its bracket once both ends are checked (ThresholdCheckpoint::attach);
// the result holds every run's LPs, iterations and time.
FrictionThreshold bisect(const ThresholdOptions& opt, const EquilibriumSystem& sys, FrictionThresholdOptions& o,
                         const ThresholdCheckpoint& checkpoint) {
  o.rel_tol = opt.rel_tol;
  const std::optional<ThresholdProgress>& resumed = checkpoint.resumed();
  if (resumed && !opt.between.empty())
    throw Error(checkpoint.file().string() + " holds the bracket of a stopped run; run without --between to "
                "continue it, or remove it to start from --between");
  if (resumed)
    std::fprintf(stderr, "threshold: resuming from %s (%s: %d LPs in %d run%s)\n",
                 bracket_text(resumed->so_far.mu_low, resumed->so_far.mu_high).c_str(),
                 checkpoint.file().string().c_str(), resumed->so_far.lps, resumed->runs,
                 resumed->runs == 1 ? "" : "s");
  else if (!opt.between.empty()) {
    o.mu_low = opt.between[0];
    o.mu_high = opt.between[1];
  }
  double lo = 0.0, hi = 0.0;  // the bracket reached, for the message of a stopped run
  int lps = 0;
  const auto t_lp = std::chrono::steady_clock::now();
  o.progress = [&](int total, const FrictionThreshold& so_far) {
    lo = so_far.mu_low;
    hi = so_far.mu_high;
    lps = so_far.lps;
    if (opt.quiet) return;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_lp).count();
    std::fprintf(stderr, "threshold: %d / %d LPs, %s, %s elapsed, ETA %s\n", lps, total, bracket_text(lo, hi).c_str(),
                 format_duration(t).c_str(), format_duration(t * (total - lps) / lps).c_str());
  };
  checkpoint.attach(o);  // the bracket read, if any, is now o's
  lo = std::isnan(o.mu_low) ? 0.0 : o.mu_low;
  hi = std::isnan(o.mu_high) ? sys.mu : o.mu_high;
  o.should_stop = [&] { return InterruptGuard::requested() || (opt.stop_after > 0 && lps >= opt.stop_after); };
  try {
    const InterruptGuard interrupts;
    return checkpoint.with_earlier(friction_threshold(sys, o));
  } catch (const Cancelled&) {
    if (std::filesystem::exists(checkpoint.file()))  // read at the start, or saved by this run
      throw Interrupted("stopped with " + bracket_text(lo, hi) + "; run the same command again to continue from it (" +
                        checkpoint.file().string() + ")");
    char buf[64];
    std::snprintf(buf, sizeof buf, "--between %.17g %.17g", lo, hi);
    throw Interrupted("stopped with " + bracket_text(lo, hi) + "; add " + buf + " to continue from it");
  }
}

void run_threshold(const ThresholdOptions& opt) {
  if (!(opt.rel_tol < 1.0)) throw Error("--rel-tol must be in (0, 1) (got " + std::to_string(opt.rel_tol) + ")");
  const auto t_start = std::chrono::steady_clock::now();
  const Packing packing = read_packing(opt.dir);
  const std::filesystem::path out =
      opt.out.empty() ? std::filesystem::path(opt.dir) / "friction_threshold.json" : std::filesystem::path(opt.out);
  const DirLock lock(out.parent_path().empty() ? "." : out.parent_path(), command_line());
  const EquilibriumSystem sys = admissible_system(packing, opt.gap_tol, opt.fn_tol);
  const ThresholdCheckpoint checkpoint(
      out.parent_path() / (out.stem().string() + "_checkpoint.json"),
      threshold_checkpoint_settings(packing, opt.gap_tol, opt.fn_tol, sys.num_contacts(), sys.mu, opt.rel_tol));
  FrictionThresholdOptions o;
  const FrictionThreshold r = bisect(opt, sys, o, checkpoint);
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  write_file_atomic(out, threshold_json(opt, packing, sys, o, r, total_s, checkpoint.resumed()).dump(2) + "\n");
  checkpoint.remove();
  std::printf("friction threshold %s", bracket_text(r.mu_low, r.mu_high).c_str());
  if (r.mu > 0.0) std::printf(", mu_s / mu = %.4g (mu = %.6g)", r.mu_high / r.mu, r.mu);
  std::printf("\ncontacts used      %d of %zu (grains with contacts %zu)\n", sys.num_contacts(),
              packing.contacts.size(), sys.grains.size());
  std::printf("LPs                %d (dual simplex, %lld iterations), %s\n", r.lps, r.iterations,
              format_duration(r.seconds).c_str());
  std::printf("wrote              %s\n", out.string().c_str());
}

}  // namespace

void add_threshold_command(CLI::App& app) {
  auto opt = std::make_shared<ThresholdOptions>();
  CLI::App* cmd = app.add_subcommand(
      "threshold", "friction threshold mu_s: the smallest friction coefficient at which the packing's "
                   "contacts still admit a force network (LP feasibility, bisection)");
  cmd->add_option("DIR", opt->dir, "packing directory")->required();
  cmd->add_option("--out", opt->out, "JSON output (default DIR/friction_threshold.json)");
  cmd->add_option("--rel-tol", opt->rel_tol, "stop once the bracket is narrower than rel-tol x mu")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--between", opt->between,
                  "LO HI: start from this bracket (no network at LO, one at HI; both checked), as a "
                  "stopped run prints it")
      ->expected(2)->check(non_negative_number());
  cmd->add_option("--stop-after", opt->stop_after,
                  "stop after this many LPs, keeping the bracket reached in the checkpoint (as Ctrl-C; run "
                  "again to resume)")
      ->check(non_negative_number());
  add_contact_selection_options(cmd, opt->gap_tol, opt->fn_tol);
  cmd->add_flag("--quiet", opt->quiet, "no progress lines");
  cmd->callback([opt] { run_threshold(*opt); });
}

}  // namespace unjam::cli
