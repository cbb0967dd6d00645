#include "unjam/campaign/ensemble_run.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "unjam/core/error.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam {

namespace {

constexpr std::size_t kMaxContactsOfTheDefaultCdProbe = 200;  // EnsembleSettings::probe empty: cd up to it

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Mean over contacts with a nonzero LP width of (sampled width) / (LP width); 1 if none.
double mean_coverage(const SampledForces& s, const ForceBounds& b, double F0) {
  double sum = 0.0;
  int n = 0;
  for (Eigen::Index k = 0; k < b.fn_max.size(); ++k) {
    const double width = b.fn_max[k] - b.fn_min[k];
    if (width > 1e-9 * F0) {
      sum += (s.sample_max[k] - s.sample_min[k]) / width;
      ++n;
    }
  }
  return n > 0 ? sum / n : 1.0;
}

SamplerReport columns(const SampledForces& s, const ForceBounds& b, double F0, double seconds) {
  return {s.sample_min, s.sample_max, s.mean, s.std, mean_coverage(s, b, F0), seconds};
}

// F_crit of every force-carrying contact of the system, by probe_contacts (the campaign's
// loop: errors inside the parallel region are caught there and rethrown naming the contact).
void run_probes(const Packing& packing, const EnsembleSettings& in, int threads, EnsembleReport& r) {
  const EquilibriumSystem& sys = r.system;
  std::vector<int> todo, contacts;  // positions in the system, and their packing contacts
  for (int k = 0; k < sys.num_contacts(); ++k)
    if (packing.contacts[sys.contacts[k]].fn > in.fn_tol * sys.F0) {
      todo.push_back(k);
      contacts.push_back(sys.contacts[k]);
    }
  CampaignSettings s = *r.probe_settings;
  s.nlgs.cancel = in.should_stop;  // inside a running probe (nlgs, cd)
  r.probe_dt = s.method == ProbeMethod::kLp ? 0.0 : s.nlgs.dt;
  const std::string what = "probe " + r.probe + " (contacts)";
  const auto t0 = std::chrono::steady_clock::now();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);  // probe_contacts runs on omp_get_max_threads() threads
  std::vector<ProbeResult> results;
  try {
    ProbeListHooks hooks;
    hooks.should_stop = in.should_stop;  // before each probe
    hooks.progress = [&](const FinishedProbe& f) {
      if (in.progress) in.progress(what, f.done, f.total);
    };
    results = probe_contacts(packing, s, contacts, hooks);
  } catch (...) {
    omp_set_num_threads(saved);
    throw;
  }
  omp_set_num_threads(saved);
  if (results.size() < contacts.size()) throw Cancelled();  // stopped before the last probe
  r.probe_seconds = seconds_since(t0);
  r.probes.resize(sys.num_contacts());
  for (std::size_t i = 0; i < results.size(); ++i) r.probes[todo[i]] = results[i];
  for (int k = 0; k < sys.num_contacts(); ++k)
    if (const auto& p = r.probes[k]) {
      r.f_crit_over_fn_max.push_back(p->f_crit / r.bounds.fn_max[k]);
      const double width = r.bounds.fn_max[k] - r.bounds.fn_min[k];
      if (width > 1e-6 * sys.F0) r.f_crit_position.push_back((p->f_crit - r.bounds.fn_min[k]) / width);
      r.below_f_cont += p->f_crit < p->f_cont ? 1 : 0;
      r.unconverged += p->converged ? 0 : 1;
    }
}

// The probe of a set of `contacts` contacts: in.probe, or where it is empty cd up to
// kMaxContactsOfTheDefaultCdProbe, else lp.
std::string probe_method(const EnsembleSettings& in, std::size_t contacts) {
  if (!in.probe.empty()) return in.probe;
  return contacts <= kMaxContactsOfTheDefaultCdProbe ? "cd" : "lp";
}

// Throws Cancelled once in.should_stop (if any) says so.
void stop_if_asked(const EnsembleSettings& in) {
  if (in.should_stop && in.should_stop()) throw Cancelled();
}

}  // namespace

