#include "unjam/probe/probe_campaign.hpp"

#include <omp.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <optional>
#include <random>

#include "unjam/analysis/contact_frame.hpp"
#include "unjam/core/error.hpp"
#include "unjam/probe/cd_step.hpp"

namespace unjam {
namespace {

ProbeRow row_of(const ProbeResult& r) {
  return {r.contact, r.a,        r.b,        r.f_cont,    r.f_crit,
          r.converged, r.sweeps, r.residual, r.violations, r.lambda_dt};
}

// One worker's probe engine: the LP-based probe keeps its model between probes.
struct Worker {
  std::unique_ptr<KinematicProbe> kinematic;
  ProbeResult probe(const Packing& p, const CampaignSettings& s, int contact) {
    if (s.method == ProbeMethod::kNlgs) return probe_nlgs(p, contact, s.nlgs);
    if (s.method == ProbeMethod::kLemke) return probe_cd_lemke(p, contact, s.nlgs).result;
    if (!kinematic) kinematic = std::make_unique<KinematicProbe>(p, s.kinematic);
    return kinematic->probe(contact);
  }
};

// Adds one probe's field to the averages: the grains of `loaded` (rattlers stay out), their
// displacement / g in the contact frame.
void add_to_average(const Packing& p, const CampaignSettings& s, const std::vector<char>& loaded,
                    const ProbeResult& r, ResponseAverage& average) {
  FrameField field;
  const ContactFrame frame = contact_frame(p.particles, p.contacts[r.contact]);
  std::vector<double> x, y;
  std::vector<Vec2> u;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!loaded[i]) continue;
    x.push_back(p.particles.x[i]);
    y.push_back(p.particles.y[i]);
    Vec2 ui = r.u[i];
    // Affine part of the cell's strain, relative to the contact point.
    if (s.total_displacement) ui += r.lambda_dt * p.cell.min_image(p.particles.position(i) - frame.origin);
    u.push_back(ui);
  }
  to_contact_frame(frame, p.cell, x, y, u, field);
  average.add_probe(r.contact, field, r.g);
}

}  // namespace

const char* method_name(ProbeMethod method) {
  switch (method) {
    case ProbeMethod::kLp: return "lp";
    case ProbeMethod::kNlgs: return "nlgs";
    case ProbeMethod::kLemke: return "lemke";
  }
  return "?";
}

ProbeMethod method_from_name(const std::string& name) {
  for (ProbeMethod m : {ProbeMethod::kLp, ProbeMethod::kNlgs, ProbeMethod::kLemke})
    if (name == method_name(m)) return m;
  throw Error("--method must be lp, nlgs or lemke (got '" + name + "')");
}

std::vector<int> campaign_targets(const Packing& p, const CampaignSettings& s) {
  std::vector<int> targets;
  const double f_min = s.force_threshold * p.force_unit();
  for (int k = 0; k < static_cast<int>(p.contacts.size()); ++k)
    if (p.contacts[k].fn > f_min) targets.push_back(k);
  if (s.sample > 0 && s.sample < static_cast<int>(targets.size())) {
    std::mt19937_64 rng(s.seed);
    std::shuffle(targets.begin(), targets.end(), rng);
    targets.resize(s.sample);
    std::sort(targets.begin(), targets.end());
  }
  return targets;
}

ProbeResult probe_contact(const Packing& p, const CampaignSettings& s, int contact) {
  Worker w;
  return w.probe(p, s, contact);
}

