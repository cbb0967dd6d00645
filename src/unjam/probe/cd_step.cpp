#include "unjam/probe/cd_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <sstream>
#include <string>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/lemke.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {

CdStepProblem build_cd_step(const Packing& packing, int contact, const ProbeSettings& settings) {
  const int nc = static_cast<int>(packing.contacts.size());
  if (contact < 0 || contact >= nc)
    throw Error("contact " + std::to_string(contact) + " does not exist (the packing has " +
                std::to_string(nc) + ")");
  CdStepProblem pb;
  static_cast<ContactProblem&>(pb) =
      build_contact_problem(packing, contact_model_of(packing, settings.model), settings.dt);
  pb.probed = contact;
  pb.g = settings.g;
  pb.g_eff[contact] = -settings.g;
  return settings.window != 0.0 ? window_step(pb, packing, settings.window) : pb;  // window_step refuses < 0, NaN
}

CdStepProblem window_step(const CdStepProblem& step, const Packing& packing, double radius) {
  if (!(radius > 0.0 && std::isfinite(radius)))
    throw Error("a window's radius must be positive and finite (mean diameters; got " + std::to_string(radius) + ")");
  const EquilibriumSystem& sys = step.system;
  const Contact& probed = packing.contacts[sys.contacts[step.probed]];
  // The probed pair's midpoint: grain a's centre plus half the branch vector l (a to b).
  const Vec2 centre = packing.particles.position(probed.a) + 0.5 * probed.l;
  const double reach = radius * 2.0 * packing.mean_radius();
  std::vector<char> inside(packing.size(), 0);
  for (std::size_t i = 0; i < packing.size(); ++i)
    inside[i] = step.cell.min_image(packing.particles.position(i) - centre).norm() <= reach;
  inside[probed.a] = inside[probed.b] = 1;  // the probed pair itself, whatever the radius

  // Rows: the window's grains keep their three rows, in the order of sys.grains; the
  // pressure row stays last, over the kept contacts.
  const int rows_full = static_cast<int>(sys.A.rows()), p_full = rows_full - 1;
  std::vector<int> row_of(rows_full, -1);
  CdStepProblem w;
  for (std::size_t g = 0; g < sys.grains.size(); ++g)
    if (inside[sys.grains[g]]) {
      const int r = 3 * static_cast<int>(w.system.grains.size());
      for (int c = 0; c < 3; ++c) row_of[3 * g + c] = r + c;
      w.system.grains.push_back(sys.grains[g]);
    }
  const int rows = 3 * static_cast<int>(w.system.grains.size()) + 1;
  row_of[p_full] = rows - 1;
  std::vector<int> kept;  // positions in sys.contacts
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const Contact& c = packing.contacts[sys.contacts[k]];
    if (inside[c.a] || inside[c.b]) {
      kept.push_back(k);
      w.system.contacts.push_back(sys.contacts[k]);
    }
  }
  std::vector<Eigen::Triplet<double>> t;
  for (std::size_t j = 0; j < kept.size(); ++j)
    for (int c = 0; c < 2; ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(sys.A, 2 * kept[j] + c); it; ++it)
        if (const int r = row_of[it.row()]; r >= 0) t.emplace_back(r, static_cast<int>(2 * j + c), it.value());
  w.system.A.resize(rows, static_cast<Eigen::Index>(2 * kept.size()));
  w.system.A.setFromTriplets(t.begin(), t.end());
  w.system.mu = sys.mu;
  w.system.F0 = sys.F0;
  // The bath on the window: the pressure row's load is the window's share of 2 V P_ext, the
  // static network's virial over the kept contacts (a_p f0, the pressure row of A_w f0) times
  // 2 V P_ext / its virial over all. So the static network still solves the unshifted window,
  // and a window that covers the cell is the whole step (the share is then x / x = 1 exactly).
  // Without the row, the static network's prestress would be a self-stress of the clamped
  // window (A_w (c f0) = 0 on its grains' rows for every c), and the rigid step would leave
  // its level open.
  const double virial_all = (sys.A * packing_forces(packing, sys))[p_full];
  const double virial_kept = (w.system.A * packing_forces(packing, w.system))[rows - 1];
  if (!(virial_all > 0.0))
    throw Error("a window needs a static network that carries the pressure (its virial is " +
                std::to_string(virial_all) + ")");
  w.system.rhs = Eigen::VectorXd::Zero(rows);
  w.system.rhs[rows - 1] = sys.rhs[p_full] * (virial_kept / virial_all);

  w.cell = step.cell;
  w.model = step.model;
  w.dt = step.dt;
  w.g = step.g;
  w.inverse_mass.resize(rows);
  for (int r = 0; r < rows_full; ++r)
    if (row_of[r] >= 0) w.inverse_mass[row_of[r]] = step.inverse_mass[r];
  w.g_eff.resize(static_cast<Eigen::Index>(kept.size()));
  for (std::size_t j = 0; j < kept.size(); ++j) {
    const int k = kept[j];
    w.g_eff[static_cast<Eigen::Index>(j)] = step.g_eff[k];
    w.state.push_back(step.state[k]);
    if (k == step.probed) w.probed = static_cast<int>(j);
  }
  return w;
}

