// `unjam ensemble DIR`: the admissible force networks of a packing (docs/ensemble.md) sampled
// by hit-and-run (uniform) and/or by the paper's random walk of kicks relaxed by contact
// dynamics, the exact LP interval of every contact, and the critical force F_crit of every
// force-carrying contact (docs/probe.md): everything the paper's Fig. 4 draws
// (scripts/plot_fig4.py).
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
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "unjam/campaign/ensemble_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/version.hpp"
#include "unjam/packing/csv_table.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam::cli {

namespace {

struct EnsembleOptions {
  std::string dir;
  std::string method = "both";  // hit-and-run | walk | both
  EnsembleSettings settings;    // the library's defaults; threads 0: all cores
  std::string cd_start = "static";  // --cd-start: settings.probe_cd.start
  bool write_samples = false;
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Prints "<what>: done / total, t s" on stderr at most every 2 s per `what`, and at the end.
class Progress {
 public:
  void operator()(const std::string& what, int done, int total) {
    auto [it, added] = next_s_.try_emplace(what, 2.0);
    if (added) start_[what] = std::chrono::steady_clock::now();
    const double t = seconds_since(start_[what]);
    if (t < it->second && done < total) return;
    it->second = t + 2.0;
    std::fprintf(stderr, "%s: %d / %d, %.1f s\n", what.c_str(), done, total, t);
  }