CriticalForceRatio critical_force_ratio(const std::vector<double>& ratio) {
  const auto within = [&ratio](double f) {
    return static_cast<int>(
        std::count_if(ratio.begin(), ratio.end(), [f](double x) { return std::abs(x - 1.0) <= f; }));
  };
  return {quantile(ratio, 0.0), quantile(ratio, 0.5), quantile(ratio, 1.0),
          within(0.01),         within(0.02),         within(0.05)};
}

ContactModel ensemble_contact_model(const Packing& packing, const EnsembleSettings& in) {
  return with_touch_gap(packing.meta.contact, in.gap_tol);
}

CampaignSettings ensemble_probe_settings(const Packing& packing, const EnsembleSettings& in,
                                         const std::string& method) {
  CampaignSettings s = campaign_settings_for(packing);
  s.method = method_from_name(method);
  s.nlgs.g = s.kinematic.g = in.probe_g;
  s.nlgs.dt = in.probe_dt > 0.0 ? in.probe_dt : default_probe_dt(s.method, in.probe_g);
  s.nlgs.velocity_tol = in.probe_velocity_tol;
  s.cd = in.probe_cd;
  // The lp probe's LP at the intervals' tolerance: its F_crit is their fn_max where the sets
  // agree (docs/ensemble.md, "The LP's tolerances").
  if (s.method == ProbeMethod::kLp) s.kinematic.lp_tolerance = in.lp_tol;
  validate(s);
  return s;  // P_ext: the nlgs probe takes the packing's own (probe/nlgs_probe)
}

std::string ensemble_probe_method(const Packing& packing, const EnsembleSettings& in) {
  return probe_method(in, select_contacts(packing, ensemble_contact_model(packing, in), in.fn_tol).size());
}

EnsembleReport compute_ensemble(const Packing& packing, const EnsembleSettings& in) {
  EnsembleReport r;
  r.system = admissible_system(packing, ensemble_contact_model(packing, in), in.fn_tol);
  const EquilibriumSystem& sys = r.system;
  r.probe = probe_method(in, static_cast<std::size_t>(sys.num_contacts()));  // sys: select_contacts' set
  // An unknown name or a setting that does not apply is refused before the LPs.
  if (r.probe != "none") r.probe_settings = ensemble_probe_settings(packing, in, r.probe);
  const int threads = in.threads > 0 ? in.threads : omp_get_max_threads();
  ForceBoundsOptions lp;
  lp.threads = threads;
  lp.tolerance = in.lp_tol;
  lp.open_tol_F0 = in.open_tol;
  lp.should_stop = in.should_stop;
  r.bounds = compute_force_bounds(sys, lp);
  if (!r.bounds.complete) throw Cancelled();
  if (in.hit_and_run) {
    HitAndRunOptions hr;
    hr.samples = in.samples;
    hr.seed = in.seed;
    hr.thin = in.thin;
    hr.burn_in = in.burn_in;
    if (in.on_sample || in.should_stop)
      hr.on_sample = [&in](const ForceNetwork& net) {  // after every sample
        if (in.on_sample) in.on_sample(net);
        stop_if_asked(in);
      };
    const auto t = std::chrono::steady_clock::now();
    r.hit_and_run = sample_hit_and_run(sys, r.bounds, hr);
    r.hr_columns = columns(*r.hit_and_run, r.bounds, sys.F0, seconds_since(t));
  }
  if (in.walk) {
    RandomWalkOptions walk;
    walk.samples = in.samples;
    walk.seed = in.seed;
    walk.kick = in.kick;
    walk.tol = in.walk_tol;
    walk.model = ensemble_contact_model(packing, in);  // the model that selected the set
    if (in.progress || in.should_stop)
      walk.progress = [&in](int done, int total) {  // after every step
        if (in.progress) in.progress("random walk (steps)", done, total);
        stop_if_asked(in);
      };
    const auto t = std::chrono::steady_clock::now();
    r.walk = sample_random_walk(packing, sys, walk);
    r.walk_columns = columns(*r.walk, r.bounds, sys.F0, seconds_since(t));
  }
  if (r.probe != "none") run_probes(packing, in, threads, r);
  return r;
}