void write_siconos_problem(const CdStepProblem& pb, const std::filesystem::path& file) {
  const int nc = pb.num_contacts();
  const Eigen::MatrixXd W = pb.delassus();
  const Eigen::VectorXd q = pb.local_free();
  std::string s;
  char buf[64];
  const auto num = [&](double v) {
    std::snprintf(buf, sizeof buf, "%.17g ", v);
    s += buf;
  };
  s += "2\n" + std::to_string(nc) + "\n";
  // NumericsMatrix, dense storage (0): rows, columns, then "rows columns" and the rows.
  const std::string n2 = std::to_string(2 * nc);
  s += "0\n" + n2 + "\n" + n2 + "\n" + n2 + "\t" + n2 + "\n";
  for (int i = 0; i < 2 * nc; ++i) {
    for (int j = 0; j < 2 * nc; ++j) num(W(i, j));
    s += "\n";
  }
  for (int i = 0; i < 2 * nc; ++i) num(q[i]);
  s += "\n";
  for (int k = 0; k < nc; ++k) num(pb.system.mu);
  s += "\n";
  write_file_atomic(file, s);
}

namespace {

// The step as an LCP in the Stewart-Trinkle form, per contact k (blocks of nc):
//   z = (fn_k, beta+_k, beta-_k, sigma_k),  ft_k = beta+_k - beta-_k,
//   w = (U_n,k,  sigma_k + U_t,k,  sigma_k - U_t,k,  mu fn_k - beta+_k - beta-_k)
// with U = W f + q_loc: complementarity makes ft = -mu fn sign(U_t) when sigma = |U_t| > 0
// and U_t = 0 when the force is inside the cone. For mu = 0 only the fn block remains.
void stewart_trinkle(const CdStepProblem& pb, Eigen::MatrixXd& M, Eigen::VectorXd& q) {
  const int nc = pb.num_contacts();
  const Eigen::MatrixXd W = pb.delassus();
  const Eigen::VectorXd ql = pb.local_free();
  const bool friction = pb.system.mu > 0.0;
  const int n = friction ? 4 * nc : nc;
  M.setZero(n, n);
  q.setZero(n);
  for (int i = 0; i < nc; ++i) {
    q[i] = ql[2 * i];
    for (int j = 0; j < nc; ++j) M(i, j) = W(2 * i, 2 * j);
  }
  if (!friction) return;
  const double mu = pb.system.mu;
  for (int i = 0; i < nc; ++i) {
    q[nc + i] = ql[2 * i + 1];
    q[2 * nc + i] = -ql[2 * i + 1];
    for (int j = 0; j < nc; ++j) {
      const double Wnt = W(2 * i, 2 * j + 1), Wtn = W(2 * i + 1, 2 * j), Wtt = W(2 * i + 1, 2 * j + 1);
      M(i, nc + j) = Wnt;
      M(i, 2 * nc + j) = -Wnt;
      M(nc + i, j) = Wtn;
      M(nc + i, nc + j) = Wtt;
      M(nc + i, 2 * nc + j) = -Wtt;
      M(2 * nc + i, j) = -Wtn;
      M(2 * nc + i, nc + j) = -Wtt;
      M(2 * nc + i, 2 * nc + j) = Wtt;
    }
    M(nc + i, 3 * nc + i) = M(2 * nc + i, 3 * nc + i) = 1.0;
    M(3 * nc + i, i) = mu;
    M(3 * nc + i, nc + i) = M(3 * nc + i, 2 * nc + i) = -1.0;
  }
}

}  // namespace

CdStepSolution probe_cd_lemke(const Packing& packing, int contact, const ProbeSettings& settings) {
  const CdStepProblem pb = build_cd_step(packing, contact, settings);
  const int nc = pb.num_contacts();
  if (nc > kMaxLemkeContacts)
    throw Error("the dense Lemke probe handles at most " + std::to_string(kMaxLemkeContacts) +
                " contacts (this step has " + std::to_string(nc) + "); use --method cd, lp or nlgs, or a smaller --window");
  Eigen::MatrixXd M;
  Eigen::VectorXd q;
  stewart_trinkle(pb, M, q);
  // Lemke's path from the covering vector e; should it end on a ray, it is run again with
  // seeded covering vectors in [1, 2]^n (a different path; the solution it reaches is exact).
  LemkeResult lcp = solve_lcp_lemke(M, q);
  std::mt19937_64 rng(settings.seed + static_cast<std::uint64_t>(contact));
  std::uniform_real_distribution<double> unit(1.0, 2.0);
  for (int retry = 0; retry < kLemkeRetries && lcp.z.size() == 0; ++retry) {
    if (settings.cancel && settings.cancel()) throw Cancelled();
    Eigen::VectorXd d(q.size());
    for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = unit(rng);
    const int pivots = lcp.pivots;
    lcp = solve_lcp_lemke(M, q, d);
    lcp.pivots += pivots;
  }

  CdStepSolution sol;
  if (lcp.z.size() > 0) {
    sol.f.setZero(2 * nc);
    const bool friction = pb.system.mu > 0.0;
    for (int k = 0; k < nc; ++k) {
      sol.f[2 * k] = lcp.z[k];
      if (friction) sol.f[2 * k + 1] = lcp.z[nc + k] - lcp.z[2 * nc + k];
    }
    sol.residual = cd_step_residual(pb, sol.f);
  }
  sol.result = cd_step_result(pb, packing, settings, sol.f);
  sol.result.sweeps = lcp.pivots;
  return sol;
}

