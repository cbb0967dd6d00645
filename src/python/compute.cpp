// unjam.pack, unjam.probe, unjam.bounds, unjam.stats and unjam.export: the library calls of
// `unjam pack`, `probe --contact`, `bounds`, `info --json` and `export`, with the tool's
// defaults (taken from the library's settings structs where the tool takes them too).
#include <omp.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "python/bindings.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/campaign/bounds_checkpoint.hpp"
#include "unjam/campaign/threshold_checkpoint.hpp"
#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/ensemble/friction_threshold.hpp"
#include "unjam/lp/rank.hpp"
#include "unjam/packing/export.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/protocol/pack_run.hpp"
#include "unjam/protocol/settings_json.hpp"

namespace unjam::python {
namespace {

struct PackArgs {
  GasSettings gas;
  CompactionSettings compaction;
  double mu = 0.1, P_ext = 1.0;
  int threads = 0;
  std::optional<std::filesystem::path> out;
  std::optional<py::function> progress;  // called every 2 s with a dict (CompactionProgress)
};

py::dict progress_dict(const CompactionProgress& g) {
  py::dict d;
  d["step"] = g.step;
  d["time"] = g.time;
  d["phi"] = g.phi;
  d["P_in_over_P_ext"] = g.P_ratio;
  d["v_mean"] = g.v_mean;
  d["sweeps_per_step"] = g.sweeps_per_step;
  d["contacts"] = g.contacts;
  d["elapsed_s"] = g.elapsed_s;
  d["eta_s"] = g.eta_s < 0.0 ? py::object(py::none()) : py::object(py::float_(g.eta_s));
  d["static_attempts"] = g.static_attempts;
  return d;
}

// The call recorded in meta.json as the command that made the packing.
std::string call_record(bool from_gas, const PackArgs& a) {
  char buf[256];
  if (from_gas)
    std::snprintf(buf, sizeof buf, "python: unjam.pack(n=%d, mu=%.17g, seed=%llu, p_ext=%.17g, threads=%d)",
                  a.gas.N, a.mu, static_cast<unsigned long long>(a.gas.seed), a.P_ext, a.threads);
  else
    std::snprintf(buf, sizeof buf, "python: unjam.relax(packing, mu=%.17g, p_ext=%.17g, threads=%d)",
                  a.mu, a.P_ext, a.threads);
  return buf;
}

// compact() of a prepared packing, GIL released, with Ctrl-C, the progress callback and, with
// `out`, checkpoints and the result there (also a stopped run, to resume with
// `unjam pack --resume OUT`). An exception of the progress callback stops the compaction and
// is raised.
Packing run_compaction(Packing p, const PackArgs& a) {
  // As `unjam pack`: the output directory made and locked before the compaction (one writer;
  // a place that cannot be written is refused now, not at the first checkpoint).
  std::optional<DirLock> lock;
  if (a.out) lock.emplace(*a.out, p.meta.command);
  SignalPoll poll;
  CompactionResult r;
  Callback progress(a.progress);
  {
    py::gil_scoped_release release;
    const ThreadCount threads(a.threads);
    CompactionHooks hooks;
    hooks.should_stop = [&] { return progress.failed() || poll(); };
    if (progress)
      hooks.progress = [&](const CompactionProgress& g) { progress([&] { return progress_dict(g); }); };
    if (a.out) {
      hooks.checkpoint = [&a](const Packing& q) { write_packing(*a.out, q); };
      hooks.checkpoint_s = 60.0;
    }
    r = compact(p, a.compaction, hooks);
    if (a.out) write_packing(*a.out, p);
  }
  progress.rethrow_if_failed();
  poll.rethrow_if_interrupted();
  if (!r.is_static) throw Error("no static packing within max_steps");
  return p;
}

// `unjam pack --n ... --out OUT`: a gas compacted into a static packing.
Packing pack(PackArgs a) {
  Packing p = gas_packing(a.gas, a.mu, a.P_ext);
  prepare_compaction(p, a.compaction, a.gas, call_record(true, a));
  return run_compaction(std::move(p), a);
}

// `unjam pack --from DIR --mu MU --p-ext P --out OUT`: the packing re-relaxed at mu and p_ext
// with the settings it was made with.
Packing relax(const Packing& from, double mu, double p_ext, int threads,
              std::optional<std::filesystem::path> out, std::optional<py::function> progress) {
  Packing p = from;
  PackArgs a;
  prepare_relaxation(p, mu, p_ext, a.compaction, a.gas);
  a.mu = mu;
  a.P_ext = p_ext;
  a.threads = threads;
  a.out = std::move(out);
  a.progress = std::move(progress);
  prepare_compaction(p, a.compaction, a.gas, call_record(false, a));
  return run_compaction(std::move(p), a);
}

// cd: the cd method's settings (`unjam probe --cd-*`), from unjam.CdSettings or the keywords.
CampaignSettings probe_settings(const Packing& p, const std::string& method, double g,
                                std::optional<double> dt, double velocity_tol, long long max_sweeps,
                                const CdPathSettings& cd, std::optional<double> window, double lp_tol) {
  CampaignSettings s = campaign_settings_for(p);
  s.method = method_from_name(method);
  s.cd = cd;
  s.nlgs.g = s.kinematic.g = g;
  s.kinematic.lp_tolerance = lp_tol;  // lp only (validate)
  s.nlgs.dt = dt ? *dt : default_probe_dt(s.method, g);
  s.nlgs.velocity_tol = velocity_tol;
  s.nlgs.max_sweeps = max_sweeps;
  if (window) {
    if (!(*window > 0.0)) throw Error("window must be > 0 (mean diameters; None: the whole packing)");
    s.nlgs.window = *window;
  }
  validate(s);
  return s;
}

// probe_contacts (in parallel; Ctrl-C checked between probes and, by the calling thread's
// probe, inside it, which abandons every running probe): a ProbeResult for contact=K, a list
// in the order of contacts=[...]. progress gets each finished probe as it arrives, and a sign of
// life of each probe every running_every seconds, under the GIL on the thread that gathers it
// or runs the probe; its first exception stops the probes (as Ctrl-C does) and is raised.
py::object probe(const Packing& p, std::optional<int> contact, std::optional<std::vector<int>> contacts,
                 const std::string& method, double g, std::optional<double> dt, double velocity_tol,
                 long long max_sweeps, const std::string& cd_start, int cd_softer_starts,
                 std::optional<double> window, long long cd_max_pieces, double cd_interior_states_pieces,
                 int cd_interior_states_stall, int cd_interior_states_retries, int cd_interior_iterations,
                 double cd_interior_neighbourhood, double cd_compliant_start, double cd_accept_residual,
                 std::optional<CdPathSettings> typed, double lp_tol, int threads,
                 std::optional<py::function> progress, double running_every) {
  if (contact.has_value() == contacts.has_value()) throw Error("give exactly one of contact=K, contacts=[...]");
  const std::vector<int> list = contact ? std::vector<int>{*contact} : *contacts;
  CdPathSettings cd = cd_settings(cd_start, cd_compliant_start, cd_softer_starts, cd_max_pieces, cd_accept_residual,
                                  cd_interior_states_pieces, cd_interior_states_stall, cd_interior_states_retries,
                                  cd_interior_iterations, cd_interior_neighbourhood);
  if (typed) {  // cd=unjam.CdSettings(...): the keywords must then be left at their defaults
    if (!same_cd_fields(cd, CdPathSettings{}))
      throw Error("give the cd settings either as cd=unjam.CdSettings(...) or as cd_* keywords, not both");
    cd = *typed;
  }
  CampaignSettings s = probe_settings(p, method, g, dt, velocity_tol, max_sweeps, cd, window, lp_tol);
  std::vector<ProbeResult> results;
  SignalPoll poll;
  if (!(running_every >= 0.0)) throw Error("running_every must be >= 0 seconds");
  Callback report(std::move(progress));
  s.nlgs.cancel = [&] { return report.failed() || poll(); };  // probe_contacts polls it before each probe too
  ProbeListHooks hooks;
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  std::atomic<int> done{0};
  const auto event = [&](const char* name) {  // the keys every event has
    py::dict d;
    d["event"] = name;
    d["done"] = done.load();
    d["total"] = static_cast<int>(list.size());
    d["elapsed_s"] = elapsed();
    return d;
  };
  if (report) {
    hooks.progress = [&](const FinishedProbe& f) {
      done = f.done;
      report([&] {
        py::dict d = event("finished");
        d["index"] = f.index;
        d["contact"] = list[f.index];
        d["result"] = py::cast(*f.result);
        d["eta_s"] = d["elapsed_s"].cast<double>() / f.done * (f.total - f.done);
        return d;
      });
    };
    hooks.running = [&](int contact, double seconds, long long polls) {
      report([&] {
        py::dict d = event("running");
        d["contact"] = contact;
        d["seconds"] = seconds;
        d["polls"] = polls;
        return d;
      });
    };
    hooks.running_every_s = running_every;
  }
  {
    py::gil_scoped_release release;
    const ThreadCount count(threads);
    results = probe_contacts(p, s, list, hooks);
  }
  report.rethrow_if_failed();
  poll.rethrow_if_interrupted();
  if (contact) return py::cast(std::move(results.front()));
  return py::cast(std::move(results));
}

// The settings of the campaign whose probe_summary.json or probe_checkpoint.json is `path`, run
// on p (campaign_settings_from_json), under the names of unjam.probe's arguments.
py::dict campaign_settings(const Packing& p, const std::filesystem::path& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(read_file(path));
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + " is not JSON (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("settings"))
    throw Error(path.string() + " holds no campaign settings (give the probe_summary.json or "
                "probe_checkpoint.json of `unjam probe --all` or `--sample K`)");
  const CampaignSettings s = campaign_settings_from_json(j.at("settings"), p, "the settings in " + path.string());
  const bool lp = s.method == ProbeMethod::kLp;
  py::dict d;
  d["method"] = std::string(method_name(s.method));
  d["g"] = s.nlgs.g;
  d["dt"] = lp ? py::none() : py::cast(s.nlgs.dt);
  d["cd"] = py::cast(s.cd);
  d["window"] = s.nlgs.window > 0.0 ? py::cast(s.nlgs.window) : py::none();
  d["lp_tol"] = s.kinematic.lp_tolerance;
  d["velocity_tol"] = s.nlgs.velocity_tol;
  d["max_sweeps"] = s.nlgs.max_sweeps;
  d["max_inertia"] = s.max_inertia;
  d["displacement"] = std::string(s.total_displacement ? "total" : "peculiar");
  d["force_threshold"] = s.force_threshold;
  d["sample"] = s.sample;
  d["seed"] = s.seed;
  return d;
}

// With `checkpoint` (a file path): resumes from it if it is there (a checkpoint of another
// packing or other settings is refused), saves it every `checkpoint_every` seconds and when
// interrupted, and removes it once every interval is known (campaign/bounds_checkpoint; the
// file is that of `unjam bounds`, with the packing unnamed).
// progress: given a dict (done, total LPs, elapsed_s, eta_s at this run's pace) every 2 s and
// at the end, under the GIL on the thread that gathers the LP; its first
// exception stops the LPs as Ctrl-C does (the checkpoint saved) and is raised.
py::dict bounds(const Packing& p, double gap_tol, double fn_tol, int threads, const std::string& method,
                double lp_tol, double open_tol, const std::optional<std::filesystem::path>& checkpoint,
                double checkpoint_every, std::optional<py::function> progress) {
  if (method != "barrier" && method != "simplex") throw Error("method must be barrier or simplex");
  if (!(checkpoint_every >= 0.0)) throw Error("checkpoint_every must be a non-negative number of seconds");
  const auto t_start = std::chrono::steady_clock::now();
  const auto elapsed = [&t_start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  ForceBoundsOptions lp;
  lp.method = method == "simplex" ? LpMethod::simplex : LpMethod::barrier;
  lp.tolerance = lp_tol;
  lp.open_tol_F0 = open_tol;
  check_force_bounds_options(lp);  // before the packing's system is built
  SignalPoll poll;
  Callback report(std::move(progress));
  const auto stop = [&] { return report.failed() || poll(); };
  lp.should_stop = stop;
  if (report)
    lp.progress = [&, first = -1, reported = -1, last = -1e9](int done, int total) mutable {  // one call at a time
      if (first < 0) first = done - 1;  // LPs known before this run (a resumed checkpoint's)
      const double t = elapsed();
      if (done == reported || (done < total && t - last < 2.0)) return;
      last = t;
      reported = done;
      report([&] {
        py::dict d;
        d["done"] = done;
        d["total"] = total;
        d["elapsed_s"] = t;
        d["eta_s"] = t * (total - done) / (done - first);  // at this run's pace
        return d;
      });
    };
  std::optional<EquilibriumSystem> sys;
  std::optional<BoundsCheckpoint> saved;
  ForceBounds b;
  RankInfo rank;
  try {
    py::gil_scoped_release release;
    const ThreadCount count(threads);
    lp.threads = omp_get_max_threads();
    sys = admissible_system(p, gap_tol, fn_tol);
    LocalDistributor dist;
    const auto time_so_far = [&] {
      return saved->earlier() + one_run(elapsed(), dist.loads());
    };
    if (checkpoint) {
      saved.emplace(*checkpoint, bounds_checkpoint_settings("", p, gap_tol, fn_tol, lp, "", sys->num_contacts()));
      saved->attach(lp, checkpoint_every, 0, stop, time_so_far);
    }
    b = compute_force_bounds(*sys, lp, dist);  // incomplete if should_stop stopped it
    if (saved && !b.complete) saved->save(b, time_so_far());
    if (saved && b.complete) saved->remove();
    if (b.complete) rank = equilibrium_rank(*sys);
  } catch (const Error&) {
    report.rethrow_if_failed();
    poll.rethrow_if_interrupted();
    throw;
  }
  report.rethrow_if_failed();
  poll.rethrow_if_interrupted();
  const int Nc = sys->num_contacts();
  py::dict d = contact_columns(p, sys->contacts);
  d["fn_min"] = py::array_t<double>(Nc, b.fn_min.data());
  d["fn_max"] = py::array_t<double>(Nc, b.fn_max.data());
  d["dimension"] = rank.dimension;
  d["rank"] = rank.rank;
  d["min_lps_skipped"] = b.min_lps_skipped;
  // How the LPs were solved, as bounds.json says it (docs/ensemble.md, "The LP").
  d["iterations"] = b.iterations;
  d["lps_at_looser_tolerance"] = b.loosened_solves;
  d["lps_finished_by_simplex"] = b.simplex_finishes;
  d["lps_solved_unscaled"] = b.unscaled_solves;
  d["lp_tolerance"] = lp.tolerance;
  d["open_tol_F0"] = lp.open_tol_F0;
  return d;
}

// unjam.friction_threshold: as `unjam threshold` (ensemble/friction_threshold). between: (LO, HI),
// a bracket to start from. Ctrl-C stops it between two LPs (KeyboardInterrupt). With
// `checkpoint` (a file path): resumes from the bracket saved there (a checkpoint of another
// packing or other settings is refused, as is one beside `between`), saves the bracket after
// every LP once both ends are checked, and removes the file at the end
// (campaign/threshold_checkpoint; the file of `unjam threshold`).
// progress: given a dict (done, total: this run's LPs; mu_s_low, mu_s_high: the bracket so far;
// elapsed_s, eta_s) after every LP, as the tool's progress lines; its first exception stops the
// bisection as Ctrl-C does (the checkpoint kept) and is raised.
py::dict friction_threshold_of(const Packing& p, double rel_tol, double gap_tol, double fn_tol,
                               std::optional<std::pair<double, double>> between,
                               const std::optional<std::filesystem::path>& checkpoint,
                               std::optional<py::function> progress) {
  FrictionThresholdOptions o;
  o.rel_tol = rel_tol;
  if (between) std::tie(o.mu_low, o.mu_high) = *between;
  SignalPoll poll;
  Callback report(std::move(progress));
  o.should_stop = [&] { return report.failed() || poll(); };
  if (report)
    o.progress = [&report, t_start = std::chrono::steady_clock::now()](int total, const FrictionThreshold& so_far) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      report([&] {
        py::dict d;
        d["done"] = so_far.lps;
        d["total"] = total;
        d["mu_s_low"] = so_far.mu_low;
        d["mu_s_high"] = so_far.mu_high;
        d["elapsed_s"] = t;
        d["eta_s"] = so_far.lps > 0 ? t * (total - so_far.lps) / so_far.lps : 0.0;
        return d;
      });
    };
  FrictionThreshold t;
  int contacts = 0;
  std::optional<ThresholdCheckpoint> saved;
  try {
    py::gil_scoped_release release;
    const EquilibriumSystem sys = admissible_system(p, gap_tol, fn_tol);
    contacts = sys.num_contacts();
    if (checkpoint) {
      saved.emplace(*checkpoint, threshold_checkpoint_settings(p, gap_tol, fn_tol, contacts, sys.mu, rel_tol));
      saved->attach(o);
    }
    t = friction_threshold(sys, o);
    if (saved) {
      t = saved->with_earlier(t);
      saved->remove();
    }
  } catch (const Error&) {
    report.rethrow_if_failed();
    poll.rethrow_if_interrupted();
    throw;
  }
  report.rethrow_if_failed();
  py::dict d;
  d["mu"] = t.mu;
  d["mu_s_low"] = t.mu_low;
  d["mu_s_high"] = t.mu_high;
  d["contacts"] = contacts;
  d["lps"] = t.lps;
  d["simplex_iterations"] = t.iterations;
  d["seconds"] = t.seconds;
  const std::optional<ThresholdProgress> resumed = saved ? saved->resumed() : std::nullopt;
  d["runs"] = resumed ? resumed->runs + 1 : 1;
  d["resumed_from"] = resumed ? py::object(py::make_tuple(resumed->so_far.mu_low, resumed->so_far.mu_high)) : py::none();
  return d;
}

py::object stats(const Packing& p, double threshold) {
  if (!(threshold >= 0.0)) throw Error("threshold must be a non-negative number");
  const nlohmann::ordered_json j = stats_json(p, compute_packing_stats(p, threshold), threshold, "");
  return py::module_::import("json").attr("loads")(j.dump());
}

void export_packing(const Packing& p, const std::filesystem::path& path, const std::string& format,
                    const ProbeResult* probe) {
  if (format != "vtk" && format != "xyz") throw Error("format must be vtk or xyz");
  std::optional<GrainDisplacement> field;
  if (probe) field = grain_displacement(*probe);
  const ExportRecord record{"", "python: unjam.export(format=" + format + ")"};
  const GrainDisplacement* f = field ? &*field : nullptr;
  write_file_atomic(path, format == "vtk" ? vtk_polydata(p, f, record) : extended_xyz(p, f, record));
}

py::array u_view(py::object self) {
  const ProbeResult& r = self.cast<const ProbeResult&>();
  py::array a = py::array_t<double>({r.u.size(), std::size_t(2)}, {sizeof(Vec2), sizeof(double)},
                                    r.u.empty() ? nullptr : r.u.front().data(), self);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

void bind_probe_result(py::module_& m) {
  py::class_<ProbeResult>(m, "ProbeResult",
                          "what one probe measures (docs/probe.md, \"The probe\")")
      .def_readonly("contact", &ProbeResult::contact)
      .def_readonly("a", &ProbeResult::a)
      .def_readonly("b", &ProbeResult::b)
      .def_readonly("f_cont", &ProbeResult::f_cont, "normal force of the static packing")
      .def_readonly("f_crit", &ProbeResult::f_crit, "normal force that opens the contact by g")
      .def_readonly("g", &ProbeResult::g)
      .def_readonly("lambda_dt", &ProbeResult::lambda_dt, "affine strain of the cell over the probe")
      .def_readonly("converged", &ProbeResult::converged)
      .def_readonly("sweeps", &ProbeResult::sweeps)
      .def_readonly("residual", &ProbeResult::residual)
      .def_readonly("violations", &ProbeResult::violations)
      .def_readonly("f_inertia", &ProbeResult::f_inertia,
                    "largest net force on a grain over the step, max m |u| / dt^2 (force units as f_crit; "
                    "NaN for lp): the load its inertia carries (docs/probe.md, \"The inertia of the step\")")
      .def_readonly("opened", &ProbeResult::opened,
                    "lemke, cd: contacts loaded in the packing (the probed one aside) that the step opens; -1 "
                    "for lp, nlgs or a probe without a solution (docs/probe.md, \"Which contacts the step opens "
                    "and sets sliding\")")
      .def_readonly("sliding", &ProbeResult::sliding,
                    "lemke, cd: contacts loaded in the packing (the probed one aside) that the step sets sliding "
                    "(|u_t| > 1e-6 g); -1 for lp, nlgs or a probe without a solution")
      .def_readonly("cpu_seconds", &ProbeResult::cpu_seconds,
                    "CPU time the probe took on its thread (s); a measurement that differs from run to run, "
                    "never a result (docs/probe.md, \"Campaigns\")")
      .def_property_readonly("u", &u_view, "(N, 2) float64 read-only view: peculiar displacement (R_max)")
      .def_property_readonly("rot", [](py::object self) {
        const ProbeResult& r = self.cast<const ProbeResult&>();
        py::array a = py::array_t<double>({r.u_rot.size()}, {sizeof(double)}, r.u_rot.data(), self);
        a.attr("setflags")(py::arg("write") = false);
        return a;
      }, "(N,) float64 read-only view: rotation of every grain (radians)");
}

}  // namespace

void bind_compute(py::module_& m) {
  bind_probe_result(m);
  const PackArgs pd;
  const CampaignSettings cd;
  m.def("pack", [](int n, double mu, std::uint64_t seed, int threads, double p_ext, double phi_gas,
                   double dt, double m_lambda, double tol, int max_sweeps, double static_tol,
                   std::int64_t max_steps, std::optional<std::filesystem::path> out,
                   std::optional<py::function> progress) {
          PackArgs a;
          a.gas.N = n;
          a.gas.seed = seed;
          a.gas.phi = phi_gas;
          a.mu = mu;
          a.P_ext = p_ext;
          a.threads = threads;
          a.out = std::move(out);
          a.progress = std::move(progress);
          auto& d = a.compaction.dynamics;
          d.dt = dt;
          d.bath.M_lambda = m_lambda;
          d.nlgs.tol = tol;
          d.nlgs.max_sweeps = max_sweeps;
          a.compaction.final_solve.tol = static_tol;
          a.compaction.max_steps = max_steps;
          return pack(a);
        },
        py::arg("n") = pd.gas.N, py::arg("mu") = pd.mu, py::arg("seed") = pd.gas.seed,
        py::arg("threads") = pd.threads, py::arg("p_ext") = pd.P_ext, py::arg("phi_gas") = pd.gas.phi,
        py::arg("dt") = pd.compaction.dynamics.dt, py::arg("m_lambda") = pd.compaction.dynamics.bath.M_lambda,
        py::arg("tol") = pd.compaction.dynamics.nlgs.tol, py::arg("max_sweeps") = pd.compaction.dynamics.nlgs.max_sweeps,
        py::arg("static_tol") = pd.compaction.final_solve.tol, py::arg("max_steps") = pd.compaction.max_steps,
        py::arg("out") = py::none(), py::arg("progress") = py::none(),
        "compact a gas of n disks into a static packing, as `unjam pack` (same seed, same bytes); "
        "progress: a callable given a dict (step, time, phi, P_in_over_P_ext, v_mean, contacts, "
        "elapsed_s, eta_s, ...) every 2 s");
  m.def("relax", &relax, py::arg("packing"), py::kw_only(), py::arg("mu"), py::arg("p_ext") = pd.P_ext,
        py::arg("threads") = pd.threads, py::arg("out") = py::none(), py::arg("progress") = py::none(),
        "re-relax a packing at friction mu and pressure p_ext with the settings it was made "
        "with, as `unjam pack --from DIR --mu MU --p-ext P` (same bytes); the packing given "
        "is not changed");
  m.def("probe", &probe, py::arg("packing"), py::kw_only(), py::arg("contact") = py::none(),
        py::arg("contacts") = py::none(), py::arg("method") = method_name(cd.method),
        py::arg("g") = cd.nlgs.g, py::arg("dt") = py::none(), py::arg("velocity_tol") = cd.nlgs.velocity_tol,
        py::arg("max_sweeps") = cd.nlgs.max_sweeps, py::arg("cd_start") = cd_start_name(cd.cd.start),
        py::arg("cd_softer_starts") = cd.cd.softer_starts, py::arg("window") = py::none(),
        py::arg("cd_max_pieces") = cd.cd.max_probe_pieces,
        py::arg("cd_interior_states_pieces") = cd.cd.interior_states_pieces,
        py::arg("cd_interior_states_stall") = cd.cd.interior_states_stall,
        py::arg("cd_interior_states_retries") = cd.cd.interior_states_retries,
        py::arg("cd_interior_iterations") = cd.cd.interior_max_iterations,
        py::arg("cd_interior_neighbourhood") = cd.cd.interior_neighbourhood,
        py::arg("cd_compliant_start") = cd.cd.compliant_start,
        py::arg("cd_accept_residual") = cd.cd.accept_residual, py::arg("cd") = py::none(),
        py::arg("lp_tol") = cd.kinematic.lp_tolerance, py::arg("threads") = 0, py::arg("progress") = py::none(), py::arg("running_every") = kRunningEverySeconds,
        "probe contact=K (a ProbeResult) or contacts=[...] (a list, probed in parallel on `threads` "
        "threads, 0: all cores; the same results for any count), as `unjam probe --contact K`; "
        "dt=None: the method's default (lemke, cd: sqrt(g / 1e-5), the quasi-static limit; nlgs: 1e-3); "
        "cd_start: where the cd method's path starts, 'static', 'compliant', 'lp' or 'interior' "
        "(`unjam probe --cd-start`; docs/probe.md, \"Where the path starts\"); cd_softer_starts: "
        "the continuation's softer starts, compliant and interior starts (`unjam probe --cd-softer-starts`); window: lemke, cd: "
        "the step on the grains within this many mean diameters of the probed pair, the others clamped "
        "to the cell, not the paper's probe (`unjam probe --window`; docs/probe.md, \"A window around "
        "the probed pair\"); None: the whole packing; cd_max_pieces: cd: stop a probe after this many pieces "
        "of its paths together (`unjam probe --cd-max-pieces`; docs/probe.md, \"A budget of pieces per "
        "probe\"); 0: no limit; cd_interior_states_pieces, cd_interior_states_stall, "
        "cd_interior_states_retries, cd_interior_iterations, cd_interior_neighbourhood: the interior start's "
        "settings, as `unjam probe --cd-interior-states-pieces`, `--cd-interior-states-stall`, "
        "`--cd-interior-states-retries`, `--cd-interior-iterations`, `--cd-interior-neighbourhood` "
        "(docs/probe.md, \"The iterate's own states\", \"The interior-point method's iterations\", "
        "\"Keeping the iterates centred\"); cd_compliant_start: the compliance of the compliant "
        "continuation's first path (compliant and interior starts), as `unjam probe --cd-compliant-start` "
        "(docs/probe.md, \"Where the continuation starts\"); cd_accept_residual: the residual (g) at which "
        "a cd probe stops at a near-exact solution instead of searching on for an exact one, as `unjam probe "
        "--cd-accept-residual` (docs/probe.md, \"Accepting a near-exact solution\"); cd: all of the cd method's "
        "settings as one unjam.CdSettings (its start included), instead of the cd_* keywords, which must then "
        "be left at their defaults; lp_tol: lp: the LP's tolerance, as `unjam probe --lp-tol` (docs/ensemble.md, "
        "\"The LP's tolerances\"); progress: a callable given a dict with event 'finished' once per "
        "finished probe, in the order they finish (index: the position in contacts, contact, result: its "
        "ProbeResult, done, total, elapsed_s, eta_s; keep the results it is given: Ctrl-C raises "
        "KeyboardInterrupt and returns nothing), and with event 'running' every running_every seconds of "
        "a probe that runs that long (nlgs, lemke, cd; contact, seconds, polls: cd pieces or nlgs sweeps / 16 "
        "so far, done, total, elapsed_s), as `unjam probe --running-every`; an exception it raises stops the "
        "probes and is raised");
  m.def("campaign_settings", &campaign_settings, py::arg("packing"), py::arg("path"),
        "the settings of a campaign of `unjam probe --all` or `--sample K` on this packing, read from its "
        "probe_summary.json or probe_checkpoint.json (path): a dict with method, g, dt (None for lp), cd "
        "(an unjam.CdSettings, the tool's defaults where the method is not cd), window (None: the whole "
        "packing), lp_tol, velocity_tol, max_sweeps, max_inertia (F0), displacement, force_threshold (F0), sample "
        "and seed; unjam.probe(packing, contact=K, method=d['method'], g=d['g'], dt=d['dt'], cd=d['cd'], "
        "window=d['window'], lp_tol=d['lp_tol']) probes contact K as the campaign did. Raises unjam.Error for a record the "
        "tool would not have written on this packing");
  m.def("bounds", &bounds, py::arg("packing"), py::kw_only(), py::arg("gap_tol") = 1e-9,
        py::arg("fn_tol") = 1e-9, py::arg("threads") = 0, py::arg("method") = "barrier",
        py::arg("lp_tol") = ForceBoundsOptions{}.tolerance, py::arg("open_tol") = ForceBoundsOptions{}.open_tol_F0,
        py::arg("checkpoint") = py::none(), py::arg("checkpoint_every") = 30.0, py::arg("progress") = py::none(),
        "[fn_min, fn_max] of every contact over the admissible force networks, as `unjam bounds`. "
        "lp_tol, open_tol: as --lp-tol and --open-tol (CLP's feasibility tolerance; a contact some admissible "
        "network loads with fn <= open_tol F0 has fn_min 0); outside their ranges unjam.Error. "
        "checkpoint: a file to resume from (if it is there) and to save the intervals known so far in, "
        "every checkpoint_every seconds and when interrupted (Ctrl-C: KeyboardInterrupt once it is saved); "
        "removed once every interval is known. A checkpoint of another packing or other settings is refused. "
        "progress: a callable given a dict (done, total: LPs, the resumed ones counted as done; elapsed_s, "
        "eta_s: at this run's pace) every 2 s and at the end; an exception it raises "
        "stops the LPs as Ctrl-C does (the checkpoint saved) and is raised");
  m.def("friction_threshold", &friction_threshold_of, py::arg("packing"), py::kw_only(), py::arg("rel_tol") = 1e-3,
        py::arg("gap_tol") = 1e-9, py::arg("fn_tol") = 1e-9, py::arg("between") = py::none(), py::arg("checkpoint") = py::none(),
        py::arg("progress") = py::none(),
        "The friction threshold, as `unjam threshold`: a dict with mu (the packing's), mu_s_low and mu_s_high "
        "(the smallest friction coefficient at which the contacts admit a force network lies in "
        "(mu_s_low, mu_s_high]; both 0 where one exists without friction), contacts, lps, simplex_iterations and "
        "seconds (of every run), runs and resumed_from (the checkpoint's bracket, or None). "
        "Bisection on the LP's feasibility until the bracket is narrower than rel_tol x mu; between=(LO, HI) "
        "starts from a bracket (no network at LO, one at HI; both checked). Ctrl-C stops it between LPs. "
        "checkpoint: a file to resume from (if it is there; `unjam threshold`'s friction_threshold_checkpoint.json "
        "is one) and to keep the bracket in after every LP once both ends are checked; removed at the end. "
        "A checkpoint of another packing or other settings, or one beside between, is refused. "
        "progress: a callable given a dict (done, total: this run's LPs; mu_s_low, mu_s_high: the bracket so far; "
        "elapsed_s, eta_s) after every LP; an exception it raises stops the bisection as Ctrl-C does (the "
        "checkpoint kept) and is raised");
  m.def("stats", &stats, py::arg("packing"), py::kw_only(), py::arg("threshold") = 1e-9,
        "phi, z, rattlers, residuals, ...: the object `unjam info --json` prints");
  m.def("export", &export_packing, py::arg("packing"), py::arg("path"), py::kw_only(),
        py::arg("format") = "vtk", py::arg("probe") = py::none(),
        "write the packing for ParaView (format='vtk', .vtp) or OVITO ('xyz'), optionally with "
        "a ProbeResult's displacement field, as `unjam export`");
}

}  // namespace unjam::python
