#include "unjam/solver/nlgs.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "unjam/core/error.hpp"
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

// The contacts of each colour cut into blocks of kBlock rows; a block never spans two
// colours. Blocks are the unit of parallel work and fix the order of every reduction
// (docs/method.md, "Nonlinear Gauss–Seidel by colours").
struct BlockLayout {
  std::vector<int> block_start, block_end;  // rows [block_start[b], block_end[b]) of block b
  std::vector<int> color_first_block;       // colour c owns blocks [first[c], first[c + 1])
  int num_blocks() const { return static_cast<int>(block_start.size()); }
};

// The state of the sweep loop that all threads of a parallel region share.
struct SweepLoop {
  std::vector<Tally> tally;       // one per block, of the block's last update
  std::vector<int> color_order;   // reshuffled every sweep
  std::mt19937_64 rng;
  double prev_sum_Rn = 0.0;       // sum_k R_n,k after the previous sweep (force units)
  int sweep = 0;
  bool done = false;
};

// Stage 1, prepare contacts (docs/method.md, "One time step"). Bodies get the free velocities
// v(t), w(t) and 1/m with m = pi R^2, I = m R^2 / 2 (docs/method.md, "Model and units"). The
// contacts are edge-coloured with the settings' seed and stored as rows in colour order:
// n, |l|, R_a / I_a, R_b / I_b, 1/m_n = 1/m_a + 1/m_b, 1/m_t = 1/m_n + R_a^2/I_a + R_b^2/I_b,
// the step's gap g_eff and the warm-start forces (R_n, R_t) = (fn, ft).
void prepare_rows(Sweeper& s, const Contacts& contacts, const Particles& particles) {
  const int n = static_cast<int>(particles.size());
  const int nc = static_cast<int>(contacts.size());
  s.V = s.pb.cell.area();
  s.body.resize(n);
  s.mass.resize(n);
  s.inertia.resize(n);
  s.radius = particles.radius;
  for (int i = 0; i < n; ++i) {
    s.mass[i] = particles.mass(i);
    s.inertia[i] = particles.inertia(i);
    s.body[i] = {particles.vx[i], particles.vy[i], particles.omega[i], 1.0 / s.mass[i]};
  }

  s.coloring = color_contacts(contacts, n, s.set.seed);
  s.row.resize(nc);
  for (int q = 0; q < nc; ++q) {
    const int k = s.coloring.order[q];
    const Contact& c = contacts[k];
    const double Ra = particles.radius[c.a], Rb = particles.radius[c.b];
    const double inv_mn = 1.0 / s.mass[c.a] + 1.0 / s.mass[c.b];
    Row& r = s.row[q];
    r = {c.a, c.b, c.n.x(), c.n.y(), c.l.norm(), Ra, Rb, Ra / s.inertia[c.a], Rb / s.inertia[c.b],
         inv_mn, inv_mn + Ra * Ra / s.inertia[c.a] + Rb * Rb / s.inertia[c.b], s.pb.g_eff[k],
         c.fn, c.ft};
  }
}

// Stage 2, warm start: applies every row's initial force to its two bodies (impulse
// dt (R_n n + R_t t)), and sets the sums the sweeps update incrementally: S = sum_k R_n,k |l_k|,
// K = sum_i m_i |v_i|^2, so P_in = (S + K) / (2 V); the mean |R| for the absolute force
// criterion; lambda* = lambda_t + dt (P_in - P_ext) / M_lambda (docs/method.md, "The cell
// strain rate").
void warm_start(Sweeper& s) {
  for (const Row& r : s.row) {
    s.apply_impulse(r, r.Rn, r.Rt);
    s.S += r.Rn * r.len;
    s.R_avg += std::hypot(r.Rn, r.Rt);
  }
  if (!s.row.empty()) s.R_avg /= static_cast<int>(s.row.size());
  for (std::size_t i = 0; i < s.body.size(); ++i)
    s.K += s.mass[i] * (s.body[i].vx * s.body[i].vx + s.body[i].vy * s.body[i].vy);
  s.update_lambda();
}

