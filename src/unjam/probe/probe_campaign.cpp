#include "unjam/probe/probe_campaign.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <string>

#include "unjam/analysis/contact_frame.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/checkpoint_settings.hpp"
#include "unjam/core/cpu_time.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/core/quantile.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/cd_step.hpp"
#include "unjam/protocol/settings_json.hpp"

namespace unjam {
namespace {

// A double that may be NaN in JSON, which has no NaN: null stands for it.
nlohmann::json nullable(double v) { return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }
double nullable_from(const nlohmann::json& j, const char* what) {
  if (j.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!j.is_number()) throw Error(std::string(what) + " is not a number or null");
  return j.get<double>();
}

ProbeRow row_of(const ProbeResult& r) {
  return {r.contact, r.a,        r.b,        r.f_cont,    r.f_crit,
          r.converged, r.sweeps, r.residual, r.violations, r.lambda_dt, r.f_inertia, r.opened, r.sliding,
          r.cpu_seconds};
}

// One worker's probe engine: the LP-based probe keeps its model between probes.
struct Worker {
  std::unique_ptr<KinematicProbe> kinematic;
  ProbeResult probe(const Packing& p, const CampaignSettings& s, int contact) {
    if (s.method == ProbeMethod::kNlgs) return probe_nlgs(p, contact, s.nlgs);
    if (s.method == ProbeMethod::kLemke) return probe_cd_lemke(p, contact, s.nlgs).result;
    if (s.method == ProbeMethod::kCd) return probe_cd_path(p, contact, s.nlgs, s.cd).result;
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

// A probe's row and field as bytes (what travels to the gathering process).
std::string encode(const ProbeResult& r) {
  ByteWriter w;
  w.put(r.contact).put(r.a).put(r.b).put(r.f_cont).put(r.f_crit).put(r.g).put(r.lambda_dt);
  w.put(r.converged).put(r.sweeps).put(r.residual).put(r.violations).put(r.f_inertia).put(r.opened).put(r.sliding);
  w.put(r.cpu_seconds);
  std::vector<double> u(2 * r.u.size());
  for (std::size_t i = 0; i < r.u.size(); ++i) u[2 * i] = r.u[i].x(), u[2 * i + 1] = r.u[i].y();
  w.put_array(u.data(), u.size());
  w.put_array(r.u_rot.data(), r.u_rot.size());
  return w.take();
}

ProbeResult decode(const std::string& bytes) {
  ByteReader in(bytes);
  ProbeResult r;
  r.contact = in.get<int>();
  r.a = in.get<int>();
  r.b = in.get<int>();
  r.f_cont = in.get<double>();
  r.f_crit = in.get<double>();
  r.g = in.get<double>();
  r.lambda_dt = in.get<double>();
  r.converged = in.get<bool>();
  r.sweeps = in.get<long long>();
  r.residual = in.get<double>();
  r.violations = in.get<int>();
  r.f_inertia = in.get<double>();
  r.opened = in.get<int>();
  r.sliding = in.get<int>();
  r.cpu_seconds = in.get<double>();
  const std::vector<double> u = in.get_array<double>();
  for (std::size_t i = 0; i + 1 < u.size(); i += 2) r.u.emplace_back(u[i], u[i + 1]);
  r.u_rot = in.get_array<double>();
  return r;
}

// The work of a loop of probes on this process: task t probes contacts[t] (contact t if
// `contacts` is null), one probe per thread at a time on omp_get_max_threads() threads, each
// thread with its own worker (the LP probe keeps its model); each result as bytes. A probe
// that s.nlgs.cancel abandons comes back cancelled (work_off). `running` (may be empty): see
// CampaignHooks::running.
void probe_tasks(WorkSource& source, const Packing& p, const CampaignSettings& s,
                 const std::vector<int>* contacts, const std::function<void(int, double, long long)>& running = {},
                 double running_every_s = 0.0) {
  work_off(source, omp_get_max_threads(), 1, [] { return Worker{}; }, [&](Worker& w, int t) {
    const int k = contacts ? (*contacts)[t] : t;
    try {
      const double cpu0 = thread_cpu_seconds();  // one probe per thread: its CPU is this thread's
      // (a probe that does not poll has nothing to report, nor a copy of the settings to make)
      ProbeResult r = running && probe_polls(s.method) ? w.probe(p, with_running(s, k, running, running_every_s), k)
                                                       : w.probe(p, s, k);
      r.cpu_seconds = thread_cpu_seconds() - cpu0;
      return encode(r);
    } catch (const Cancelled&) {
      throw;
    } catch (const std::exception& e) {
      throw Error("probe of contact " + std::to_string(k) + ": " + e.what());
    }
  });
}

// Whether `a` or `b` (each may be empty) returns true; empty if both are.
std::function<bool()> either(const std::function<bool()>& a, const std::function<bool()>& b) {
  if (!a) return b;
  if (!b) return a;
  return [a, b] { return a() || b(); };
}

// The cd method with the interior-point start: that start, or the inertial start, whose first
// stage, jumps and fallback are interior-point starts (docs/probe.md, "The quasi-static step
// as the limit of vanishing inertia").
bool has_interior(const CampaignSettings& s) {
  return s.method == ProbeMethod::kCd &&
         (s.cd.start == CdPathStart::interior_point || s.cd.start == CdPathStart::inertial ||
          s.cd.start == CdPathStart::interior_inertial);
}

// The cd method with a continuation in dt: the inertial and interior-inertial starts.
bool has_inertial(const CampaignSettings& s) {
  return s.method == ProbeMethod::kCd &&
         (s.cd.start == CdPathStart::inertial || s.cd.start == CdPathStart::interior_inertial);
}

// The continuation in dt's counts (CdPathSettings::inertial_stages to inertial_jumps): each
// one's key in a campaign's record, its option and its least value. Its factor
// (inertial_factor, a number > 1) is handled beside them.
struct InertialCount {
  const char* key;
  const char* option;
  int CdPathSettings::*field;
  int least;
};
constexpr InertialCount kInertialCounts[] = {
    {"cd_inertial_stages", "--cd-inertial-stages", &CdPathSettings::inertial_stages, 1},
    {"cd_inertial_halvings", "--cd-inertial-halvings", &CdPathSettings::inertial_halvings, 0},
    {"cd_inertial_retries", "--cd-inertial-retries", &CdPathSettings::inertial_retries, 0},
    {"cd_inertial_jumps", "--cd-inertial-jumps", &CdPathSettings::inertial_jumps, 0}};

// The option of the first setting of the continuation in dt that is not its default; nullptr
// if none.
const char* changed_inertial_option(const CdPathSettings& cd) {
  const CdPathSettings d;
  if (cd.inertial_factor != d.inertial_factor) return "--cd-inertial-factor";
  for (const InertialCount& c : kInertialCounts)
    if (cd.*c.field != d.*c.field) return c.option;
  return nullptr;
}

// The cd method with a compliant continuation: the compliant start, or a start with the
// interior-point start, which falls back to it (docs/probe.md, "An interior-point start").
bool has_continuation(const CampaignSettings& s) {
  return has_interior(s) || (s.method == ProbeMethod::kCd && s.cd.start == CdPathStart::compliant);
}

}  // namespace

CampaignSettings with_running(const CampaignSettings& s, int k,
                              const std::function<void(int, double, long long)>& running, double every) {
  if (!(every >= 0.0)) throw Error("with_running: the interval must be >= 0 s (got " + std::to_string(every) + ")");
  if (!running || !probe_polls(s.method)) return s;
  CampaignSettings st = s;
  using clock = std::chrono::steady_clock;
  st.nlgs.cancel = [cancel = s.nlgs.cancel, running, k, every, t0 = clock::now(), next = every,
                    polls = 0LL]() mutable {
    ++polls;
    const double seconds = std::chrono::duration<double>(clock::now() - t0).count();
    if (seconds >= next) {
      running(k, seconds, polls);
      next = every > 0.0 ? every * (std::floor(seconds / every) + 1.0) : seconds;
    }
    return cancel && cancel();
  };
  return st;
}

const char* method_name(ProbeMethod method) {
  switch (method) {
    case ProbeMethod::kLp: return "lp";
    case ProbeMethod::kNlgs: return "nlgs";
    case ProbeMethod::kLemke: return "lemke";
    case ProbeMethod::kCd: return "cd";
  }
  return "?";
}

ProbeMethod method_from_name(const std::string& name) {
  for (ProbeMethod m : {ProbeMethod::kLp, ProbeMethod::kNlgs, ProbeMethod::kLemke, ProbeMethod::kCd})
    if (name == method_name(m)) return m;
  throw Error("--method must be lp, nlgs, lemke or cd (got '" + name + "')");
}

const char* cd_start_name(CdPathStart start) {
  switch (start) {
    case CdPathStart::lp_optimum: return "lp";
    case CdPathStart::compliant: return "compliant";
    case CdPathStart::interior_point: return "interior";
    case CdPathStart::inertial: return "inertial";
    case CdPathStart::interior_inertial: return "interior-inertial";
    case CdPathStart::static_network: break;
  }
  return "static";
}

CdPathStart cd_start_from_name(const std::string& name) {
  for (CdPathStart s : {CdPathStart::static_network, CdPathStart::lp_optimum, CdPathStart::compliant,
                        CdPathStart::interior_point, CdPathStart::inertial, CdPathStart::interior_inertial})
    if (name == cd_start_name(s)) return s;
  throw Error("--cd-start must be static, lp, compliant, interior, inertial or interior-inertial (got '" + name +
              "')");
}

CampaignSettings campaign_settings_for(const Packing& p) {
  CompactionSettings cs;
  GasSettings gas;
  from_json(p.meta.settings, cs, gas);  // refuses recorded settings that `pack --resume` would refuse
  CampaignSettings s;
  s.nlgs.model = s.kinematic.model = p.meta.contact;
  return s;
}

double default_probe_dt(ProbeMethod method, double g) {
  if (method == ProbeMethod::kLemke || method == ProbeMethod::kCd) return std::sqrt(g / kQuasiStaticInertia);
  return ProbeSettings{}.dt;
}

void validate(const CdPathSettings& cd) {
  if (cd.softer_starts < 0)
    throw Error("--cd-softer-starts must be >= 0 (got " + std::to_string(cd.softer_starts) + ")");
  if (!(cd.compliant_start > 0.0 && std::isfinite(cd.compliant_start)))
    throw Error("--cd-compliant-start must be positive and finite (got " + std::to_string(cd.compliant_start) + ")");
  if (cd.max_probe_pieces < 0)
    throw Error("--cd-max-pieces must be >= 0 (got " + std::to_string(cd.max_probe_pieces) + ")");
  if (!(cd.accept_residual >= kExactStepTolerance && cd.accept_residual <= kMaxPathResidual)) {
    char range[96];
    std::snprintf(range, sizeof range, "must be in [%g, %g] g (got %g)", kExactStepTolerance, kMaxPathResidual,
                  cd.accept_residual);
    throw Error(std::string("--cd-accept-residual ") + range);
  }
  if (!(cd.settle_compliance >= 0.0 && std::isfinite(cd.settle_compliance)))
    throw Error("--cd-settle-compliance must be >= 0 and finite (got " + std::to_string(cd.settle_compliance) + ")");
  if (!(cd.lost_factor >= 0.0 && std::isfinite(cd.lost_factor)))
    throw Error("--cd-lost-factor must be >= 0 and finite (got " + std::to_string(cd.lost_factor) + ")");
  if (!(cd.restart_floor >= 0.0 && std::isfinite(cd.restart_floor)))
    throw Error("--cd-restart-floor must be >= 0 and finite (got " + std::to_string(cd.restart_floor) + ")");
  if (!(cd.interior_states_pieces >= 0.0 && std::isfinite(cd.interior_states_pieces)))
    throw Error("--cd-interior-states-pieces must be >= 0 and finite (got " +
                std::to_string(cd.interior_states_pieces) + ")");
  if (cd.interior_states_stall < 0)
    throw Error("--cd-interior-states-stall must be >= 0 (got " + std::to_string(cd.interior_states_stall) + ")");
  if (cd.interior_states_retries < 0)
    throw Error("--cd-interior-states-retries must be >= 0 (got " + std::to_string(cd.interior_states_retries) + ")");
  if (cd.interior_max_iterations < 1)
    throw Error("--cd-interior-iterations must be >= 1 (got " + std::to_string(cd.interior_max_iterations) + ")");
  if (!(cd.interior_neighbourhood >= 0.0 && cd.interior_neighbourhood < 1.0))
    throw Error("--cd-interior-neighbourhood must be in [0, 1) (got " + std::to_string(cd.interior_neighbourhood) + ")");
  if (!(cd.interior_share > 0.0 && cd.interior_share < 1.0))
    throw Error("--cd-interior-share must be in (0, 1) (got " + std::to_string(cd.interior_share) + ")");
  if (!(cd.inertial_factor > 1.0 && std::isfinite(cd.inertial_factor)))
    throw Error("--cd-inertial-factor must be > 1 and finite (got " + std::to_string(cd.inertial_factor) + ")");
  for (const InertialCount& c : kInertialCounts)
    if (cd.*c.field < c.least)
      throw Error(std::string(c.option) + " must be >= " + std::to_string(c.least) + " (got " +
                  std::to_string(cd.*c.field) + ")");
}

void validate(const CampaignSettings& s) {
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(s.nlgs.g) || !positive(s.kinematic.g) || !positive(s.nlgs.dt) ||
      !positive(s.nlgs.velocity_tol))
    throw Error("the probe's g, dt and velocity_tol must be positive");
  if (!(s.max_inertia >= 0.0 && std::isfinite(s.max_inertia)))
    throw Error("the largest inertia of a probe that enters the averages must be >= 0 and finite (in F0)");
  check_lp_tolerance(s.kinematic.lp_tolerance, "--lp-tol: ");
  if (s.kinematic.lp_tolerance != KinematicProbeSettings{}.lp_tolerance && s.method != ProbeMethod::kLp)
    throw Error(std::string("--lp-tol applies to the lp method, not to ") + method_name(s.method));
  if (s.max_inertia > 0.0 && s.method == ProbeMethod::kLp)
    throw Error("a largest inertia applies to the methods with a time step (nlgs, lemke, cd), not to lp");
  validate(s.cd);
  if (s.cd.softer_starts != CdPathSettings{}.softer_starts && !has_continuation(s))
    throw Error("--cd-softer-starts applies to the cd method's compliant and interior starts only");
  if (s.cd.compliant_start != CdPathSettings{}.compliant_start && !has_continuation(s))
    throw Error("--cd-compliant-start applies to the cd method's compliant and interior starts only");
  if (s.cd.interior_share != CdPathSettings{}.interior_share &&
      !(s.method == ProbeMethod::kCd && s.cd.start == CdPathStart::interior_inertial))
    throw Error("--cd-interior-share applies to the cd method's interior-inertial start only");
  if (const char* option = changed_inertial_option(s.cd); option && !has_inertial(s))
    throw Error(std::string(option) + " applies to the cd method's inertial and interior-inertial starts only");
  if (s.cd.restart_floor > 0.0 && !has_continuation(s))
    throw Error("--cd-restart-floor applies to the cd method's compliant and interior starts only");
  if (s.cd.max_probe_pieces > 0 && s.method != ProbeMethod::kCd)
    throw Error(std::string("--cd-max-pieces applies to the cd method, not to ") + method_name(s.method));
  if (s.cd.accept_residual != CdPathSettings{}.accept_residual && s.method != ProbeMethod::kCd)
    throw Error(std::string("--cd-accept-residual applies to the cd method, not to ") + method_name(s.method));
  if (s.cd.settle_compliance > 0.0 && s.method != ProbeMethod::kCd)
    throw Error(std::string("--cd-settle-compliance applies to the cd method, not to ") + method_name(s.method));
  if (s.cd.lost_factor > 0.0 && s.method != ProbeMethod::kCd)
    throw Error(std::string("--cd-lost-factor applies to the cd method, not to ") + method_name(s.method));
  if (!(s.nlgs.window >= 0.0 && std::isfinite(s.nlgs.window)))
    throw Error("--window must be >= 0 and finite (mean diameters; got " + std::to_string(s.nlgs.window) + ")");
  if (s.nlgs.window > 0.0 && s.method != ProbeMethod::kCd && s.method != ProbeMethod::kLemke)
    throw Error(std::string("--window applies to the exact methods (cd, lemke), not to ") + method_name(s.method));
  if (s.nlgs.window > 0.0 && s.method == ProbeMethod::kCd && s.cd.start == CdPathStart::lp_optimum)
    throw Error("--window does not go with --cd-start lp (the lp optimum is the whole packing's)");
  if (s.cd.start != CdPathStart::static_network && s.method != ProbeMethod::kCd)
    throw Error(std::string("the cd start '") + cd_start_name(s.cd.start) + "' applies to the cd method only (the method is " +
                method_name(s.method) + ")");
}

bool enters_averages(const ProbeRow& r, double max_inertia, double f0) {
  return r.residual != kNoSolution && !(max_inertia > 0.0 && r.f_inertia > max_inertia * f0);
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

std::vector<int> shard_targets(const std::vector<int>& targets, int shard, int shards) {
  std::vector<int> mine;
  for (std::size_t place = 0; place < targets.size(); ++place)
    if (in_shard(static_cast<int>(place), shard, shards)) mine.push_back(targets[place]);
  return mine;
}

ProbeResult probe_contact(const Packing& p, const CampaignSettings& s, int contact) {
  Worker w;
  return w.probe(p, s, contact);
}

std::vector<ProbeResult> probe_contacts(const Packing& p, const CampaignSettings& s,
                                        const std::vector<int>& contacts, const ProbeListHooks& hooks) {
  const int M = static_cast<int>(p.contacts.size());
  if (hooks.running && !(hooks.running_every_s >= 0.0))
    throw Error("probe_contacts: running_every_s must be >= 0 (got " + std::to_string(hooks.running_every_s) + ")");
  for (const int k : contacts)
    if (k < 0 || k >= M)
      throw Error("contact " + std::to_string(k) + ": the packing has " + std::to_string(M) + " contacts");
  std::vector<int> tasks(contacts.size());  // positions in `contacts`
  std::iota(tasks.begin(), tasks.end(), 0);
  std::vector<std::optional<ProbeResult>> results(contacts.size());
  WorkLoop loop;
  loop.should_stop = either(hooks.should_stop, s.nlgs.cancel);
  loop.work = [&](WorkSource& source) {
    probe_tasks(source, p, s, &contacts, hooks.running, hooks.running_every_s);
  };
  int finished = 0;
  loop.gather = [&](std::vector<TaskResult>& done) {
    for (TaskResult& tr : done) {
      results[tr.task] = decode(tr.bytes);
      ++finished;
      if (hooks.progress) hooks.progress({tr.task, &*results[tr.task], finished, static_cast<int>(contacts.size())});
    }
  };
  LocalDistributor local;
  local.run(tasks, loop);
  // Tasks are handed out in order; a stop leaves the ones not handed out, a cancel those it
  // abandoned: the results up to the first missing one are a prefix of `contacts`.
  std::vector<ProbeResult> out;
  for (std::optional<ProbeResult>& r : results) {
    if (!r) break;
    out.push_back(std::move(*r));
  }
  return out;
}

bool run_campaign(const Packing& p, const CampaignSettings& s, CampaignState& state,
                  const CampaignHooks& hooks) {
  LocalDistributor local;
  return run_campaign(p, s, state, hooks, local);
}

bool run_campaign(const Packing& p, const CampaignSettings& settings, CampaignState& state,
                  const CampaignHooks& hooks, WorkDistributor& distributor) {
  if (hooks.running && !(hooks.running_every_s >= 0.0))
    throw Error("campaign: running_every_s must be >= 0 (got " + std::to_string(hooks.running_every_s) + ")");
  CampaignSettings s = settings;
  s.nlgs.cancel = either(settings.nlgs.cancel, hooks.cancel);
  const std::vector<int> all = campaign_targets(p, s);
  std::vector<int> todo;
  if (distributor.gathers()) {
    std::vector<char> listed(p.contacts.size(), 0);
    for (const ProbeRow& r : state.rows) {
      if (r.contact < 0 || r.contact >= static_cast<int>(p.contacts.size()))
        throw Error("the saved probes list contact " + std::to_string(r.contact) + ", but the packing has " +
                    std::to_string(p.contacts.size()) + " contacts");
      listed[r.contact] = 1;
    }
    for (const int k : all)
      if (!state.average.has_probe(k) && !listed[k]) todo.push_back(k);
  }
  const std::vector<char> loaded = p.loaded_grains(s.force_threshold * p.force_unit());
  WorkLoop loop;
  loop.should_stop = either(hooks.should_stop, s.nlgs.cancel);
  // a target's place among all (sorted): what decides its shard
  loop.place = [&all](int k) { return static_cast<int>(std::lower_bound(all.begin(), all.end(), k) - all.begin()); };
  loop.work = [&](WorkSource& source) { probe_tasks(source, p, s, nullptr, hooks.running, hooks.running_every_s); };
  loop.gather = [&](std::vector<TaskResult>& results) {
    for (const TaskResult& tr : results) {
      const ProbeResult r = decode(tr.bytes);
      const ProbeRow row = row_of(r);
      if (enters_averages(row, s.max_inertia, p.force_unit())) add_to_average(p, s, loaded, r, state.average);
      state.rows.insert(std::upper_bound(state.rows.begin(), state.rows.end(), row,
                                         [](const ProbeRow& x, const ProbeRow& y) { return x.contact < y.contact; }),
                        row);
    }
    if (hooks.progress) hooks.progress(static_cast<int>(state.rows.size()), static_cast<int>(all.size()));
    if (hooks.checkpoint) hooks.checkpoint(state);
  };
  return distributor.run(todo, loop);
}

OverBudget probes_over_budget(const CampaignState& state, long long max_pieces) {
  OverBudget n;
  if (max_pieces <= 0) return n;
  for (const ProbeRow& r : state.rows) {
    const bool stopped = r.sweeps > max_pieces;
    n.probes += stopped;
    n.exact += stopped && r.converged;
  }
  return n;
}

int probes_accepted(const CampaignState& state, double accept_residual) {
  if (!(accept_residual > kExactStepTolerance)) return 0;
  int n = 0;
  for (const ProbeRow& r : state.rows) n += !r.converged && r.residual <= accept_residual;
  return n;
}

ProbeCpu probe_cpu(const std::vector<ProbeRow>& rows) {
  ProbeCpu c;
  std::vector<double> all, exact, near, none;
  for (const ProbeRow& r : rows) {
    if (!(r.cpu_seconds >= 0.0)) continue;  // NaN: not measured
    all.push_back(r.cpu_seconds);
    c.total += r.cpu_seconds;
    if (c.max_contact < 0 || r.cpu_seconds > c.max) {
      c.max = r.cpu_seconds;
      c.max_contact = r.contact;
    }
    (r.converged ? exact : r.residual == kNoSolution ? none : near).push_back(r.cpu_seconds);
  }
  c.timed = static_cast<int>(all.size());
  c.exact = static_cast<int>(exact.size());
  c.near_exact = static_cast<int>(near.size());
  c.no_solution = static_cast<int>(none.size());
  if (!all.empty()) {
    c.median = quantile(all, 0.5);
    c.p90 = quantile(std::move(all), 0.9);
  }
  if (!exact.empty()) c.exact_median = quantile(std::move(exact), 0.5);
  if (!near.empty()) c.near_exact_median = quantile(std::move(near), 0.5);
  if (!none.empty()) c.no_solution_median = quantile(std::move(none), 0.5);
  return c;
}

nlohmann::json to_json(const ProbeCpu& c) {
  // a statistic of no probes: null
  const auto median = [](int n, double m) { return n > 0 ? nlohmann::json(m) : nlohmann::json(nullptr); };
  return {{"probes", c.timed},
          {"total_seconds", c.total},
          {"median_seconds", median(c.timed, c.median)},
          {"p90_seconds", median(c.timed, c.p90)},
          {"max_seconds", median(c.timed, c.max)},
          {"max_contact", c.max_contact},
          {"exact", {{"probes", c.exact}, {"median_seconds", median(c.exact, c.exact_median)}}},
          {"near_exact", {{"probes", c.near_exact}, {"median_seconds", median(c.near_exact, c.near_exact_median)}}},
          {"without_solution",
           {{"probes", c.no_solution}, {"median_seconds", median(c.no_solution, c.no_solution_median)}}}};
}

nlohmann::json probe_cpu_json(const CampaignState& state) {
  nlohmann::json a = nlohmann::json::array();
  for (const ProbeRow& r : state.rows)
    if (r.cpu_seconds >= 0.0) a.push_back({r.contact, r.cpu_seconds});
  return a;
}

void set_probe_cpu(CampaignState& state, const nlohmann::json& record) {
  for (ProbeRow& r : state.rows) r.cpu_seconds = std::numeric_limits<double>::quiet_NaN();
  if (!record.is_array()) return;
  for (const auto& e : record) {
    if (!e.is_array() || e.size() != 2 || !e[0].is_number_integer() || !e[1].is_number()) continue;
    const double seconds = e[1].get<double>();
    if (!(seconds >= 0.0) || !std::isfinite(seconds)) continue;
    const long long k = e[0].get<long long>();
    const auto row = std::lower_bound(state.rows.begin(), state.rows.end(), k,
                                      [](const ProbeRow& x, long long c) { return x.contact < c; });
    if (row != state.rows.end() && row->contact == k) row->cpu_seconds = seconds;
  }
}

CampaignSummary summarize(const Packing& p, const CampaignState& state, std::optional<FitWindow> window,
                          double max_inertia, int bootstrap_samples, std::uint64_t seed) {
  CampaignSummary sum;
  sum.probes = static_cast<int>(state.rows.size());
  double f_cont = 0.0, f_crit = 0.0;
  int solved = 0;
  for (const ProbeRow& r : state.rows) {
    const bool enters = enters_averages(r, max_inertia, p.force_unit());
    if (!r.converged) ++sum.not_converged;
    if (r.residual == kNoSolution) ++sum.without_solution;
    else if (!enters) ++sum.inertial;
    if (!enters) continue;
    ++solved;
    f_cont += r.f_cont;
    f_crit += r.f_crit;
  }
  if (solved > 0) {
    sum.F_cont_over_F0 = f_cont / solved / p.force_unit();
    sum.F_crit_over_F_cont = f_crit / f_cont;
  }
  if (solved > 1 && f_cont > 0.0) {
    double e2 = 0.0;  // over the rows in contact order: the same bits for any thread count
    for (const ProbeRow& r : state.rows) {
      if (!enters_averages(r, max_inertia, p.force_unit())) continue;
      const double e = r.f_crit - sum.F_crit_over_F_cont * r.f_cont;
      e2 += e * e;
    }
    sum.F_crit_over_F_cont_err = std::sqrt(e2 / (double(solved) * (solved - 1))) / (f_cont / solved);
  }
  std::vector<double> inertia;
  for (const ProbeRow& r : state.rows) {
    if (std::isnan(r.f_inertia)) continue;
    const double f = r.f_inertia / p.force_unit();
    if (inertia.empty() || f > sum.f_inertia_max_over_F0) {
      sum.f_inertia_max_over_F0 = f;
      sum.f_inertia_max_contact = r.contact;
    }
    inertia.push_back(f);
  }
  sum.inertia_probes = static_cast<int>(inertia.size());
  if (!inertia.empty()) sum.f_inertia_median_over_F0 = quantile(std::move(inertia), 0.5);
  std::vector<double> opened, sliding;
  for (const ProbeRow& r : state.rows) {
    if (r.opened < 0 || r.sliding < 0) continue;
    opened.push_back(r.opened);
    sliding.push_back(r.sliding);
  }
  sum.state_probes = static_cast<int>(opened.size());
  if (!opened.empty()) {
    sum.opened_median = quantile(std::move(opened), 0.5);
    sum.sliding_median = quantile(std::move(sliding), 0.5);
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

// The interior-point method's cap on its iterations before it was a setting
// (CdPathSettings::interior_max_iterations): the one cap the settings leave unrecorded.
constexpr int kUnrecordedInteriorIterations = 40;
// The compliant continuation's first compliance before it was a setting
// (CdPathSettings::compliant_start): the one value the settings leave unrecorded.
constexpr double kUnrecordedCompliantStart = 0.1;

nlohmann::json to_json(const CampaignSettings& s) {
  const bool lp = s.method == ProbeMethod::kLp;
  const std::optional<ContactModel>& model = lp ? s.kinematic.model : s.nlgs.model;
  if (!model) throw Error("campaign settings without a contact model (campaign_settings_for sets it)");
  nlohmann::json j = {
      {"method", method_name(s.method)},
      {"g", lp ? s.kinematic.g : s.nlgs.g},
      {"touch_gap", model->touch_gap},
      {"displacement", s.total_displacement ? "total" : "peculiar"},
      {"force_threshold_F0", s.force_threshold},
      {"sample", s.sample},
      {"seed", s.seed},
  };
  if (lp) {
    j["state_tol_F0"] = s.kinematic.state_tol;
    j["M_lambda"] = model->M_lambda;
    // recorded where it is not the default, so that earlier checkpoints still resume
    if (s.kinematic.lp_tolerance != KinematicProbeSettings{}.lp_tolerance) j["lp_tolerance"] = s.kinematic.lp_tolerance;
  } else {
    j["dt"] = s.nlgs.dt;
    j["M_lambda"] = model->M_lambda;
    // recorded where it is not the default, so that earlier checkpoints still resume
    if (s.method == ProbeMethod::kCd && s.cd.start != CdPathStart::static_network)
      j["cd_start"] = cd_start_name(s.cd.start);
    // Recorded where they apply and are on (0 is the continuation's single start; the
    // interior-point start falls back to the continuation).
    if (has_continuation(s) && s.cd.softer_starts > 0) j["cd_softer_starts"] = s.cd.softer_starts;
    // The continuation's first compliance: recorded where it is not the value of the
    // checkpoints made before it was a setting, so that those still resume.
    if (has_continuation(s) && s.cd.compliant_start != kUnrecordedCompliantStart)
      j["cd_compliant_start"] = s.cd.compliant_start;
    if (has_continuation(s) && s.cd.restart_floor > 0.0)
      j["cd_restart_floor"] = s.cd.restart_floor;  // recorded where set, as cd_start
    if (has_interior(s)) {
      // The first path from the iterate's own states (docs/probe.md, "The iterate's own
      // states"), its cut where it stops gaining ground and its retries at softer compliances:
      // each recorded where on, so that a checkpoint made without it is not resumed with it, nor
      // the other way round.
      if (s.cd.interior_states_pieces > 0.0) {
        j["cd_interior_states_pieces"] = s.cd.interior_states_pieces;
        if (s.cd.interior_states_stall > 0) j["cd_interior_states_stall"] = s.cd.interior_states_stall;
        if (s.cd.interior_states_retries > 0) j["cd_interior_states_retries"] = s.cd.interior_states_retries;
      }
      // The interior-point method's cap on its iterations: recorded where it is not the cap of
      // the checkpoints made before it was a setting, so that those still resume.
      if (s.cd.interior_max_iterations != kUnrecordedInteriorIterations)
        j["cd_interior_iterations"] = s.cd.interior_max_iterations;
      // Its second run in the wide neighbourhood: recorded where on, so that a checkpoint made
      // with it resumes only with it, and one made without (or before it) only without.
      if (s.cd.interior_neighbourhood > 0.0) j["cd_interior_neighbourhood"] = s.cd.interior_neighbourhood;
    }
    if (s.method == ProbeMethod::kCd && s.cd.start == CdPathStart::interior_inertial)
      j["cd_interior_share"] = s.cd.interior_share;  // recorded with the start it applies to
    if (has_inertial(s)) {
      // The continuation in dt: each recorded where it is not the default (the value of the
      // checkpoints made before it was a setting, so that those still resume).
      const CdPathSettings d;
      if (s.cd.inertial_factor != d.inertial_factor) j["cd_inertial_factor"] = s.cd.inertial_factor;
      for (const InertialCount& c : kInertialCounts)
        if (s.cd.*c.field != d.*c.field) j[c.key] = s.cd.*c.field;
    }
    if (s.method == ProbeMethod::kCd && s.cd.max_probe_pieces > 0)
      j["cd_max_pieces"] = s.cd.max_probe_pieces;  // recorded where set, as cd_start
    if (s.method == ProbeMethod::kCd && s.cd.accept_residual != CdPathSettings{}.accept_residual)
      j["cd_accept_residual"] = s.cd.accept_residual;  // recorded where set, as cd_start
    if (s.method == ProbeMethod::kCd && s.cd.settle_compliance > 0.0)
      j["cd_settle_compliance"] = s.cd.settle_compliance;  // recorded where set, as cd_start
    if (s.method == ProbeMethod::kCd && s.cd.lost_factor > 0.0)
      j["cd_lost_factor"] = s.cd.lost_factor;  // recorded where set, as cd_start
    if (s.max_inertia > 0.0) j["max_inertia_F0"] = s.max_inertia;  // recorded where set, as cd_start
    if (s.nlgs.window > 0.0) j["window_d"] = s.nlgs.window;            // recorded where set, as cd_start
    if (s.method == ProbeMethod::kNlgs) {
      j["velocity_tol"] = s.nlgs.velocity_tol;
      j["max_sweeps"] = s.nlgs.max_sweeps;
    }
  }
  return j;
}

CampaignSettings campaign_settings_from_json(const nlohmann::json& j, const Packing& p, const std::string& name) {
  if (!j.is_object()) throw Error(name + " are not a JSON object");
  static const std::set<std::string> kKnown = {
      "method", "g", "touch_gap", "displacement", "force_threshold_F0", "sample", "seed", "state_tol_F0",
      "lp_tolerance", "M_lambda", "dt", "cd_start", "cd_softer_starts", "cd_compliant_start", "cd_interior_states_pieces",
      "cd_interior_states_stall", "cd_interior_states_retries", "cd_interior_iterations",
      "cd_interior_neighbourhood", "cd_max_pieces", "cd_accept_residual", "cd_settle_compliance",
      "cd_lost_factor", "cd_restart_floor", "cd_interior_share", "cd_inertial_factor", "cd_inertial_stages", "cd_inertial_halvings",
      "cd_inertial_retries", "cd_inertial_jumps", "max_inertia_F0", "window_d", "velocity_tol", "max_sweeps"};
  for (const auto& [key, value] : j.items())
    if (kKnown.count(key) == 0) throw Error(name + " have a setting this unjam does not know: '" + key + "'");
  CampaignSettings s = campaign_settings_for(p);
  try {
    s.method = method_from_name(j.at("method").get<std::string>());
    s.nlgs.g = s.kinematic.g = j.at("g").get<double>();
    const std::string displacement = j.at("displacement").get<std::string>();
    if (displacement != "total" && displacement != "peculiar")
      throw Error("displacement must be total or peculiar (got '" + displacement + "')");
    s.total_displacement = displacement == "total";
    s.force_threshold = j.at("force_threshold_F0").get<double>();
    s.sample = json_integer<int>(j.at("sample"), "sample");
    s.seed = json_integer<std::uint64_t>(j.at("seed"), "seed");
    if (s.method == ProbeMethod::kLp) {
      s.kinematic.state_tol = j.at("state_tol_F0").get<double>();
      s.kinematic.lp_tolerance = j.value("lp_tolerance", KinematicProbeSettings{}.lp_tolerance);
      s.nlgs.dt = default_probe_dt(s.method, s.nlgs.g);
    } else {
      s.nlgs.dt = j.at("dt").get<double>();
      // Each absent cd setting at the value to_json leaves out.
      const auto number = [&j](const char* key, double absent) {
        return j.contains(key) ? j.at(key).get<double>() : absent;
      };
      const auto integer = [&j](const char* key, long long absent) {
        return j.contains(key) ? json_integer<long long>(j.at(key), key) : absent;
      };
      if (s.method == ProbeMethod::kCd) {
        s.cd.start = cd_start_from_name(j.value("cd_start", std::string(cd_start_name(CdPathStart::static_network))));
        s.cd.max_probe_pieces = integer("cd_max_pieces", 0);
        s.cd.accept_residual = number("cd_accept_residual", CdPathSettings{}.accept_residual);
        s.cd.settle_compliance = number("cd_settle_compliance", 0.0);
        s.cd.lost_factor = number("cd_lost_factor", 0.0);
        if (s.cd.start == CdPathStart::interior_inertial) s.cd.interior_share = j.at("cd_interior_share").get<double>();
      }
      if (has_inertial(s)) {
        const CdPathSettings d;
        s.cd.inertial_factor = number("cd_inertial_factor", d.inertial_factor);
        for (const InertialCount& c : kInertialCounts) s.cd.*c.field = static_cast<int>(integer(c.key, d.*c.field));
      }
      if (has_continuation(s)) {
        s.cd.softer_starts = static_cast<int>(integer("cd_softer_starts", 0));
        s.cd.compliant_start = number("cd_compliant_start", kUnrecordedCompliantStart);
        s.cd.restart_floor = number("cd_restart_floor", 0.0);
      }
      if (has_interior(s)) {
        s.cd.interior_states_pieces = number("cd_interior_states_pieces", 0.0);
        s.cd.interior_states_stall = static_cast<int>(integer("cd_interior_states_stall", 0));
        s.cd.interior_states_retries = static_cast<int>(integer("cd_interior_states_retries", 0));
        s.cd.interior_max_iterations = static_cast<int>(integer("cd_interior_iterations", kUnrecordedInteriorIterations));
        s.cd.interior_neighbourhood = number("cd_interior_neighbourhood", 0.0);
      }
      s.max_inertia = number("max_inertia_F0", 0.0);
      s.nlgs.window = number("window_d", 0.0);
      if (s.method == ProbeMethod::kNlgs) {
        s.nlgs.velocity_tol = j.at("velocity_tol").get<double>();
        s.nlgs.max_sweeps = json_integer<long long>(j.at("max_sweeps"), "max_sweeps");
      }
    }
    validate(s);
  } catch (const nlohmann::json::exception& e) {
    throw Error(name + ": " + e.what());
  } catch (const Error& e) {
    throw Error(name + ": " + e.what());
  }
  // What the record holds and the settings do not give back: a key of another method or start,
  // a default written out, another packing's contact model.
  if (const nlohmann::json again = to_json(s); again != j)
    throw Error(name + " are not what unjam probe records on this packing (" +
                settings_differences(j, again, "recorded", "read back") + ")");
  return s;
}

nlohmann::json to_json(const CampaignState& state) {
  nlohmann::json rows = nlohmann::json::array();
  for (const ProbeRow& r : state.rows)
    rows.push_back({r.contact, r.a, r.b, r.f_cont, r.f_crit, r.converged, r.sweeps, r.residual,
                    r.violations, r.lambda_dt, nullable(r.f_inertia), r.opened, r.sliding});
  return {{"rows", rows}, {"average", state.average.to_json()}};
}

namespace {

// campaign_state_from_json without the message's prefix.
CampaignState parse_campaign_state(const nlohmann::json& j, const Packing& p) {
  const ResponseGrid grid = ResponseGrid::for_cell(p.cell, 2.0 * p.mean_radius());
  if (!j.is_object()) throw Error("the state is not a JSON object");
  ResponseAverage average = ResponseAverage::from_json(j.at("average"));
  if (!(average.grid() == grid)) throw Error("its averages are not on this packing's grid");
  CampaignState state(grid);
  state.average = std::move(average);
  const auto contacts = static_cast<int>(p.contacts.size());
  for (const auto& r : j.at("rows")) {
    // 10 or 11 values: a checkpoint written before f_inertia, or opened and sliding, were
    // recorded (its rows keep NaN and -1)
    if (!r.is_array() || (r.size() != 10 && r.size() != 11 && r.size() != 13))
      throw Error("a row is not an array of 13 values (or of 10 or 11, from an older unjam)");
    const ProbeRow row{json_integer<int>(r[0], "row contact"),   json_integer<int>(r[1], "row grain a"),
                       json_integer<int>(r[2], "row grain b"),     r[3].get<double>(),
                       r[4].get<double>(),                        r[5].get<bool>(),
                       json_integer<long long>(r[6], "row sweeps"), r[7].get<double>(),
                       json_integer<int>(r[8], "row violations"), r[9].get<double>(),
                       r.size() >= 11 ? nullable_from(r[10], "row f_inertia")
                                      : std::numeric_limits<double>::quiet_NaN(),
                       r.size() == 13 ? json_integer<int>(r[11], "row opened") : -1,
                       r.size() == 13 ? json_integer<int>(r[12], "row sliding") : -1};
    if (row.opened < -1 || row.sliding < -1) throw Error("a row's opened or sliding is below -1");
    if (row.contact < 0 || row.contact >= contacts)
      throw Error("contact " + std::to_string(row.contact) + " out of range (the packing has " +
                  std::to_string(contacts) + " contacts)");
    if (!state.rows.empty() && !(state.rows.back().contact < row.contact))
      throw Error("the rows are not in increasing contact order (contact " + std::to_string(row.contact) + ")");
    const Contact& c = p.contacts[row.contact];
    if (row.a != c.a || row.b != c.b)
      throw Error("contact " + std::to_string(row.contact) + " is between grains " + std::to_string(c.a) + " and " +
                  std::to_string(c.b) + ", not " + std::to_string(row.a) + " and " + std::to_string(row.b));
    state.rows.push_back(row);
  }
  std::vector<char> listed(p.contacts.size(), 0);
  for (const ProbeRow& row : state.rows) listed[row.contact] = 1;
  for (const auto& [id, profile] : state.average.probe_profiles())
    if (id < 0 || id >= contacts || !listed[id])
      throw Error("the averages hold probe " + std::to_string(id) + ", which has no row");
  return state;
}

}  // namespace

CampaignState campaign_state_from_json(const nlohmann::json& j, const Packing& p) {
  try {
    return parse_campaign_state(j, p);
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("probe checkpoint is corrupt: ") + e.what());
  } catch (const Error& e) {
    throw Error(std::string("probe checkpoint is corrupt: ") + e.what());
  }
}

std::string campaign_checkpoint_text(const std::string& fingerprint, const nlohmann::json& settings,
                                     const CampaignState& state, const CampaignTime* runs) {
  const nlohmann::json state_json = to_json(state);
  nlohmann::json j = {{"packing", fingerprint},
                      {"settings", settings},
                      {"state_fnv1a64", fnv1a64_hex(state_json.dump())},
                      {"state", state_json}};
  if (runs) {
    j["runs"] = to_json(*runs);
    j["probe_cpu"] = probe_cpu_json(state);
  }
  return j.dump();
}

std::optional<CampaignState> read_campaign_checkpoint(const std::string& text, const std::string& name,
                                                      const Packing& p, const nlohmann::json& settings,
                                                      CampaignTime* runs) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw Error(name + " is not valid JSON; remove it to start over");
  const auto packing = j.find("packing");
  if (packing == j.end() || *packing != packing_fingerprint(p)) return std::nullopt;
  require_same_settings(j.value("settings", nlohmann::json{}), settings, name);
  const auto state = j.find("state");
  const auto sum = j.find("state_fnv1a64");
  if (state == j.end() || sum == j.end() || *sum != fnv1a64_hex(state->dump()))
    throw Error(name + " is damaged (its state does not match its checksum); remove it to start over");
  try {
    CampaignState read = campaign_state_from_json(*state, p);
    set_probe_cpu(read, j.value("probe_cpu", nlohmann::json()));
    if (runs) *runs = campaign_time_from_json(j.value("runs", nlohmann::json()), static_cast<long long>(read.rows.size()));
    return read;
  } catch (const Error& e) {
    throw Error(name + ": " + e.what() + "; remove it to start over");
  }
}

}  // namespace unjam
