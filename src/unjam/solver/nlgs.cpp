#include "unjam/solver/nlgs.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "unjam/solver/coloring.hpp"

namespace unjam {
namespace {

// Contacts per block: the unit of parallel work and of the deterministic reductions.
constexpr int kBlock = 128;

// Hot per-grain state: velocity, angular velocity and inverse mass.
struct Body {
  double vx, vy, w, inv_m;
};

// Hot per-contact state, stored in colour order.
struct Row {
  int a, b;
  double nx, ny, len;      // normal and branch length |l|
  double Ra, Rb;           // radii
  double RaIa, RbIb;       // R / I of each grain (spin change per unit tangential impulse)
  double inv_mn, inv_mt;   // 1/m_n = 1/m_a + 1/m_b;  1/m_t = 1/m_n + R_a^2/I_a + R_b^2/I_b
  double g_eff;            // gap the step must respect
  double Rn, Rt;           // current force
};

// What one block of contacts reports after its updates.
struct Tally {
  double dS = 0.0;         // change of sum_k R_n,k |l_k|
  double dK = 0.0;         // change of sum_i m_i |v_i|^2
  double max_dU = 0.0;
  double sum_absR = 0.0;   // sum_k |R_k| after the update
  double sum_Rn = 0.0;
  int rel_ok = 0;          // contacts passing the relative force criterion
  int abs_fail = 0;        // contacts failing both force criteria
};

struct Sweeper {
  const StepProblem& pb;
  const NlgsSettings& set;
  std::vector<Body> body;
  std::vector<Row> row;
  std::vector<double> mass, inertia, radius;
  Coloring coloring;
  double S = 0.0;       // sum_k R_n,k |l_k|
  double K = 0.0;       // sum_i m_i |v_i|^2
  double lambda = 0.0;  // current iterate of the cell strain rate
  double V = 1.0;
  double R_avg = 0.0;   // mean |R| of the previous sweep (absolute criterion of kForceChange)

  double pressure() const { return (S + K) / (2.0 * V); }

  void update_lambda() {
    lambda = pb.bath.enabled
                 ? pb.lambda_t + pb.dt * (pressure() - pb.bath.P_ext) / pb.bath.M_lambda
                 : pb.lambda_t;
  }

  // Applies the force change (dRn, dRt) of contact r to its two bodies: the impulse on b is
  // dt (dRn n + dRt t), t = (-n_y, n_x), on a its negative; torques T_a = -R_a R_t,
  // T_b = -R_b R_t.
  void apply_impulse(const Row& r, double dRn, double dRt) {
    const double dt = pb.dt;
    Body& A = body[r.a];
    Body& B = body[r.b];
    const double px = dt * (dRn * r.nx - dRt * r.ny);
    const double py = dt * (dRn * r.ny + dRt * r.nx);
    A.vx -= px * A.inv_m;
    A.vy -= py * A.inv_m;
    B.vx += px * B.inv_m;
    B.vy += py * B.inv_m;
    A.w -= dt * dRt * r.RaIa;
    B.w -= dt * dRt * r.RbIb;
  }

  // Solves contact r given all others; applies its force change to the two bodies.
  void update(Row& r, Tally& t) {
    const double dt = pb.dt;
    Body& A = body[r.a];
    Body& B = body[r.b];
    const double dvx = B.vx - A.vx, dvy = B.vy - A.vy;
    // Relative velocity of the contact points, b relative to a, with the affine part.
    const double Un = dvx * r.nx + dvy * r.ny + lambda * r.len;
    const double Ut = -dvx * r.ny + dvy * r.nx - (A.w * r.Ra + B.w * r.Rb);
    // U*: the same without this contact's own force.
    const double Us_n = Un - dt * r.Rn * r.inv_mn;
    const double Us_t = Ut - dt * r.Rt * r.inv_mt;
    double Rn = 0.0, Rt = 0.0;
    if (r.g_eff + dt * Us_n <= 0.0) {
      Rn = -(r.g_eff / dt + Us_n) / (dt * r.inv_mn);  // closes exactly: dt U_n = -g_eff
      Rt = -Us_t / (dt * r.inv_mt);                   // sticking: U_t = 0
      const double limit = pb.mu * Rn;
      Rt = std::clamp(Rt, -limit, limit);              // sliding
    }
    if (set.relax != 1.0) {  // projected over-relaxation
      Rn = std::max(0.0, r.Rn + set.relax * (Rn - r.Rn));
      Rt = std::clamp(r.Rt + set.relax * (Rt - r.Rt), -pb.mu * Rn, pb.mu * Rn);
    }
    const double dRn = Rn - r.Rn, dRt = Rt - r.Rt;
    const double KA = A.vx * A.vx + A.vy * A.vy, KB = B.vx * B.vx + B.vy * B.vy;
    apply_impulse(r, dRn, dRt);
    t.dK += (A.vx * A.vx + A.vy * A.vy - KA) / A.inv_m + (B.vx * B.vx + B.vy * B.vy - KB) / B.inv_m;
    t.dS += dRn * r.len;
    t.max_dU = std::max(t.max_dU, dt * std::max(std::abs(dRn) * r.inv_mn, std::abs(dRt) * r.inv_mt));
    // Force-change criteria of kForceChange (nlgs.hpp).
    const double d2 = dRn * dRn + dRt * dRt;
    const double s2 = (Rn + r.Rn) * (Rn + r.Rn) + (Rt + r.Rt) * (Rt + r.Rt);
    if (d2 <= set.tol * s2) ++t.rel_ok;
    else if (d2 >= set.tol * R_avg * R_avg) ++t.abs_fail;
    t.sum_absR += std::sqrt(Rn * Rn + Rt * Rt);
    t.sum_Rn += Rn;
    r.Rn = Rn;
    r.Rt = Rt;
  }

