// `unjam ensemble DIR`: uniform samples of the admissible force networks by hit-and-run
// (PHYSICS.md section 7, docs/ensemble.md), with the exact LP interval of every contact.
// Writes DIR/ensemble.csv (a,b,fn,sample_min,sample_max,mean,std,fn_min,fn_max; 17
// significant digits), DIR/ensemble.json (eta, samples, seed, dimension, version) and, with
// --write-samples, DIR/ensemble-samples.csv (one row per sample: fn of every contact).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/ensemble/hit_and_run.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::cli {

namespace {

struct EnsembleOptions {
  std::string dir;
  int samples = 20000;
  std::uint64_t seed = 1;
  int thin = 0;
  int burn_in = 0;
  double gap_tol = 1e-9;
  double fn_tol = 1e-9;
  int threads = 1;
  bool write_samples = false;
};

void run_ensemble(const EnsembleOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const Packing packing = read_packing(opt.dir);
  const EquilibriumSystem sys =
      build_equilibrium_system(packing, select_contacts(packing, opt.gap_tol, opt.fn_tol));
  ForceBoundsOptions lp;
  lp.threads = opt.threads;
  const ForceBounds bounds = compute_force_bounds(sys, lp);

  HitAndRunOptions hr;
  hr.samples = opt.samples;
  hr.seed = opt.seed;
  hr.thin = opt.thin;
  hr.burn_in = opt.burn_in;
  std::string samples_csv;
  char buf[64];
  if (opt.write_samples) {
    for (int k = 0; k < sys.num_contacts(); ++k) {
      const Contact& c = packing.contacts[sys.contacts[k]];
      samples_csv += (k ? ",fn_" : "fn_") + std::to_string(c.a) + "_" + std::to_string(c.b);
    }
    samples_csv += '\n';
    hr.on_sample = [&samples_csv, &buf](const ForceNetwork& net) {
      for (Eigen::Index k = 0; k < net.fn.size(); ++k) {
        std::snprintf(buf, sizeof buf, k ? ",%.17g" : "%.17g", net.fn[k]);
        samples_csv += buf;
      }
      samples_csv += '\n';
    };
  }
  const auto t_walk = std::chrono::steady_clock::now();
  const HitAndRunResult r = sample_hit_and_run(sys, bounds, hr);
  const double walk_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_walk).count();

  std::string csv = "a,b,fn,sample_min,sample_max,mean,std,fn_min,fn_max\n";
  char line[320];
  double coverage = 0.0;
  int covered = 0;
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const Contact& c = packing.contacts[sys.contacts[k]];
    std::snprintf(line, sizeof line, "%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", c.a,
                  c.b, c.fn, r.sample_min[k], r.sample_max[k], r.mean[k], r.std[k],
                  bounds.fn_min[k], bounds.fn_max[k]);
    csv += line;
    const double width = bounds.fn_max[k] - bounds.fn_min[k];
    if (width > 1e-9 * sys.F0) {
      coverage += (r.sample_max[k] - r.sample_min[k]) / width;
      ++covered;
    }
  }
  coverage = covered > 0 ? coverage / covered : 1.0;
  const std::filesystem::path dir(opt.dir);
  write_file_atomic(dir / "ensemble.csv", csv);
  if (opt.write_samples) write_file_atomic(dir / "ensemble-samples.csv", samples_csv);
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  const nlohmann::ordered_json j = {
      {"program_version", kVersion},
      {"packing", opt.dir},
      {"method", "hit-and-run, uniform on the admissible polytope"},
      {"mu", sys.mu},
      {"F0", sys.F0},
      {"contacts_used", sys.num_contacts()},
      {"contacts_open_in_every_network", r.fixed_open},
      {"dimension", r.dimension},
      {"samples", r.samples},
      {"steps", r.steps},
      {"seed", opt.seed},
      {"thin", opt.thin},
      {"burn_in", opt.burn_in},
      {"eta", r.eta},
      {"mean_fn", r.mean_fn},
      {"mean_coverage_of_lp_width", coverage},
      {"start_depth", r.start_depth},
      {"parameters", {{"gap_tol", opt.gap_tol}, {"fn_tol_F0", opt.fn_tol}}},
      {"timings_s", {{"lp", bounds.seconds}, {"walk", walk_seconds}, {"total", total}}},
  };
  write_file_atomic(dir / "ensemble.json", j.dump(2) + "\n");
  std::printf("contacts %d, dimension %d, samples %d (seed %llu)\n", sys.num_contacts(),
              r.dimension, r.samples, static_cast<unsigned long long>(opt.seed));
  std::printf("eta = <dF>/<|F|> = %.6g, mean sampled/LP width %.4g, %.3g s\n", r.eta, coverage,
              total);
}

}  // namespace

void add_ensemble_command(CLI::App& app) {
  auto opt = std::make_shared<EnsembleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "ensemble", "Uniform samples of the admissible force networks (hit-and-run) and eta");
  cmd->add_option("DIR", opt->dir, "packing directory")->required();
  cmd->add_option("--samples", opt->samples, "networks to sample")->check(CLI::PositiveNumber);
  cmd->add_option("--seed", opt->seed, "seed of the random walk");
  cmd->add_option("--thin", opt->thin, "steps per sample (0: the dimension)");
  cmd->add_option("--burn-in", opt->burn_in, "steps before the first sample (0: 100 x dimension)");
  cmd->add_option("--gap-tol", opt->gap_tol, "touching contacts: gap <= gap-tol (R_max)");
  cmd->add_option("--fn-tol", opt->fn_tol, "force-carrying contacts: fn > fn-tol F0");
  cmd->add_option("--threads", opt->threads, "OpenMP threads for the LP bounds")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--write-samples", opt->write_samples, "write DIR/ensemble-samples.csv");
  cmd->callback([opt] { run_ensemble(*opt); });
}

}  // namespace unjam::cli
