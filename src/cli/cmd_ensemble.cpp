// `unjam ensemble DIR`: the admissible force networks of a packing (PHYSICS.md section 7,
// docs/ensemble.md) sampled by hit-and-run (uniform) and/or by the paper's random walk of
// kicks relaxed by contact dynamics, the exact LP interval of every contact, and the
// critical force F_crit of every force-carrying contact (section 6): everything the
// paper's Fig. 4 draws (scripts/plot_fig4.py).
// Writes
//   DIR/ensemble.csv   one row per contact of the admissible set (force units of the
//                      packing, shortest round-trip decimals):
//                      a,b,fn,fn_min,fn_max
//                      [,hr_min,hr_max,hr_mean,hr_std]        with --method hit-and-run|both
//                      [,walk_min,walk_max,walk_mean,walk_std]  with --method walk|both
//                      [,f_crit,f_crit_method,probe_converged,probe_sweeps]  unless --probe
//                      none; f_crit and the rest are empty for a contact without force
//                      (fn <= fn-tol F0), f_crit_method is "nlgs" or "lp";
//   DIR/ensemble.json  eta and coverage of the LP widths per method, F_crit / fn_max
//                      statistics, settings, timings, version, command line;
//   DIR/ensemble-samples.csv with --write-samples (hit-and-run samples: fn of every contact).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/ensemble/hit_and_run.hpp"
#include "unjam/ensemble/random_walk.hpp"
#include "unjam/packing/csv_table.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/kinematic_probe.hpp"
#include "unjam/probe/nlgs_probe.hpp"

namespace unjam::cli {

namespace {

struct EnsembleOptions {
  std::string dir;
  std::string method = "both";  // hit-and-run | walk | both
  std::string probe;            // nlgs | lp | none; empty: nlgs up to 200 contacts, else lp
  int samples = 20000;
  std::uint64_t seed = 1;
  int thin = 0;
  int burn_in = 0;
  double kick = 1.0;            // walk kick amplitude / <F_n>
  double walk_tol = 1e-10;      // walk relaxation residual / F0
  double probe_g = 1e-9;        // probe opening (R_max)
  double probe_dt = 1e-3;       // nlgs probe time step (t0)
  double probe_velocity_tol = 1e-6;  // nlgs probe: max |dU| per sweep < this g / dt
  double gap_tol = 1e-9;
  double fn_tol = 1e-9;
  int threads = 0;  // 0: all cores
  bool write_samples = false;
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Per-contact statistics of one sampler, as both samplers report them.
struct SamplerColumns {
  Eigen::VectorXd min, max, mean, std;
};

// Mean over contacts with a nonzero LP width of (sampled width) / (LP width).
double mean_coverage(const SamplerColumns& s, const ForceBounds& b, double F0) {
  double sum = 0.0;
  int n = 0;
  for (Eigen::Index k = 0; k < b.fn_max.size(); ++k) {
    const double width = b.fn_max[k] - b.fn_min[k];
    if (width > 1e-9 * F0) {
      sum += (s.max[k] - s.min[k]) / width;
      ++n;
    }
  }
  return n > 0 ? sum / n : 1.0;
}

// Quantiles of x (sorted copy, linear interpolation), x non-empty.
double quantile(std::vector<double> x, double q) {
  std::sort(x.begin(), x.end());
  const double pos = q * (x.size() - 1.0);
  const std::size_t i = static_cast<std::size_t>(pos);
  if (i + 1 >= x.size()) return x.back();
  return x[i] + (pos - i) * (x[i + 1] - x[i]);
}

// Prints "<what>: done / total, t s" on stderr at most every 2 s, and at the end.
class Progress {
 public:
  Progress(std::string what, int total)
      : what_(std::move(what)), total_(total), start_(std::chrono::steady_clock::now()) {}
  void operator()(int done) {
    const double t = seconds_since(start_);
    if (t < next_s_ && done < total_) return;
    next_s_ = t + 2.0;
    std::fprintf(stderr, "%s: %d / %d, %.1f s\n", what_.c_str(), done, total_, t);
  }

