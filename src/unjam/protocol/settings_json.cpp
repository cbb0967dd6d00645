#include "unjam/protocol/settings_json.hpp"

#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"

namespace unjam {
namespace {

template <class T>
void read(const nlohmann::json& j, const char* key, T& value) {
  if (!j.contains(key)) return;
  try {
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>)
      value = json_integer<T>(j.at(key), std::string("settings: '") + key + "'");
    else
      value = j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw Error(std::string("settings: '") + key + "' has the wrong type");
  }
}

}  // namespace

nlohmann::json to_json(const CompactionSettings& s, const GasSettings& g) {
  const auto& d = s.dynamics;
  return {
      {"gas", {{"N", g.N}, {"R_min", g.R_min}, {"R_max", g.R_max}, {"phi", g.phi}, {"seed", g.seed}}},
      {"dynamics",
       {{"dt", d.dt}, {"M_lambda", d.bath.M_lambda}, {"nlgs_tol", d.nlgs.tol},
        {"nlgs_max_sweeps", d.nlgs.max_sweeps}, {"min_detection", d.min_detection}}},
      {"static",
       {{"v_static", s.v_static}, {"p_static", s.p_static}, {"attempt_budget", s.attempt_budget},
        {"tol", s.final_solve.tol}, {"polish_from", s.final_solve.polish_from},
        {"touch_gap", s.final_solve.touch_gap}, {"max_sweeps", s.final_solve.max_sweeps}}},
  };
}

void from_json(const nlohmann::json& j, CompactionSettings& s, GasSettings& g) {
  if (!j.is_object()) return;
  if (j.contains("gas")) {
    const auto& x = j["gas"];
    read(x, "N", g.N);
    read(x, "R_min", g.R_min);
    read(x, "R_max", g.R_max);
    read(x, "phi", g.phi);
    read(x, "seed", g.seed);
  }
  if (j.contains("dynamics")) {
    const auto& x = j["dynamics"];
    auto& d = s.dynamics;
    read(x, "dt", d.dt);
    read(x, "M_lambda", d.bath.M_lambda);
    read(x, "nlgs_tol", d.nlgs.tol);
    read(x, "nlgs_max_sweeps", d.nlgs.max_sweeps);
    read(x, "min_detection", d.min_detection);
  }
  if (j.contains("static")) {
    const auto& x = j["static"];
    read(x, "v_static", s.v_static);
    read(x, "p_static", s.p_static);
    read(x, "attempt_budget", s.attempt_budget);
    read(x, "tol", s.final_solve.tol);
    read(x, "polish_from", s.final_solve.polish_from);
    read(x, "touch_gap", s.final_solve.touch_gap);
    read(x, "max_sweeps", s.final_solve.max_sweeps);
  }
}

void apply_contact_model(const ContactModel& model, CompactionSettings& settings) {
  settings.dynamics.bath.M_lambda = model.M_lambda;
  settings.final_solve.touch_gap = model.touch_gap;
}

void prepare_compaction(Packing& p, CompactionSettings& settings, const GasSettings& gas,
                        const std::string& command) {
  settings.dynamics.bath.P_ext = p.meta.contact.P_ext;
  validate(settings, p.meta.contact.mu);
  p.meta.settings = to_json(settings, gas);
  p.meta.contact.M_lambda = settings.dynamics.bath.M_lambda;
  p.meta.contact.touch_gap = settings.final_solve.touch_gap;
  p.meta.command = command;
}

void prepare_relaxation(Packing& p, double mu, double P_ext, CompactionSettings& settings,
                        GasSettings& gas) {
  from_json(p.meta.settings, settings, gas);
  apply_contact_model(p.meta.contact, settings);
  p.meta.contact.mu = mu;
  p.meta.contact.P_ext = P_ext;
}

}  // namespace unjam
