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
  return pb;
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
                " contacts (this packing has " + std::to_string(nc) + "); use --method lp or nlgs");
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
  return r;
}

std::string step_forces_csv(const CdStepProblem& pb, const Packing& packing, const Eigen::VectorXd& f) {
  CsvWriter w({"contact", "a", "b", "fn", "ft"});
  for (int k = 0; k < pb.num_contacts(); ++k) {
    const Contact& c = packing.contacts[pb.system.contacts[k]];
    w.cell(pb.system.contacts[k]).cell(c.a).cell(c.b).cell(f[2 * k]).cell(f[2 * k + 1]);
    w.end_row();
  }
  return w.str();
}

}  // namespace unjam