 private:
  std::string what_;
  int total_;
  double next_s_ = 2.0;
  std::chrono::steady_clock::time_point start_;
};

// F_crit of every contact of the system that carries force, by the nlgs or the lp probe,
// contacts split over OpenMP threads (one KinematicProbe per thread).
struct ProbeColumns {
  std::vector<std::optional<ProbeResult>> result;  // per contact of the system
  double seconds = 0.0;
};

ProbeColumns run_probes(const Packing& packing, const EquilibriumSystem& sys,
                        const EnsembleOptions& opt, const std::string& method) {
  ProbeColumns out;
  out.result.resize(sys.num_contacts());
  std::vector<int> todo;
  for (int k = 0; k < sys.num_contacts(); ++k)
    if (packing.contacts[sys.contacts[k]].fn > opt.fn_tol * sys.F0) todo.push_back(k);
  const auto t0 = std::chrono::steady_clock::now();
  ProbeSettings nlgs;
  nlgs.g = opt.probe_g;
  nlgs.dt = opt.probe_dt;
  nlgs.velocity_tol = opt.probe_velocity_tol;
  nlgs.bath.P_ext = packing.meta.P_ext;
  KinematicProbeSettings lp;
  lp.g = opt.probe_g;
  Progress progress("probe " + method + " (contacts)", static_cast<int>(todo.size()));
  int done = 0;
  const int n = static_cast<int>(todo.size());
#pragma omp parallel num_threads(opt.threads)
  {
    std::optional<KinematicProbe> kinematic;
    if (method == "lp") kinematic.emplace(packing, lp);
#pragma omp for schedule(dynamic, 1)
    for (int i = 0; i < n; ++i) {
      const int c = sys.contacts[todo[i]];
      out.result[todo[i]] = method == "lp" ? kinematic->probe(c) : probe_nlgs(packing, c, nlgs);
#pragma omp critical(ensemble_probe_progress)
      progress(++done);
    }
  }
  out.seconds = seconds_since(t0);
  return out;
}

void run_ensemble(const EnsembleOptions& given) {
  const auto t_start = std::chrono::steady_clock::now();
  EnsembleOptions opt = given;
  opt.threads = thread_count(opt.threads);
  const Packing packing = read_packing(opt.dir);
  const DirLock lock(opt.dir, command_line());
  const EquilibriumSystem sys =
      build_equilibrium_system(packing, select_contacts(packing, opt.gap_tol, opt.fn_tol));
  const int Nc = sys.num_contacts();
  const bool use_hr = opt.method != "walk", use_walk = opt.method != "hit-and-run";
  const std::string probe = !opt.probe.empty() ? opt.probe : Nc <= 200 ? "nlgs" : "lp";

  ForceBoundsOptions lp;
  lp.threads = opt.threads;
  const ForceBounds bounds = compute_force_bounds(sys, lp);

  nlohmann::ordered_json methods = nlohmann::ordered_json::object();
  std::optional<SamplerColumns> hr_cols, walk_cols;
  std::optional<CsvWriter> samples_csv;  // --write-samples: fn of every hit-and-run sample
  if (use_hr) {
    HitAndRunOptions hr;
    hr.samples = opt.samples;
    hr.seed = opt.seed;
    hr.thin = opt.thin;
    hr.burn_in = opt.burn_in;
    if (opt.write_samples) {
      std::vector<std::string> names;
      for (const int c : sys.contacts)
        names.push_back("fn_" + std::to_string(packing.contacts[c].a) + "_" +
                        std::to_string(packing.contacts[c].b));
      samples_csv.emplace(names);
      hr.on_sample = [&samples_csv](const ForceNetwork& net) {
        for (Eigen::Index k = 0; k < net.fn.size(); ++k) samples_csv->cell(net.fn[k]);
        samples_csv->end_row();
      };
    }
    std::fprintf(stderr, "hit-and-run: %d samples\n", opt.samples);
    const auto t = std::chrono::steady_clock::now();
    const HitAndRunResult r = sample_hit_and_run(sys, bounds, hr);
    const double seconds = seconds_since(t);
    hr_cols = SamplerColumns{r.sample_min, r.sample_max, r.mean, r.std};
    methods["hit_and_run"] = {
        {"description", "hit-and-run, uniform on the admissible polytope"},
        {"eta", r.eta},
        {"mean_fn", r.mean_fn},
        {"mean_coverage_of_lp_width", mean_coverage(*hr_cols, bounds, sys.F0)},
        {"samples", r.samples},
        {"steps", r.steps},
        {"dimension", r.dimension},
        {"contacts_open_in_every_network", r.fixed_open},
        {"start_depth", r.start_depth},
        {"thin", opt.thin},
        {"burn_in", opt.burn_in},
        {"seconds", seconds}};
  }
  if (use_walk) {
    RandomWalkOptions walk;
    walk.samples = opt.samples;
    walk.seed = opt.seed;
    walk.kick = opt.kick;
    walk.tol = opt.walk_tol;
    Progress progress("random walk (steps)", opt.samples);
    walk.progress = [&progress](int done, int) { progress(done); };
    const auto t = std::chrono::steady_clock::now();
    const RandomWalkResult r = sample_random_walk(packing, sys, walk);
    const double seconds = seconds_since(t);
    walk_cols = SamplerColumns{r.sample_min, r.sample_max, r.mean, r.std};
    methods["walk"] = {
        {"description", "random walk: kicks U(-a, a) on fn and ft, a = kick <F_n>, relaxed "
                        "by the static contact-dynamics solve"},
        {"eta", r.eta},
        {"mean_fn", r.mean_fn},
        {"mean_coverage_of_lp_width", mean_coverage(*walk_cols, bounds, sys.F0)},
        {"samples", r.samples},
        {"failures", r.failures},
        {"kick", opt.kick},
        {"kick_amplitude", r.kick_amplitude},
        {"solve_tol_F0", opt.walk_tol},
        {"nlgs_sweeps", r.sweeps},
        {"seconds", seconds}};
  }
  std::optional<ProbeColumns> probes;
  if (probe != "none") probes = run_probes(packing, sys, opt, probe);

  std::vector<std::string> columns{"a", "b", "fn", "fn_min", "fn_max"};
  for (const auto& [prefix, used] : {std::pair{"hr_", use_hr}, std::pair{"walk_", use_walk}})
    if (used)
      for (const char* s : {"min", "max", "mean", "std"})
        columns.push_back(std::string(prefix) + s);
  if (probes)
    columns.insert(columns.end(), {"f_crit", "f_crit_method", "probe_converged", "probe_sweeps"});
  CsvWriter csv(columns);
  std::vector<double> ratio;  // F_crit / fn_max over the probed contacts
  int unconverged = 0;
  for (int k = 0; k < Nc; ++k) {
    const Contact& c = packing.contacts[sys.contacts[k]];
    csv.cell(c.a).cell(c.b).cell(c.fn).cell(bounds.fn_min[k]).cell(bounds.fn_max[k]);
    for (const std::optional<SamplerColumns>* s : {&hr_cols, &walk_cols}) {
      if (!*s) continue;
      const SamplerColumns& m = **s;
      csv.cell(m.min[k]).cell(m.max[k]).cell(m.mean[k]).cell(m.std[k]);
    }
    if (probes) {
      if (const auto& r = probes->result[k]) {
        csv.cell(r->f_crit).cell(probe).cell(r->converged ? 1 : 0);
        csv.cell(static_cast<std::int64_t>(r->sweeps));
        ratio.push_back(r->f_crit / bounds.fn_max[k]);
        unconverged += r->converged ? 0 : 1;
      } else {
        csv.cell("").cell("").cell("").cell("");
      }
    }
    csv.end_row();
  }
  const std::filesystem::path dir(opt.dir);
  write_file_atomic(dir / "ensemble.csv", csv.str());
  if (samples_csv) write_file_atomic(dir / "ensemble-samples.csv", samples_csv->str());

  nlohmann::ordered_json probe_json = {{"method", probe}};
  if (probes) {
    probe_json["contacts_probed"] = ratio.size();
    probe_json["unconverged"] = unconverged;
    probe_json["settings"] = {{"g", opt.probe_g},
                              {"dt", opt.probe_dt},
                              {"velocity_tol_g_per_dt", opt.probe_velocity_tol},
                              {"threads", opt.threads}};
    if (!ratio.empty()) {
      const auto within = [&ratio](double f) {
        return std::count_if(ratio.begin(), ratio.end(),
                             [f](double x) { return std::abs(x - 1.0) <= f; });
      };
      probe_json["f_crit_over_fn_max"] = {
          {"min", quantile(ratio, 0.0)},   {"median", quantile(ratio, 0.5)},
          {"max", quantile(ratio, 1.0)},   {"within_1_percent", within(0.01)},
          {"within_2_percent", within(0.02)}, {"within_5_percent", within(0.05)}};
    }
    probe_json["seconds"] = probes->seconds;
  }
  const double total = seconds_since(t_start);
  const nlohmann::ordered_json j = {
      {"program_version", kVersion},
      {"command", command_line()},
      {"packing", opt.dir},
      {"mu", sys.mu},
      {"F0", sys.F0},
      {"contacts_used", Nc},
      {"samples", opt.samples},
      {"seed", opt.seed},
      {"methods", methods},
      {"probe", probe_json},
      {"parameters", {{"gap_tol", opt.gap_tol}, {"fn_tol_F0", opt.fn_tol}}},
      {"timings_s", {{"lp", bounds.seconds}, {"total", total}}},
  };
  write_file_atomic(dir / "ensemble.json", j.dump(2) + "\n");

  std::printf("contacts %d, samples %d (seed %llu)\n", Nc, opt.samples,
              static_cast<unsigned long long>(opt.seed));
  for (const auto& [name, m] : methods.items())
    std::printf("%-12s eta = <dF>/<|F|> = %.6g, mean sampled/LP width %.4g, %.3g s\n",
                name.c_str(), m["eta"].get<double>(), m["mean_coverage_of_lp_width"].get<double>(),
                m["seconds"].get<double>());
  if (probe_json.contains("f_crit_over_fn_max")) {
    const auto& f = probe_json["f_crit_over_fn_max"];
    std::printf("F_crit/fn_max (%s, %zu contacts, %d unconverged): min %.4g, median %.4g, "
                "max %.4g; within 1/2/5 %%: %d/%d/%d; %.3g s\n",
                probe.c_str(), ratio.size(), unconverged, f["min"].get<double>(),
                f["median"].get<double>(), f["max"].get<double>(),
                f["within_1_percent"].get<int>(), f["within_2_percent"].get<int>(),
                f["within_5_percent"].get<int>(), probes->seconds);
  }
  std::printf("total %.3g s\n", total);
}

}  // namespace

void add_ensemble_command(CLI::App& app) {
  auto opt = std::make_shared<EnsembleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "ensemble", "admissible force networks: hit-and-run and/or the paper's random walk, LP "
                  "intervals, eta and F_crit per contact (Fig. 4)");
  cmd->add_option("DIR", opt->dir, "packing directory")->required();
  cmd->add_option("--method", opt->method, "sampler: hit-and-run, walk or both")
      ->capture_default_str()->check(CLI::IsMember({"hit-and-run", "walk", "both"}));
  cmd->add_option("--probe", opt->probe,
                  "F_crit of every force-carrying contact: nlgs, lp or none (default: nlgs up "
                  "to 200 contacts, else lp)")
      ->check(CLI::IsMember({"nlgs", "lp", "none"}));
  cmd->add_option("--samples", opt->samples, "networks to sample (walk: steps)")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--seed", opt->seed, "seed of both samplers")->capture_default_str()->check(seed_value());
  cmd->add_option("--thin", opt->thin, "hit-and-run steps per sample (0: the dimension)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--burn-in", opt->burn_in,
                  "hit-and-run steps before the first sample (0: 100 x dimension)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--kick", opt->kick, "walk kick amplitude in units of <F_n>")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--walk-tol", opt->walk_tol, "walk relaxation residual target (F0)")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--probe-g", opt->probe_g, "probe opening g (R_max)")->capture_default_str()->check(positive_number());
  cmd->add_option("--probe-dt", opt->probe_dt, "nlgs probe time step (t0)")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--probe-velocity-tol", opt->probe_velocity_tol,
                  "nlgs probe convergence: max |dU| per sweep below this times g / dt")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--gap-tol", opt->gap_tol, "touching contacts: gap <= gap-tol (R_max)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--fn-tol", opt->fn_tol, "force-carrying contacts: fn > fn-tol F0")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--threads", opt->threads,
                  "OpenMP threads for the LP bounds and the probes (0: all cores)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_flag("--write-samples", opt->write_samples,
                "write DIR/ensemble-samples.csv (hit-and-run samples)");
  cmd->callback([opt] { run_ensemble(*opt); });
}

}  // namespace unjam::cli