ProbeResult cd_step_result(const CdStepProblem& pb, const Packing& packing,
                           const ProbeSettings& settings, const Eigen::VectorXd& f) {
  ProbeResult r;
  const int contact = pb.system.contacts[pb.probed];
  r.contact = contact;
  r.a = packing.contacts[contact].a;
  r.b = packing.contacts[contact].b;
  r.f_cont = packing.contacts[contact].fn;
  r.g = settings.g;
  r.u.assign(packing.size(), Vec2(0.0, 0.0));
  r.u_rot.assign(packing.size(), 0.0);
  if (f.size() == 0) {
    r.converged = false;
    r.residual = kNoSolution;
    return r;
  }
  r.residual = cd_step_residual(pb, f).max();
  r.converged = r.residual <= kExactStepTolerance;
  r.f_crit = f[2 * pb.probed];
  const Eigen::VectorXd qd = pb.generalized_displacement(f);
  for (std::size_t i = 0; i < pb.system.grains.size(); ++i) {
    const int grain = pb.system.grains[i];
    r.u[grain] = Vec2(qd[3 * i], qd[3 * i + 1]);
    r.u_rot[grain] = qd[3 * i + 2] / packing.particles.radius[grain];
  }
  r.lambda_dt = qd[pb.system.pressure_row()];
  r.f_inertia = step_inertia_force(packing, r, pb.dt);
  const StepStateChanges changes = step_state_changes(pb, packing, step_states(pb, f));
  r.opened = changes.opened;
  r.sliding = changes.sliding;
  return r;
}

const char* step_state_name(StepState state) {
  switch (state) {
    case StepState::open: return "open";
    case StepState::stick: return "stick";
    case StepState::slide: return "slide";
  }
  return "?";
}

namespace {

// step_states of forces f whose displacements u = pb.relative_displacement(f) are at hand.
std::vector<StepState> states_of(const CdStepProblem& pb, const Eigen::VectorXd& f, const Eigen::VectorXd& u) {
  const double tol = kExactStepTolerance, F0 = pb.system.F0;
  std::vector<StepState> states(pb.num_contacts());
  for (int k = 0; k < pb.num_contacts(); ++k) {
    if (f[2 * k] <= tol * F0) states[k] = StepState::open;
    else if (std::abs(u[2 * k + 1]) > tol * pb.g) states[k] = StepState::slide;
    else states[k] = StepState::stick;
  }
  return states;
}

}  // namespace

std::vector<StepState> step_states(const CdStepProblem& pb, const Eigen::VectorXd& f) {
  return states_of(pb, f, pb.relative_displacement(f));
}

StepStateChanges step_state_changes(const CdStepProblem& pb, const Packing& packing,
                                    const std::vector<StepState>& states) {
  const double tol = kExactStepTolerance, F0 = pb.system.F0;
  StepStateChanges c;
  for (int k = 0; k < pb.num_contacts(); ++k) {
    if (k == pb.probed) continue;
    if (packing.contacts[pb.system.contacts[k]].fn > tol * F0) {
      ++c.loaded;
      if (states[k] == StepState::open) ++c.opened;
      if (states[k] == StepState::slide) ++c.sliding;
    } else {
      ++c.unloaded;
      if (states[k] != StepState::open) ++c.closed;
    }
  }
  return c;
}

std::string step_forces_csv(const CdStepProblem& pb, const Packing& packing, const Eigen::VectorXd& f) {
  const Eigen::VectorXd u = pb.relative_displacement(f);
  const std::vector<StepState> states = states_of(pb, f, u);
  CsvWriter w({"contact", "a", "b", "fn0", "fn", "ft", "un", "ut", "state"});
  for (int k = 0; k < pb.num_contacts(); ++k) {
    const Contact& c = packing.contacts[pb.system.contacts[k]];
    w.cell(pb.system.contacts[k]).cell(c.a).cell(c.b).cell(c.fn).cell(f[2 * k]).cell(f[2 * k + 1]);
    w.cell(u[2 * k] / pb.g).cell(u[2 * k + 1] / pb.g).cell(std::string_view(step_state_name(states[k])));
    w.end_row();
  }
  return w.str();
}

}  // namespace unjam