nlohmann::ordered_json ensemble_methods_json(const EnsembleSettings& s, const EnsembleReport& r) {
  nlohmann::ordered_json methods = nlohmann::ordered_json::object();
  if (const auto& h = r.hit_and_run)
    methods["hit_and_run"] = {{"description", "hit-and-run, uniform on the admissible polytope"},
                              {"eta", h->eta},
                              {"mean_fn", h->mean_fn},
                              {"mean_coverage_of_lp_width", r.hr_columns->coverage},
                              {"samples", h->samples},
                              {"steps", h->steps},
                              {"dimension", h->dimension},
                              {"contacts_open_in_every_network", h->fixed_open},
                              {"start_depth", h->start_depth},
                              {"thin", s.thin},
                              {"burn_in", s.burn_in},
                              {"seconds", r.hr_columns->seconds}};
  if (const auto& w = r.walk)
    methods["walk"] = {{"description", "random walk: kicks U(-a, a) on fn and ft, a = kick <F_n>, relaxed "
                                       "by the static contact-dynamics solve"},
                       {"eta", w->eta},
                       {"mean_fn", w->mean_fn},
                       {"mean_coverage_of_lp_width", r.walk_columns->coverage},
                       {"samples", w->samples},
                       {"failures", w->failures},
                       {"kick", s.kick},
                       {"kick_amplitude", w->kick_amplitude},
                       {"solve_tol_F0", s.walk_tol},
                       {"nlgs_sweeps", w->sweeps},
                       {"seconds", r.walk_columns->seconds}};
  return methods;
}

nlohmann::ordered_json ensemble_probe_json(const EnsembleSettings& s, const EnsembleReport& r) {
  nlohmann::ordered_json j = {{"method", r.probe}};
  if (r.probe == "none") return j;
  const std::vector<double>& ratio = r.f_crit_over_fn_max;
  j["contacts_probed"] = ratio.size();
  j["unconverged"] = r.unconverged;
  j["settings"] = {{"g", s.probe_g}, {"dt", r.probe_dt}, {"threads", s.threads}};
  if (r.probe == "nlgs") j["settings"]["velocity_tol_g_per_dt"] = s.probe_velocity_tol;
  if (r.probe == "cd") {  // its start, and its other settings as `unjam probe` records them where set
    j["settings"]["start"] = cd_start_name(r.probe_settings->cd.start);
    const nlohmann::json recorded = to_json(*r.probe_settings);
    for (const auto& [key, value] : recorded.items())
      if (key.rfind("cd_", 0) == 0 && key != "cd_start") j["settings"][key] = value;
  }
  if (!ratio.empty()) {
    const CriticalForceRatio c = critical_force_ratio(ratio);
    j["f_crit_over_fn_max"] = {{"min", c.min},
                               {"median", c.median},
                               {"max", c.max},
                               {"within_1_percent", c.within_1_percent},
                               {"within_2_percent", c.within_2_percent},
                               {"within_5_percent", c.within_5_percent}};
  }
  const std::vector<double>& t = r.f_crit_position;
  if (!t.empty())
    j["position_in_interval"] = {
        {"min", quantile(t, 0.0)},
        {"median", quantile(t, 0.5)},
        {"at_top", std::count_if(t.begin(), t.end(), [](double x) { return x >= 0.99; })}};
  j["below_f_cont"] = r.below_f_cont;
  j["seconds"] = r.probe_seconds;
  return j;
}

nlohmann::ordered_json ensemble_parameters_json(const EnsembleSettings& s) {
  return {{"gap_tol", s.gap_tol}, {"fn_tol_F0", s.fn_tol}, {"lp_tolerance", s.lp_tol}, {"open_tol_F0", s.open_tol}};
}

}  // namespace unjam
