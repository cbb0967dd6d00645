// unjam.ensemble: `unjam ensemble` for Python (campaign/ensemble_run; docs/ensemble.md): the
// LP interval of every contact of the admissible set, the samplers' per-contact statistics and
// F_crit of every force-carrying contact, as arrays in the order of ensemble.csv, with
// ensemble.json's "methods", "probe" and "parameters" as dicts.
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "python/bindings.hpp"
#include "unjam/campaign/ensemble_run.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/cd_path.hpp"

namespace unjam::python {
namespace {

py::object json_to_python(const nlohmann::ordered_json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

// method: "hit-and-run", "walk" or "both" (--method); probe: None (cd up to 200 contacts, else
// lp), "nlgs", "lp", "cd" or "none" (--probe). keep_samples: the fn of every hit-and-run sample
// as a (samples, contacts) array "samples_fn" (--write-samples). progress: given a dict (what,
// done, total, elapsed_s) as the tool's progress lines (the walk's steps, the probes), under
// the GIL on the thread that reports; its first exception stops the run as Ctrl-C does and is
// raised. Ctrl-C stops it within a fraction of a second of an LP, a sample or a probe step
// (KeyboardInterrupt; nothing is kept).
py::dict ensemble(const Packing& p, const std::string& method, const std::optional<std::string>& probe, int samples,
                  std::uint64_t seed, int thin, int burn_in, double kick, double walk_tol, double probe_g,
                  double probe_dt, double probe_velocity_tol, double gap_tol, double fn_tol, double lp_tol,
                  double open_tol, const std::optional<CdPathSettings>& cd, int threads, bool keep_samples,
                  std::optional<py::function> progress) {
  if (method != "hit-and-run" && method != "walk" && method != "both")
    throw Error("method must be hit-and-run, walk or both (got '" + method + "')");
  // Another unknown name is refused by compute_ensemble before the LPs.
  if (probe && *probe == "lemke") throw Error("probe must be nlgs, lp, cd or none (got 'lemke')");
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (samples < 1) throw Error("samples must be >= 1 (got " + std::to_string(samples) + ")");
  if (thin < 0 || burn_in < 0) throw Error("thin and burn_in must be >= 0 (0: the sampler's default)");
  if (!non_negative(kick) || !positive(walk_tol) || !positive(probe_g) || !non_negative(probe_dt) ||
      !positive(probe_velocity_tol) || !non_negative(gap_tol) || !non_negative(fn_tol))
    throw Error("kick, probe_dt, gap_tol and fn_tol must be finite and >= 0; walk_tol, probe_g and "
                "probe_velocity_tol finite and > 0");
  if (threads < 0) throw Error("threads must be >= 0 (0: all cores)");
  ForceBoundsOptions lp;
  lp.tolerance = lp_tol;
  lp.open_tol_F0 = open_tol;
  check_force_bounds_options(lp);  // before the packing's system is built

  EnsembleSettings s;
  s.hit_and_run = method != "walk";
  s.walk = method != "hit-and-run";
  s.probe = probe.value_or("");
  s.samples = samples;
  s.seed = seed;
  s.thin = thin;
  s.burn_in = burn_in;
  s.kick = kick;
  s.walk_tol = walk_tol;
  s.probe_g = probe_g;
  s.probe_dt = probe_dt;
  s.probe_velocity_tol = probe_velocity_tol;
  s.gap_tol = gap_tol;
  s.fn_tol = fn_tol;
  s.lp_tol = lp_tol;
  s.open_tol = open_tol;
  if (cd) s.probe_cd = *cd;  // refused unless the probe is cd (validate, before the LPs)
  s.threads = threads > 0 ? threads : omp_get_max_threads();  // recorded in "probe" as the tool does
  std::vector<double> kept;  // the hit-and-run samples' fn, row by row
  if (keep_samples && s.hit_and_run)
    s.on_sample = [&kept](const ForceNetwork& net) { kept.insert(kept.end(), net.fn.data(), net.fn.data() + net.fn.size()); };
  SignalPoll poll;
  Callback report(std::move(progress));
  s.should_stop = [&] { return report.failed() || poll(); };
  const auto t_start = std::chrono::steady_clock::now();
  if (report)
    s.progress = [&](const std::string& what, int done, int total) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      report([&] {
        py::dict d;
        d["what"] = what;
        d["done"] = done;
        d["total"] = total;
        d["elapsed_s"] = t;
        return d;
      });
    };
  EnsembleReport r;
  try {
    py::gil_scoped_release release;
    r = compute_ensemble(p, s);
  } catch (const Error&) {  // Cancelled too: the poll's or the callback's error is raised instead
    report.rethrow_if_failed();
    poll.rethrow_if_interrupted();
    throw;
  }
  report.rethrow_if_failed();
  poll.rethrow_if_interrupted();

  const int Nc = r.system.num_contacts();
  py::dict d = contact_columns(p, r.system.contacts);
  d["fn_min"] = py::array_t<double>(Nc, r.bounds.fn_min.data());
  d["fn_max"] = py::array_t<double>(Nc, r.bounds.fn_max.data());
  for (const auto& [prefix, m] : {std::pair{"hr_", &r.hr_columns}, std::pair{"walk_", &r.walk_columns}}) {
    if (!*m) continue;
    const SamplerReport& c = **m;
    d[py::str(std::string(prefix) + "min")] = py::array_t<double>(Nc, c.min.data());
    d[py::str(std::string(prefix) + "max")] = py::array_t<double>(Nc, c.max.data());
    d[py::str(std::string(prefix) + "mean")] = py::array_t<double>(Nc, c.mean.data());
    d[py::str(std::string(prefix) + "std")] = py::array_t<double>(Nc, c.std.data());
  }
  if (r.probe != "none") {  // NaN, False and -1 for a contact without force (not probed)
    py::array_t<double> f_crit(Nc);
    py::array_t<bool> converged(Nc);
    py::array_t<long long> sweeps(Nc);
    for (int k = 0; k < Nc; ++k) {
      const std::optional<ProbeResult>& q = r.probes[k];
      f_crit.mutable_at(k) = q ? q->f_crit : std::numeric_limits<double>::quiet_NaN();
      converged.mutable_at(k) = q && q->converged;
      sweeps.mutable_at(k) = q ? q->sweeps : -1;
    }
    d["f_crit"] = f_crit;
    d["probe_converged"] = converged;
    d["probe_sweeps"] = sweeps;
  }
  if (keep_samples && s.hit_and_run) {
    const py::ssize_t rows = Nc > 0 ? static_cast<py::ssize_t>(kept.size() / Nc) : 0;
    d["samples_fn"] = py::array_t<double>({rows, static_cast<py::ssize_t>(Nc)}, kept.data());
  }
  d["mu"] = r.system.mu;
  d["F0"] = r.system.F0;
  d["samples"] = s.samples;
  d["seed"] = s.seed;
  d["methods"] = json_to_python(ensemble_methods_json(s, r));
  d["probe"] = json_to_python(ensemble_probe_json(s, r));
  d["parameters"] = json_to_python(ensemble_parameters_json(s));
  d["lp_seconds"] = r.bounds.seconds;
  return d;
}

}  // namespace

void bind_ensemble(py::module_& m) {
  const EnsembleSettings e;
  m.def("ensemble", &ensemble, py::arg("packing"), py::kw_only(), py::arg("method") = "both",
        py::arg("probe") = py::none(), py::arg("samples") = e.samples, py::arg("seed") = e.seed,
        py::arg("thin") = e.thin, py::arg("burn_in") = e.burn_in, py::arg("kick") = e.kick,
        py::arg("walk_tol") = e.walk_tol, py::arg("probe_g") = e.probe_g, py::arg("probe_dt") = e.probe_dt,
        py::arg("probe_velocity_tol") = e.probe_velocity_tol, py::arg("gap_tol") = e.gap_tol,
        py::arg("fn_tol") = e.fn_tol, py::arg("lp_tol") = e.lp_tol, py::arg("open_tol") = e.open_tol,
        py::arg("cd") = py::none(), py::arg("threads") = 0, py::arg("keep_samples") = false, py::arg("progress") = py::none(),
        "the ensemble of admissible force networks, as `unjam ensemble` (same seed, same numbers): a dict "
        "of arrays in the order of ensemble.csv (contact, a, b, fn, fn_min, fn_max; hr_min, hr_max, hr_mean, "
        "hr_std with method 'hit-and-run' or 'both'; walk_* with 'walk' or 'both'; f_crit (NaN where not "
        "probed), probe_converged, probe_sweeps (-1 where not probed) unless probe='none'), with ensemble.json's "
        "methods, probe and parameters as dicts, mu, F0, samples, seed and lp_seconds. probe: None (cd up to "
        "200 contacts, else lp), 'nlgs', 'lp', 'cd' or 'none'; cd: the cd probe's settings, an unjam.CdSettings "
        "(`--cd-*`; e.g. start='interior' at 500 disks and more); keep_samples: the fn of every hit-and-run "
        "sample as samples_fn, a (samples, contacts) array (--write-samples); progress: a callable given a "
        "dict (what, done, total, elapsed_s) as the random walk's steps and the probes go on; an exception it "
        "raises stops the run and is raised. Ctrl-C stops it (KeyboardInterrupt; nothing is kept)");
}

}  // namespace unjam::python