 private:
  std::map<std::string, double> next_s_;
  std::map<std::string, std::chrono::steady_clock::time_point> start_;
};

// ensemble.csv: one row per contact of the admissible set.
std::string ensemble_csv(const Packing& packing, const EnsembleReport& r) {
  std::vector<std::string> columns{"a", "b", "fn", "fn_min", "fn_max"};
  for (const auto& [prefix, s] : {std::pair{"hr_", &r.hr_columns}, std::pair{"walk_", &r.walk_columns}})
    if (*s)
      for (const char* stat : {"min", "max", "mean", "std"}) columns.push_back(std::string(prefix) + stat);
  const bool probed = r.probe != "none";
  if (probed) columns.insert(columns.end(), {"f_crit", "f_crit_method", "probe_converged", "probe_sweeps"});
  CsvWriter csv(columns);
  for (int k = 0; k < r.system.num_contacts(); ++k) {
    const Contact& c = packing.contacts[r.system.contacts[k]];
    csv.cell(c.a).cell(c.b).cell(c.fn).cell(r.bounds.fn_min[k]).cell(r.bounds.fn_max[k]);
    for (const std::optional<SamplerReport>* s : {&r.hr_columns, &r.walk_columns}) {
      if (!*s) continue;
      const SamplerReport& m = **s;
      csv.cell(m.min[k]).cell(m.max[k]).cell(m.mean[k]).cell(m.std[k]);
    }
    if (probed) {
      if (const auto& p = r.probes[k]) {
        csv.cell(p->f_crit).cell(r.probe).cell(p->converged ? 1 : 0).cell(static_cast<std::int64_t>(p->sweeps));
      } else {
        csv.cell("").cell("").cell("").cell("");
      }
    }
    csv.end_row();
  }
  return csv.str();
}

void print_summary(const EnsembleSettings& s, const EnsembleReport& r, const nlohmann::ordered_json& j) {
  std::printf("contacts %d, samples %d (seed %llu)\n", r.system.num_contacts(), s.samples,
              static_cast<unsigned long long>(s.seed));
  for (const auto& [name, m] : j["methods"].items())
    std::printf("%-12s eta = <dF>/<|F|> = %.6g, mean sampled/LP width %.4g, %.3g s\n", name.c_str(),
                m["eta"].get<double>(), m["mean_coverage_of_lp_width"].get<double>(), m["seconds"].get<double>());
  if (j["probe"].contains("f_crit_over_fn_max")) {
    const auto& f = j["probe"]["f_crit_over_fn_max"];
    std::printf("F_crit/fn_max (%s, %zu contacts, %d unconverged): min %.4g, median %.4g, "
                "max %.4g; within 1/2/5 %%: %d/%d/%d; %.3g s\n",
                r.probe.c_str(), r.f_crit_over_fn_max.size(), r.unconverged, f["min"].get<double>(),
                f["median"].get<double>(), f["max"].get<double>(), f["within_1_percent"].get<int>(),
                f["within_2_percent"].get<int>(), f["within_5_percent"].get<int>(), r.probe_seconds);
  }
  if (j["probe"].contains("position_in_interval")) {
    const auto& t = j["probe"]["position_in_interval"];
    std::printf("F_crit in its interval, t = (F_crit - fn_min) / (fn_max - fn_min): min %.4g, "
                "median %.4g, %d at the top (t >= 0.99); %d below f_cont\n",
                t["min"].get<double>(), t["median"].get<double>(), t["at_top"].get<int>(),
                j["probe"]["below_f_cont"].get<int>());
  }
  std::printf("total %.3g s\n", j["timings_s"]["total"].get<double>());
}

void run_ensemble(const EnsembleOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  EnsembleSettings s = opt.settings;
  s.threads = thread_count(s.threads);
  s.hit_and_run = opt.method != "walk";
  s.walk = opt.method != "hit-and-run";
  s.probe_cd.start = cd_start_from_name(opt.cd_start);
  const Packing packing = read_packing(opt.dir);
  // A probe setting that does not apply is refused before anything runs or is written.
  if (const std::string m = ensemble_probe_method(packing, s); m != "none") ensemble_probe_settings(packing, s, m);
  const DirLock lock(opt.dir, command_line());
  std::optional<CsvWriter> samples_csv;  // --write-samples: fn of every hit-and-run sample
  if (opt.write_samples) {
    std::vector<std::string> names;
    for (const int c : select_contacts(packing, ensemble_contact_model(packing, s), s.fn_tol))
      names.push_back("fn_" + std::to_string(packing.contacts[c].a) + "_" + std::to_string(packing.contacts[c].b));
    samples_csv.emplace(names);
    s.on_sample = [&samples_csv](const ForceNetwork& net) {
      for (Eigen::Index k = 0; k < net.fn.size(); ++k) samples_csv->cell(net.fn[k]);
      samples_csv->end_row();
    };
  }
  if (s.hit_and_run) std::fprintf(stderr, "hit-and-run: %d samples\n", s.samples);
  Progress progress;
  s.progress = [&progress](const std::string& what, int done, int total) { progress(what, done, total); };
  const EnsembleReport r = compute_ensemble(packing, s);
  const std::filesystem::path dir(opt.dir);
  write_file_atomic(dir / "ensemble.csv", ensemble_csv(packing, r));
  if (samples_csv) write_file_atomic(dir / "ensemble-samples.csv", samples_csv->str());
  const nlohmann::ordered_json j = {
      {"program_version", kVersion},
      {"command", command_line()},
      {"packing", opt.dir},
      {"mu", r.system.mu},
      {"F0", r.system.F0},
      {"contacts_used", r.system.num_contacts()},
      {"samples", s.samples},
      {"seed", s.seed},
      {"methods", ensemble_methods_json(s, r)},
      {"probe", ensemble_probe_json(s, r)},
      {"parameters", ensemble_parameters_json(s)},
      {"timings_s", {{"lp", r.bounds.seconds}, {"total", seconds_since(t_start)}}},
  };
  write_file_atomic(dir / "ensemble.json", j.dump(2) + "\n");
  print_summary(s, r, j);
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
  cmd->add_option("--probe", opt->settings.probe,
                  "F_crit of every force-carrying contact: nlgs, lp, cd (the exact step) or none "
                  "(default: cd up to 200 contacts, else lp)")
      ->check(CLI::IsMember({"nlgs", "lp", "cd", "none"}));
  add_cd_path_options(cmd, opt->settings.probe_cd, opt->cd_start);
  cmd->add_option("--samples", opt->settings.samples, "networks to sample (walk: steps)")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--seed", opt->settings.seed, "seed of both samplers")->capture_default_str()->check(seed_value());
  cmd->add_option("--thin", opt->settings.thin, "hit-and-run steps per sample (0: the dimension)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--burn-in", opt->settings.burn_in,
                  "hit-and-run steps before the first sample (0: 100 x dimension)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--kick", opt->settings.kick, "walk kick amplitude in units of <F_n>")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--walk-tol", opt->settings.walk_tol, "walk relaxation residual target (F0)")
      ->capture_default_str()->check(positive_number());
  cmd->add_option("--probe-g", opt->settings.probe_g, "probe opening g (R_max)")->capture_default_str()->check(positive_number());
  cmd->add_option("--probe-dt", opt->settings.probe_dt,
                  "probe time step (t0; 0: nlgs 1e-3, cd the quasi-static sqrt(g / 1e-5))")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--probe-velocity-tol", opt->settings.probe_velocity_tol,
                  "nlgs probe convergence: max |dU| per sweep below this times g / dt")
      ->capture_default_str()->check(positive_number());
  add_contact_selection_options(cmd, opt->settings.gap_tol, opt->settings.fn_tol);
  add_lp_tolerance_options(cmd, opt->settings.lp_tol, opt->settings.open_tol);
  cmd->add_option("--threads", opt->settings.threads,
                  "OpenMP threads for the LP bounds and the probes (0: all cores)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_flag("--write-samples", opt->write_samples,
                "write DIR/ensemble-samples.csv (hit-and-run samples)");
  cmd->callback([opt] { run_ensemble(*opt); });
}

}  // namespace unjam::cli