bool run_campaign(const Packing& p, const CampaignSettings& s, CampaignState& state,
                  const CampaignHooks& hooks) {
  const std::vector<int> all = campaign_targets(p, s);
  std::vector<int> todo;
  std::vector<char> listed(p.contacts.size(), 0);
  for (const ProbeRow& r : state.rows) {
    if (r.contact < 0 || r.contact >= static_cast<int>(p.contacts.size()))
      throw Error("the saved probes list contact " + std::to_string(r.contact) + ", but the packing has " +
                  std::to_string(p.contacts.size()) + " contacts");
    listed[r.contact] = 1;
  }
  for (const int k : all)
    if (!state.average.has_probe(k) && !listed[k]) todo.push_back(k);
  const std::vector<char> loaded = p.loaded_grains(s.force_threshold * p.force_unit());
  const int threads = omp_get_max_threads();
  std::vector<Worker> workers(threads);
  // Batches of a few probes per thread: between batches the state is merged, reported,
  // checkpointed, and a stop request is honoured.
  const int batch = 4 * threads;
  for (std::size_t start = 0; start < todo.size(); start += batch) {
    if (hooks.should_stop && hooks.should_stop()) return false;
    const int n = static_cast<int>(std::min<std::size_t>(batch, todo.size() - start));
    std::vector<std::optional<ProbeResult>> results(n);
    std::vector<std::string> errors(n);
#pragma omp parallel for schedule(dynamic, 1)
    for (int j = 0; j < n; ++j) {
      try {
        results[j] = workers[omp_get_thread_num()].probe(p, s, todo[start + j]);
      } catch (const std::exception& e) {
        errors[j] = e.what();
      }
    }
    for (int j = 0; j < n; ++j) {
      if (!results[j]) throw Error("probe of contact " + std::to_string(todo[start + j]) + ": " + errors[j]);
      if (results[j]->residual != kNoSolution) add_to_average(p, s, loaded, *results[j], state.average);
      state.rows.push_back(row_of(*results[j]));
    }
    std::sort(state.rows.begin(), state.rows.end(),
              [](const ProbeRow& x, const ProbeRow& y) { return x.contact < y.contact; });
    if (hooks.progress) hooks.progress(static_cast<int>(state.rows.size()), static_cast<int>(all.size()));
    if (hooks.checkpoint) hooks.checkpoint(state);
  }
  return true;
}

CampaignSummary summarize(const Packing& p, const CampaignState& state,
                          std::optional<FitWindow> window, int bootstrap_samples, std::uint64_t seed) {
  CampaignSummary sum;
  sum.probes = static_cast<int>(state.rows.size());
  double f_cont = 0.0, f_crit = 0.0;
  int solved = 0;
  for (const ProbeRow& r : state.rows) {
    if (!r.converged) ++sum.not_converged;
    if (r.residual == kNoSolution) continue;
    ++solved;
    f_cont += r.f_cont;
    f_crit += r.f_crit;
  }
  if (solved > 0) {
    sum.F_cont_over_F0 = f_cont / solved / p.force_unit();
    sum.F_crit_over_F_cont = f_crit / f_cont;
  }
  try {
    sum.fit = fit_power_law(state.average,
                            window.value_or(default_fit_window(p.cell, 2.0 * p.mean_radius())),
                            bootstrap_samples, seed);
    sum.has_fit = true;
  } catch (const Error& e) {
    sum.fit_error = e.what();
  }
  return sum;
}

nlohmann::json to_json(const CampaignSettings& s) {
  const bool lp = s.method == ProbeMethod::kLp;
  nlohmann::json j = {
      {"method", method_name(s.method)},
      {"g", lp ? s.kinematic.g : s.nlgs.g},
      {"touch_gap", lp ? s.kinematic.touch_gap : s.nlgs.touch_gap},
      {"displacement", s.total_displacement ? "total" : "peculiar"},
      {"force_threshold_F0", s.force_threshold},
      {"sample", s.sample},
      {"seed", s.seed},
  };
  if (lp) {
    j["state_tol_F0"] = s.kinematic.state_tol;
    j["M_lambda"] = s.kinematic.M_lambda;
  } else {
    j["dt"] = s.nlgs.dt;
    j["M_lambda"] = s.nlgs.bath.M_lambda;
    if (s.method == ProbeMethod::kNlgs) {
      j["velocity_tol"] = s.nlgs.velocity_tol;
      j["max_sweeps"] = s.nlgs.max_sweeps;
    }
  }
  return j;
}

nlohmann::json to_json(const CampaignState& state) {
  nlohmann::json rows = nlohmann::json::array();
  for (const ProbeRow& r : state.rows)
    rows.push_back({r.contact, r.a, r.b, r.f_cont, r.f_crit, r.converged, r.sweeps, r.residual,
                    r.violations, r.lambda_dt});
  return {{"rows", rows}, {"average", state.average.to_json()}};
}

CampaignState campaign_state_from_json(const nlohmann::json& j) {
  try {
    CampaignState state(ResponseAverage::from_json(j.at("average")).grid());
    state.average = ResponseAverage::from_json(j.at("average"));
    for (const auto& r : j.at("rows"))
      state.rows.push_back({r.at(0).get<int>(), r.at(1).get<int>(), r.at(2).get<int>(),
                            r.at(3).get<double>(), r.at(4).get<double>(), r.at(5).get<bool>(),
                            r.at(6).get<long long>(), r.at(7).get<double>(), r.at(8).get<int>(),
                            r.at(9).get<double>()});
    return state;
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("probe checkpoint is corrupt: ") + e.what());
  }
}

}  // namespace unjam