// Stage 3, block layout: the rows of colour c, [color_start[c], color_start[c + 1]), cut
// into blocks of kBlock.
BlockLayout layout_blocks(const Coloring& coloring) {
  const int num_colors = coloring.num_colors();
  BlockLayout L;
  L.color_first_block.assign(num_colors + 1, 0);
  for (int c = 0; c < num_colors; ++c) {
    L.color_first_block[c] = L.num_blocks();
    for (int q = coloring.color_start[c]; q < coloring.color_start[c + 1]; q += kBlock) {
      L.block_start.push_back(q);
      L.block_end.push_back(std::min(q + kBlock, coloring.color_start[c + 1]));
    }
  }
  L.color_first_block[num_colors] = L.num_blocks();
  return L;
}

// One colour of a sweep, run by every thread of the team: each block's rows are updated in
// order (a colour's contacts share no grain, so blocks run in parallel with the result of a
// sequential pass), then one thread adds the blocks' dS and dK in block order and updates
// lambda* (docs/method.md, "The cell strain rate").
void sweep_color(Sweeper& s, const BlockLayout& L, std::vector<Tally>& tally, int color) {
#pragma omp for schedule(static)
  for (int blk = L.color_first_block[color]; blk < L.color_first_block[color + 1]; ++blk) {
    Tally t;
    for (int q = L.block_start[blk], e = L.block_end[blk]; q < e; ++q) s.update(s.row[q], t);
    tally[blk] = t;
  }
#pragma omp single
  {
    for (int blk = L.color_first_block[color]; blk < L.color_first_block[color + 1]; ++blk) {
      s.S += tally[blk].dS;
      s.K += tally[blk].dK;
    }
    s.update_lambda();
  }
}

// Stage 4b, convergence after a sweep (docs/method.md, "Convergence rules"); sums the
// blocks' tallies in block order and updates the mean |R| for the next sweep.
//   kForceChange:    rel_ok >= 0.9 N_c, no contact failing both force criteria, and
//                    (sum R_n - previous sum R_n)^2 <= tol (sum R_n)^2;
//   kVelocityChange: max_k dt |dR_k| / m_eff < velocity_tol;
//   kStatic:         every check_every sweeps (and at max_sweeps), the largest grain
//                    residual m |v| / dt, I |w| / (dt R) below static_tol F0 and
//                    |P_in / P_ext - 1| < static_tol.
// True when the rule holds and at least min_sweeps sweeps were made.
bool check_convergence(Sweeper& s, const std::vector<Tally>& tally, int sweep, double& prev_sum_Rn,
                       NlgsResult& res) {
  const NlgsSettings& set = s.set;
  const int nc = static_cast<int>(s.row.size());
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
      ok = all.rel_ok >= 0.9 * nc && all.abs_fail == 0 && dm * dm <= set.tol * all.sum_Rn * all.sum_Rn;
      break;
    }
    case Convergence::kVelocityChange:
      ok = all.max_dU < set.velocity_tol;
      break;
    case Convergence::kStatic:
      if (sweep % set.check_every == 0 || sweep >= set.max_sweeps) {
        res.max_residual_F0 = s.max_residual() / set.F0;
        ok = res.max_residual_F0 < set.static_tol &&
             std::abs(s.pressure() / s.pb.bath.P_ext - 1.0) < set.static_tol;
      }
      break;
  }
  prev_sum_Rn = all.sum_Rn;
  return ok && sweep >= set.min_sweeps;
}

// Stage 4a, sweeps up to sweep chunk_end or convergence, in one parallel region (a team of
// one thread unless `parallel`): per sweep, the colour order is reshuffled, every colour is
// swept (sweep_color), then convergence is checked.
void sweep_chunk(Sweeper& s, const BlockLayout& L, SweepLoop& loop, NlgsResult& res, int chunk_end,
                 bool parallel) {
  const int num_colors = static_cast<int>(loop.color_order.size());
#pragma omp parallel if (parallel) default(shared)
  {
    while (!loop.done && loop.sweep < chunk_end) {
#pragma omp single
      std::shuffle(loop.color_order.begin(), loop.color_order.end(), loop.rng);
      for (int ci = 0; ci < num_colors; ++ci) sweep_color(s, L, loop.tally, loop.color_order[ci]);
#pragma omp single
      {
        ++loop.sweep;
        res.converged = check_convergence(s, loop.tally, loop.sweep, loop.prev_sum_Rn, res);
        loop.done = res.converged || loop.sweep >= s.set.max_sweeps;
      }
    }
  }
}