  // Largest net force m |v| / dt and torque I |w| / (dt R) of any grain: in a static solve
  // (v_free = 0) these are the force and torque residuals of the network.
  double max_residual() const {
    double worst = 0.0;
    for (std::size_t i = 0; i < body.size(); ++i) {
      const double f = std::hypot(body[i].vx, body[i].vy) * mass[i];
      const double T = std::abs(body[i].w) * inertia[i] / radius[i];
      worst = std::max({worst, f, T});
    }
    return worst / pb.dt;
  }
};


// Measured cost of a contact update in each mode (ns), shared by all solves of the process;
// exponential moving averages, 0 while unknown.
std::atomic<double> g_ns_serial{0.0}, g_ns_parallel{0.0};
std::atomic<int> g_choices{0};

void record_speed(bool parallel, double ns) {
  auto& avg = parallel ? g_ns_parallel : g_ns_serial;
  const double old = avg.load();
  avg.store(old == 0.0 ? ns : 0.7 * old + 0.3 * ns);
}

// Parallel when it has been measured faster; each mode is measured first, and the slower
// one is tried again every 32nd choice, since the load of the machine changes.
bool choose_parallel() {
  const double par = g_ns_parallel.load(), ser = g_ns_serial.load();
  if (par == 0.0) return true;
  if (ser == 0.0) return false;
  const bool faster = par < ser;
  return (++g_choices % 32 == 0) ? !faster : faster;
}

// Within a solve: parallel sweeps clearly slower than serial ones measured before.
bool parallel_is_slow() {
  const double ser = g_ns_serial.load();
  return ser > 0.0 && g_ns_parallel.load() > 1.5 * ser;
}

}  // namespace

NlgsResult solve_nlgs(const StepProblem& pb, const NlgsSettings& set, Contacts& contacts,
                      Particles& particles) {
  const int n = static_cast<int>(particles.size());
  const int nc = static_cast<int>(contacts.size());
  Sweeper s{pb, set, {}, {}, {}, {}, {}, {}};
  s.V = pb.cell.area();
  s.body.resize(n);
  s.mass.resize(n);
  s.inertia.resize(n);
  s.radius = particles.radius;
  for (int i = 0; i < n; ++i) {
    s.mass[i] = particles.mass(i);
    s.inertia[i] = particles.inertia(i);
    s.body[i] = {particles.vx[i], particles.vy[i], particles.omega[i], 1.0 / s.mass[i]};
  }

  s.coloring = color_contacts(contacts, n, set.seed);
  s.row.resize(nc);
  for (int q = 0; q < nc; ++q) {
    const int k = s.coloring.order[q];
    const Contact& c = contacts[k];
    const double Ra = particles.radius[c.a], Rb = particles.radius[c.b];
    const double inv_mn = 1.0 / s.mass[c.a] + 1.0 / s.mass[c.b];
    Row& r = s.row[q];
    r = {c.a, c.b, c.n.x(), c.n.y(), c.l.norm(), Ra, Rb, Ra / s.inertia[c.a], Rb / s.inertia[c.b],
         inv_mn, inv_mn + Ra * Ra / s.inertia[c.a] + Rb * Rb / s.inertia[c.b], pb.g_eff[k],
         c.fn, c.ft};
  }

  // Warm start: apply the initial forces to the free velocities.
  for (const Row& r : s.row) {
    s.apply_impulse(r, r.Rn, r.Rt);
    s.S += r.Rn * r.len;
    s.R_avg += std::hypot(r.Rn, r.Rt);
  }
  if (nc > 0) s.R_avg /= nc;
  for (int i = 0; i < n; ++i) s.K += s.mass[i] * (s.body[i].vx * s.body[i].vx + s.body[i].vy * s.body[i].vy);
  s.update_lambda();

  // Blocks of each colour; a block never spans two colours.
  const int num_colors = s.coloring.num_colors();
  std::vector<int> block_start, color_first_block(num_colors + 1, 0);
  for (int c = 0; c < num_colors; ++c) {
    color_first_block[c] = static_cast<int>(block_start.size());
    for (int q = s.coloring.color_start[c]; q < s.coloring.color_start[c + 1]; q += kBlock)
      block_start.push_back(q);
  }
  color_first_block[num_colors] = static_cast<int>(block_start.size());
  const int num_blocks = static_cast<int>(block_start.size());
  std::vector<Tally> tally(num_blocks);
  const auto block_end = [&](int blk, int color) {
    return std::min(block_start[blk] + kBlock, s.coloring.color_start[color + 1]);
  };

  std::vector<int> color_order(num_colors);
  std::iota(color_order.begin(), color_order.end(), 0);
  std::mt19937_64 rng(set.seed ^ 0x9e3779b97f4a7c15ULL);

  NlgsResult res;
  res.num_colors = num_colors;
  double prev_sum_Rn = std::accumulate(s.row.begin(), s.row.end(), 0.0,
                                       [](double acc, const Row& r) { return acc + r.Rn; });
  bool done = nc == 0;
  int sweep = 0;
  // Serial and parallel sweeps give bit-identical results, so the mode is free: the faster
  // one measured so far, with a fall-back to serial inside a solve when parallel sweeps turn
  // slow (two barriers per colour stall when another process holds a core).
  const bool eligible = omp_get_max_threads() > 1 && !omp_in_parallel() &&
                        num_blocks > 2 * num_colors && set.threading != Threading::kSerial;
  const bool adaptive = set.threading == Threading::kAuto;
  bool parallel = eligible && (!adaptive || choose_parallel());
  const double updates_per_sweep = static_cast<double>(nc);
  constexpr int kChunk = 16;  // sweeps between two looks at the clock
  while (!done) {
    const int chunk_end = sweep + kChunk, chunk_start = sweep;
    const auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel if (parallel) default(shared)
    {
      while (!done && sweep < chunk_end) {
#pragma omp single
        std::shuffle(color_order.begin(), color_order.end(), rng);
        for (int ci = 0; ci < num_colors; ++ci) {
          const int color = color_order[ci];
#pragma omp for schedule(static)
          for (int blk = color_first_block[color]; blk < color_first_block[color + 1]; ++blk) {
            Tally t;
            for (int q = block_start[blk], e = block_end(blk, color); q < e; ++q)
              s.update(s.row[q], t);
            tally[blk] = t;
          }
#pragma omp single
          {
            for (int blk = color_first_block[color]; blk < color_first_block[color + 1]; ++blk) {
              s.S += tally[blk].dS;
              s.K += tally[blk].dK;
            }
            s.update_lambda();
          }
        }
#pragma omp single
        {
          ++sweep;
          Tally all;
          for (const Tally& t : tally) {
            all.max_dU = std::max(all.max_dU, t.max_dU);
            all.sum_absR += t.sum_absR;
            all.sum_Rn += t.sum_Rn;
            all.rel_ok += t.rel_ok;
            all.abs_fail += t.abs_fail;
          }
          s.R_avg = all.sum_absR / nc;
          res.max_dU = all.max_dU;
          bool ok = false;
          switch (set.rule) {
            case Convergence::kForceChange: {
              const double dm = all.sum_Rn - prev_sum_Rn;
              ok = all.rel_ok >= 0.9 * nc && all.abs_fail == 0 &&
                   dm * dm <= set.tol * all.sum_Rn * all.sum_Rn;
              break;
            }
            case Convergence::kVelocityChange:
              ok = all.max_dU < set.velocity_tol;
              break;
            case Convergence::kStatic:
              if (sweep % set.check_every == 0 || sweep >= set.max_sweeps) {
                res.max_residual_F0 = s.max_residual() / set.F0;
                ok = res.max_residual_F0 < set.static_tol &&
                     std::abs(s.pressure() / pb.bath.P_ext - 1.0) < set.static_tol;
              }
              break;
          }
          prev_sum_Rn = all.sum_Rn;
          res.converged = ok && sweep >= set.min_sweeps;
          done = res.converged || sweep >= set.max_sweeps;
        }
      }
    }
    if (eligible) {
      const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
                        (updates_per_sweep * std::max(1, sweep - chunk_start));
      record_speed(parallel, ns);
      if (adaptive && parallel && parallel_is_slow()) parallel = false;
    }
  }

  res.sweeps = sweep;
  res.lambda = s.lambda;
  res.P_in = s.pressure();
  if (set.rule == Convergence::kStatic && nc > 0) res.max_residual_F0 = s.max_residual() / set.F0;
  for (int q = 0; q < nc; ++q) {
    Contact& c = contacts[s.coloring.order[q]];
    c.fn = s.row[q].Rn;
    c.ft = s.row[q].Rt;
  }
  for (int i = 0; i < n; ++i) {
    particles.vx[i] = s.body[i].vx;
    particles.vy[i] = s.body[i].vy;
    particles.omega[i] = s.body[i].w;
  }
  return res;
}

}  // namespace unjam
