// `unjam bounds DIR`: the exact interval [fn_min, fn_max] of every contact's normal force over
// the admissible force networks (PHYSICS.md section 7, docs/ensemble.md), by LP.
// Writes DIR/bounds.csv (a,b,fn,fn_min,fn_max; 17 significant digits, force units of the
// packing) and DIR/bounds.json (dimension, rank, contacts, timings, parameters, version).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::cli {

namespace {

struct BoundsOptions {
  std::string dir;
  std::string out;          // CSV path; default DIR/bounds.csv, JSON beside it
  double gap_tol = 1e-9;    // touching: gap <= gap_tol (units of R_max)
  double fn_tol = 1e-9;     // force-carrying: fn > fn_tol F0
  int threads = 0;          // 0: all cores
  std::string method = "barrier";
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void run_bounds(const BoundsOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const Packing packing = read_packing(opt.dir);
  const std::filesystem::path csv_path =
      opt.out.empty() ? std::filesystem::path(opt.dir) / "bounds.csv" : std::filesystem::path(opt.out);
  const DirLock lock(csv_path.has_parent_path() ? csv_path.parent_path() : ".", command_line());
  const EquilibriumSystem sys =
      build_equilibrium_system(packing, select_contacts(packing, opt.gap_tol, opt.fn_tol));
  const double t_build = seconds_since(t_start);
  const auto t_rank = std::chrono::steady_clock::now();
  const RankInfo rank = equilibrium_rank(sys);
  const double rank_seconds = seconds_since(t_rank);

  ForceBoundsOptions lp;
  lp.threads = thread_count(opt.threads);
  lp.method = opt.method == "simplex" ? LpMethod::simplex : LpMethod::barrier;
  const int Nc = sys.num_contacts();
  if (Nc >= 500) {
    int next_report = 0;
    lp.progress = [&next_report, t_lp = std::chrono::steady_clock::now()](int done, int total) {
      if (done < next_report && done < total) return;
      next_report = done + std::max(1, total / 20);
      const double t = seconds_since(t_lp);
      std::fprintf(stderr, "bounds: %d / %d LPs, %s elapsed, ETA %s\n", done, total,
                   format_duration(t).c_str(),
                   done > 0 ? format_duration(t * (total - done) / done).c_str() : "?");
    };
  }
  const ForceBounds bounds = compute_force_bounds(sys, lp);

  std::string csv = "a,b,fn,fn_min,fn_max\n";
  double sum_width = 0.0, sum_fn = 0.0;
  char line[160];
  for (int k = 0; k < Nc; ++k) {
    const Contact& c = packing.contacts[sys.contacts[k]];
    std::snprintf(line, sizeof line, "%d,%d,%.17g,%.17g,%.17g\n", c.a, c.b, c.fn,
                  bounds.fn_min[k], bounds.fn_max[k]);
    csv += line;
    sum_width += bounds.fn_max[k] - bounds.fn_min[k];
    sum_fn += c.fn;
  }
  const double width_over_fn = sum_fn > 0.0 ? sum_width / sum_fn : 0.0;
  std::filesystem::path json_path = csv_path;
  json_path.replace_extension(".json");
  write_file_atomic(csv_path, csv);

  const double total = seconds_since(t_start);
  const nlohmann::ordered_json j = {
      {"program_version", kVersion},
      {"packing", opt.dir},
      {"N", packing.size()},
      {"mu", sys.mu},
      {"P_ext", packing.meta.P_ext},
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
        {"method", opt.method}, {"lp_tolerance", lp.tolerance}}},
      {"min_lps_skipped", bounds.min_lps_skipped},
      {"iterations", bounds.iterations},
      {"lps_at_looser_tolerance", bounds.loosened_solves},
      {"timings_s",
       {{"read_and_build", t_build}, {"rank", rank_seconds}, {"lp", bounds.seconds},
        {"lp_per_contact", Nc > 0 ? bounds.seconds / Nc : 0.0}, {"total", total}}},
  };
  write_file_atomic(json_path, j.dump(2) + "\n");

  std::printf("contacts used      %d of %zu (grains with contacts %zu)\n", Nc,
              packing.contacts.size(), sys.grains.size());
  std::printf("dimension          %d (cone columns %d, rank %d)\n", rank.dimension, rank.columns,
              rank.rank);
  std::printf("mean width / <fn>  %.6g\n", width_over_fn);
  std::printf("fn_min = 0 without own LP  %d contacts\n", bounds.min_lps_skipped);
  if (bounds.loosened_solves > 0)
    std::printf("barrier stalls     %lld LPs solved again at 10-100x the tolerance\n",
                bounds.loosened_solves);
  std::printf("time per contact   %.3g s (LP %.3g s, %s, %d threads)\n",
              Nc > 0 ? bounds.seconds / Nc : 0.0, bounds.seconds, opt.method.c_str(), lp.threads);
  std::printf("wrote              %s, %s\n", csv_path.string().c_str(), json_path.string().c_str());
}

}  // namespace

void add_bounds_command(CLI::App& app) {
  auto opt = std::make_shared<BoundsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bounds", "exact interval [fn_min, fn_max] of every contact's normal force over the "
                "admissible force networks (LP)");
  cmd->add_option("DIR", opt->dir, "packing directory")->required();
  cmd->add_option("--out", opt->out, "CSV output (default DIR/bounds.csv; JSON beside it)");
  cmd->add_option("--gap-tol", opt->gap_tol, "touching contacts: gap <= gap-tol (R_max)")
      ->check(non_negative_number());
  cmd->add_option("--fn-tol", opt->fn_tol, "force-carrying contacts: fn > fn-tol F0")
      ->check(non_negative_number());
  cmd->add_option("--threads", opt->threads, "OpenMP threads (0: all cores)")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--method", opt->method, "LP method: barrier (default) or simplex")
      ->check(CLI::IsMember({"barrier", "simplex"}));
  cmd->callback([opt] { run_bounds(*opt); });
}

}  // namespace unjam::cli