// Stage 4, iterate sweeps until convergence or max_sweeps, in chunks of kChunk sweeps
// timed in ns per contact update (docs/method.md, "Threading of the sweeps"). The mode is
// serial or parallel by the settings' policy; under kAuto, the faster one by `threading`,
// falling back to serial within the solve when parallel sweeps turn slow.
void iterate_sweeps(Sweeper& s, const BlockLayout& L, NlgsThreading& threading, NlgsResult& res) {
  const NlgsSettings& set = s.set;
  const int num_colors = s.coloring.num_colors();
  const int nc = static_cast<int>(s.row.size());
  SweepLoop loop;
  loop.tally.resize(L.num_blocks());
  loop.color_order.resize(num_colors);
  std::iota(loop.color_order.begin(), loop.color_order.end(), 0);
  loop.rng.seed(set.seed ^ 0x9e3779b97f4a7c15ULL);
  loop.prev_sum_Rn = std::accumulate(s.row.begin(), s.row.end(), 0.0,
                                     [](double acc, const Row& r) { return acc + r.Rn; });
  loop.done = nc == 0;

  const bool eligible = omp_get_max_threads() > 1 && !omp_in_parallel() &&
                        L.num_blocks() > 2 * num_colors && set.threading != Threading::kSerial;
  const bool adaptive = set.threading == Threading::kAuto;
  bool parallel = eligible && (!adaptive || threading.choose_parallel());
  constexpr int kChunk = 16;  // sweeps between two looks at the clock (and at the cancel)
  while (!loop.done) {
    if (s.set.cancel && s.set.cancel()) throw Cancelled();
    const int chunk_start = loop.sweep;
    const auto t0 = std::chrono::steady_clock::now();
    sweep_chunk(s, L, loop, res, chunk_start + kChunk, parallel);
    if (eligible) {
      const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
                        (static_cast<double>(nc) * std::max(1, loop.sweep - chunk_start));
      threading.record(parallel, ns);
      if (adaptive && parallel && threading.parallel_is_slow()) parallel = false;
    }
  }
  res.sweeps = loop.sweep;
}

// Stage 5, store the forces: R_n, R_t at t + dt back into the contacts (force units; the
// step's impulse is dt R), the velocities v(t + dt), w(t + dt) into the grains, and
// lambda(t + dt), P_in = (S + K) / (2 V) and, for kStatic, the final residual / F0.
void store_forces(const Sweeper& s, Contacts& contacts, Particles& particles, NlgsResult& res) {
  res.lambda = s.lambda;
  res.P_in = s.pressure();
  if (s.set.rule == Convergence::kStatic && !s.row.empty()) res.max_residual_F0 = s.max_residual() / s.set.F0;
  for (std::size_t q = 0; q < s.row.size(); ++q) {
    Contact& c = contacts[s.coloring.order[q]];
    c.fn = s.row[q].Rn;
    c.ft = s.row[q].Rt;
  }
  for (std::size_t i = 0; i < s.body.size(); ++i) {
    particles.vx[i] = s.body[i].vx;
    particles.vy[i] = s.body[i].vy;
    particles.omega[i] = s.body[i].w;
  }
}

}  // namespace

bool NlgsThreading::choose_parallel() {
  if (ns_parallel_ == 0.0) return true;
  if (ns_serial_ == 0.0) return false;
  const bool faster = ns_parallel_ < ns_serial_;
  return (++choices_ % 32 == 0) ? !faster : faster;
}

void NlgsThreading::record(bool parallel, double ns_per_update) {
  double& avg = parallel ? ns_parallel_ : ns_serial_;
  avg = avg == 0.0 ? ns_per_update : 0.7 * avg + 0.3 * ns_per_update;
}

bool NlgsThreading::parallel_is_slow() const {
  return ns_serial_ > 0.0 && ns_parallel_ > 1.5 * ns_serial_;
}

// The stages of the step's contact problem (docs/method.md, "One time step"): prepare the
// contact rows, warm start, lay out the blocks, iterate sweeps with a convergence check after
// each, store the forces and velocities.
NlgsResult solve_nlgs(const StepProblem& pb, const NlgsSettings& set, Contacts& contacts,
                      Particles& particles, NlgsThreading& threading) {
  Sweeper s{pb, set, {}, {}, {}, {}, {}, {}};
  prepare_rows(s, contacts, particles);
  warm_start(s);
  const BlockLayout blocks = layout_blocks(s.coloring);
  NlgsResult res;
  res.num_colors = s.coloring.num_colors();
  iterate_sweeps(s, blocks, threading, res);
  store_forces(s, contacts, particles, res);
  return res;
}

}  // namespace unjam
