#include "unjam/protocol/compaction.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "unjam/core/error.hpp"

namespace unjam {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

void validate(const CompactionSettings& s, double mu) {
  if (!(mu >= 0.0) || !std::isfinite(mu)) throw Error("friction coefficient mu must be a finite number >= 0");
  const auto& d = s.dynamics;
  if (!(d.bath.P_ext > 0.0) || !std::isfinite(d.bath.P_ext)) throw Error("P_ext must be a finite number > 0");
  if (!(d.bath.M_lambda > 0.0)) throw Error("the bath mass M_lambda must be > 0");
  if (!(d.dt > 0.0)) throw Error("the time step dt must be > 0");
  if (!(d.nlgs.tol > 0.0)) throw Error("the NLGS tolerance must be > 0");
  if (d.nlgs.max_sweeps < 1) throw Error("the NLGS max sweeps must be >= 1");
  if (!(d.min_detection > 0.0)) throw Error("the detection distance must be > 0");
  if (!(s.final_solve.tol > 0.0)) throw Error("the static residual tolerance must be > 0");
  if (!(s.v_static > 0.0)) throw Error("the static velocity threshold must be > 0");
}

std::size_t estimated_memory_bytes(std::size_t N) { return 16'000'000 + 8'000 * N; }

double mean_speed_of_loaded_grains(const Packing& p) {
  const std::vector<char> loaded = p.loaded_grains(0.0);
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (loaded[i]) {
      sum += std::hypot(p.particles.vx[i], p.particles.vy[i]);
      ++count;
    }
  return count > 0 ? sum / count : 0.0;
}

CompactionResult compact(Packing& p, const CompactionSettings& s, const CompactionHooks& hooks) {
  validate(s, p.meta.contact.mu);
  CompactionResult res;
  const auto start = Clock::now();
  auto last_progress = start, last_checkpoint = start;
  std::int64_t sweeps_since_report = 0, steps_since_report = 0;
  const double L_over_d = std::sqrt(p.cell.area()) / (2.0 * p.mean_radius());
  const int attempt_sweeps =
      static_cast<int>(std::min(1e9, std::max(2000.0, s.attempt_budget * L_over_d * L_over_d)));
  std::int64_t sweeps_since_attempt = attempt_sweeps;
  double v_last_attempt = INFINITY;
  // ETA from the decay of log(v_mean) between progress reports.
  double last_log_v = NAN, last_report_s = 0.0;

  const double min_side = p.min_cell_side();
  p.state.is_static = false;
  // Measurements of Threading::kAuto, shared by the compaction's steps and static attempts.
  NlgsThreading threading;
  while (res.steps < s.max_steps) {
    if (hooks.should_stop && hooks.should_stop()) {
      res.stopped = true;
      break;
    }
    const StepReport rep = advance(p, s.dynamics, threading);
    if (std::min(p.cell.Lx, p.cell.Ly) < min_side) {
      char buf[240];
      std::snprintf(buf, sizeof buf,
                    "the cell shrank to %.4g x %.4g, below 2 (R_1 + R_2) = %.4g, where a pair touches "
                    "through two periodic images: %zu disks are too few to jam in a periodic cell "
                    "(step %lld); use more", p.cell.Lx, p.cell.Ly, min_side, p.size(),
                    static_cast<long long>(p.state.step));
      throw Error(buf);
    }
    ++res.steps;
    res.sweeps += rep.sweeps;
    res.contact_updates += static_cast<std::int64_t>(rep.sweeps) * rep.num_contacts;
    sweeps_since_report += rep.sweeps;
    sweeps_since_attempt += rep.sweeps;
    ++steps_since_report;

    const double v_mean = mean_speed_of_loaded_grains(p);
    const double P_ratio = rep.P_in / s.dynamics.bath.P_ext;
    const bool loaded = std::any_of(p.contacts.begin(), p.contacts.end(),
                                    [](const Contact& c) { return c.fn > 0.0; });
    if (loaded && v_mean < s.v_static && std::abs(P_ratio - 1.0) < s.p_static &&
        (sweeps_since_attempt >= attempt_sweeps || v_mean < v_last_attempt / 3.0)) {
      Packing trial = p;
      StaticSolveSettings fs = s.final_solve;
      fs.dt = s.dynamics.dt;  // the solve steps with the compaction's dt (static_solve.hpp)
      fs.max_sweeps = std::min(fs.max_sweeps, attempt_sweeps);
      sweeps_since_attempt = 0;
      v_last_attempt = v_mean;
      fs.seed = s.dynamics.nlgs.seed + static_cast<std::uint64_t>(res.static_attempts);
      res.final_solve = solve_static(trial, s.dynamics.bath, fs, threading);
      ++res.static_attempts;
      if (hooks.attempt) hooks.attempt(p.state.step, v_mean, res.final_solve);
      if (res.final_solve.converged) {
        p = std::move(trial);
        p.state.is_static = true;
        res.is_static = true;
        break;
      }
    }

    const double now_s = seconds_since(start);
    if (hooks.progress && seconds_since(last_progress) >= hooks.progress_s) {
      CompactionProgress pr;
      pr.step = p.state.step;
      pr.time = p.state.time;
      pr.phi = p.packing_fraction();
      pr.P_ratio = P_ratio;
      pr.v_mean = v_mean;
      pr.sweeps_per_step = static_cast<double>(sweeps_since_report) / std::max<std::int64_t>(1, steps_since_report);
      pr.contacts = rep.num_contacts;
      pr.elapsed_s = now_s;
      pr.static_attempts = res.static_attempts;
      const double log_v = std::log(std::max(v_mean, 1e-300));
      if (std::isfinite(last_log_v) && log_v < last_log_v && v_mean > 0.0) {
        const double rate = (last_log_v - log_v) / (now_s - last_report_s);  // e-folds per second
        pr.eta_s = std::max(0.0, (log_v - std::log(s.v_static)) / rate);
      }
      last_log_v = log_v;
      last_report_s = now_s;
      hooks.progress(pr);
      last_progress = Clock::now();
      sweeps_since_report = steps_since_report = 0;
    }
    if (hooks.checkpoint && seconds_since(last_checkpoint) >= hooks.checkpoint_s) {
      hooks.checkpoint(p);
      last_checkpoint = Clock::now();
    }
  }
  res.wall_s = seconds_since(start);
  return res;
}

}  // namespace unjam
