#include "unjam/solver/interior_point.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include <klu.h>

#include "unjam/core/error.hpp"

namespace unjam {

namespace {

// Largest step a in (0, 1] with x + a dx >= 0.
double step_to_boundary(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) {
  double a = 1.0;
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (dx[i] < 0.0) a = std::min(a, -x[i] / dx[i]);
  return a;
}

// SuiteSparse's KLU on the Newton matrix, whose pattern is fixed: analysed once, factorised
// at every iteration (its values change on the diagonal of the complementarity rows).
class NewtonLu {
 public:
  NewtonLu() { klu_defaults(&common_); }
  ~NewtonLu() {
    if (numeric_) klu_free_numeric(&numeric_, &common_);
    if (symbolic_) klu_free_symbolic(&symbolic_, &common_);
  }
  NewtonLu(const NewtonLu&) = delete;
  NewtonLu& operator=(const NewtonLu&) = delete;
  bool factorize(Eigen::SparseMatrix<double>& K) {
    const int n = static_cast<int>(K.rows());
    if (!symbolic_) symbolic_ = klu_analyze(n, K.outerIndexPtr(), K.innerIndexPtr(), &common_);
    if (!symbolic_) return false;
    // The previous pivot order while it stays stable (reciprocal pivot growth above 1e-8, as
    // the path's factorisations), else afresh with partial pivoting.
    if (numeric_ && klu_refactor(K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr(), symbolic_, numeric_, &common_) &&
        klu_rgrowth(K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr(), symbolic_, numeric_, &common_) &&
        common_.rgrowth > 1e-8)
      return true;
    if (numeric_) klu_free_numeric(&numeric_, &common_);
    numeric_ = klu_factor(K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr(), symbolic_, &common_);
    return numeric_ != nullptr && common_.status == KLU_OK;
  }
  Eigen::VectorXd solve(Eigen::VectorXd b) {
    klu_solve(symbolic_, numeric_, static_cast<int>(b.size()), 1, b.data(), &common_);
    return b;
  }

 private:
  klu_common common_;
  klu_symbolic* symbolic_ = nullptr;
  klu_numeric* numeric_ = nullptr;
};

}  // namespace

// Scaled unknowns (docs/probe.md, "An interior-point start"): v' = v / U (U = velocity_scale),
// forces and beta in F0, sigma in U; the balance rows divided by F0, the complements w in U
// (w_sigma in F0). Per contact k the complementarity variables are z[p k + t], t = 0 (fn),
// 1 (beta+), 2 (beta-), 3 (sigma); p = 4, or p = 1 (fn only) at mu = 0.
InteriorPointResult interior_point_step(const ContactProblem& pb, const InteriorPointSettings& s) {
  if (!(s.velocity_scale > 0.0) || !std::isfinite(s.velocity_scale))
    throw Error("interior point: velocity_scale must be positive (got " + std::to_string(s.velocity_scale) + ")");
  if (s.max_iterations < 1 || s.stall_iterations < 1)
    throw Error("interior point: max_iterations and stall_iterations must be >= 1");
  const Eigen::SparseMatrix<double>& A = pb.system.A;
  const int n = static_cast<int>(A.rows()), nc = pb.num_contacts();
  const double mu = pb.system.mu, F0 = pb.system.F0, U = s.velocity_scale, dt2 = pb.dt * pb.dt;
  const int p = mu > 0.0 ? 4 : 1, m = p * nc;
  Eigen::VectorXd mv(n);  // the balance rows' mass, scaled
  for (int i = 0; i < n; ++i) mv[i] = (U / F0) / pb.inverse_mass[i];
  Eigen::VectorXd c = Eigen::VectorXd::Zero(m);
  for (int k = 0; k < nc; ++k) c[p * k] = pb.g_eff[k] / (dt2 * U);
  const Eigen::VectorXd b = pb.system.rhs / F0;

  const auto forces = [&](const Eigen::VectorXd& z) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * nc);
    for (int k = 0; k < nc; ++k) {
      f[2 * k] = z[p * k];
      if (p == 4) f[2 * k + 1] = z[p * k + 1] - z[p * k + 2];
    }
    return f;
  };
  // G v + N z + c: the complements of z, affine in (v, z).
  const auto complements = [&](const Eigen::VectorXd& v, const Eigen::VectorXd& z) {
    const Eigen::VectorXd u = A.transpose() * v;
    Eigen::VectorXd w(m);
    for (int k = 0; k < nc; ++k) {
      const int j = p * k;
      w[j] = u[2 * k] + c[j];
      if (p == 1) continue;
      w[j + 1] = z[j + 3] + u[2 * k + 1];
      w[j + 2] = z[j + 3] - u[2 * k + 1];
      w[j + 3] = mu * z[j] - z[j + 1] - z[j + 2];
    }
    return w;
  };
  const auto balance_residual = [&](const Eigen::VectorXd& v, const Eigen::VectorXd& z) {
    return Eigen::VectorXd(mv.cwiseProduct(v) - A * forces(z) + b);
  };

  // The start: every z = 1, v balancing those forces, w = its complements raised to >= 1.
  Eigen::VectorXd z = Eigen::VectorXd::Ones(m);
  Eigen::VectorXd v = (A * forces(z) - b).cwiseQuotient(mv);
  Eigen::VectorXd w = complements(v, z).cwiseMax(1.0);

  // The Newton matrix [[diag mv, -A_f], [G, N + diag(w / z)]] with the grains' rows of v
  // eliminated (their masses are diagonal), as the path's reduced system (probe/cd_path):
  //     [P + N + diag(w / z), g_p; -a_p^T, mv_p] (dz, dv_p) = (rhs_z + G_G mv_G^-1 r_G, -r_p),
  // P = G_G mv_G^-1 A_f,G (sparse: contacts that share a grain), g_p and a_p the pressure
  // dof's column of G and row of A_f. Its pattern is fixed; only the diagonal changes.
  const int nG = n - 1;  // the pressure dof is A's last row
  std::vector<Eigen::Triplet<double>> tg, ta;  // G (m x n), A_f (n x m)
  for (int k = 0; k < nc; ++k) {
    const int j = p * k;
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, 2 * k); it; ++it) {
      tg.emplace_back(j, static_cast<int>(it.row()), it.value());
      ta.emplace_back(static_cast<int>(it.row()), j, it.value());
    }
    if (p == 1) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, 2 * k + 1); it; ++it) {
      const int i = static_cast<int>(it.row());
      tg.emplace_back(j + 1, i, it.value());
      tg.emplace_back(j + 2, i, -it.value());
      ta.emplace_back(i, j + 1, it.value());
      ta.emplace_back(i, j + 2, -it.value());
    }
  }
  Eigen::SparseMatrix<double> G(m, n), Af(n, m);
  G.setFromTriplets(tg.begin(), tg.end());
  Af.setFromTriplets(ta.begin(), ta.end());
  const Eigen::SparseMatrix<double> G_G = G.leftCols(nG);
  const Eigen::VectorXd mv_G = mv.head(nG);
  const Eigen::SparseMatrix<double> Af_G = Af.topRows(nG);
  const Eigen::SparseMatrix<double> P = G_G * mv_G.cwiseInverse().asDiagonal() * Af_G;
  std::vector<Eigen::Triplet<double>> tk;
  for (int col = 0; col < P.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(P, col); it; ++it)
      tk.emplace_back(static_cast<int>(it.row()), col, it.value());
  for (int k = 0; k < nc && p == 4; ++k) {
    const int j = p * k;
    tk.emplace_back(j + 1, j + 3, 1.0);
    tk.emplace_back(j + 2, j + 3, 1.0);
    tk.emplace_back(j + 3, j, mu);
    tk.emplace_back(j + 3, j + 1, -1.0);
    tk.emplace_back(j + 3, j + 2, -1.0);
  }
  for (int j = 0; j < m; ++j) tk.emplace_back(j, j, 0.0);  // diag(w / z), set per iteration
  for (Eigen::SparseMatrix<double>::InnerIterator it(G, nG); it; ++it)
    tk.emplace_back(static_cast<int>(it.row()), m, it.value());
  const Eigen::SparseMatrix<double> Af_row = Af.bottomRows(1);
  for (int col = 0; col < Af_row.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Af_row, col); it; ++it) tk.emplace_back(m, col, -it.value());
  tk.emplace_back(m, m, mv[nG]);
  Eigen::SparseMatrix<double> K0(m + 1, m + 1);
  K0.setFromTriplets(tk.begin(), tk.end());
  K0.makeCompressed();
  std::vector<double*> diag(static_cast<std::size_t>(m));  // K's diagonal entries, and K0's values there
  Eigen::VectorXd diag0(m);
  Eigen::SparseMatrix<double> K = K0;
  for (int j = 0; j < m; ++j) {
    diag[static_cast<std::size_t>(j)] = &K.coeffRef(j, j);
    diag0[j] = *diag[static_cast<std::size_t>(j)];
  }
  NewtonLu lu;

  InteriorPointResult r;
  std::vector<double> history;
  for (;;) {
    const double t = z.dot(w) / m;
    history.push_back(t);
    if (t < s.target) break;
    if (r.iterations >= s.max_iterations) {
      r.stalled = true;
      break;
    }
    const std::size_t h = history.size();
    if (h > static_cast<std::size_t>(s.stall_iterations) &&
        !(t < 0.5 * history[h - 1 - static_cast<std::size_t>(s.stall_iterations)])) {
      r.stalled = true;
      break;
    }
    for (int j = 0; j < m; ++j) *diag[static_cast<std::size_t>(j)] = diag0[j] + w[j] / z[j];
    if (!lu.factorize(K)) {
      r.stalled = true;
      break;
    }
    const Eigen::VectorXd rb = balance_residual(v, z);
    const Eigen::VectorXd rw = w - complements(v, z);
    const Eigen::VectorXd rG = rb.head(nG).cwiseQuotient(mv_G);
    // Solves for (dv, dz) with complementarity right-hand side rc; dw follows.
    const auto newton = [&](const Eigen::VectorXd& rc, Eigen::VectorXd& dv, Eigen::VectorXd& dz, Eigen::VectorXd& dw) {
      Eigen::VectorXd rhs(m + 1);
      rhs.head(m) = rc.cwiseQuotient(z) + rw + G_G * rG;
      rhs[m] = -rb[nG];
      const Eigen::VectorXd d = lu.solve(rhs);
      dz = d.head(m);
      dv.resize(n);
      dv.head(nG) = (Af_G * dz - rb.head(nG)).cwiseQuotient(mv_G);
      dv[nG] = d[m];
      dw = complements(dv, dz) - c - rw;  // G dv + N dz - rw (complements() adds c)
    };
    Eigen::VectorXd dv, dz, dw;
    newton(-z.cwiseProduct(w), dv, dz, dw);  // predictor: towards t = 0
    const double a_aff = std::min(step_to_boundary(z, dz), step_to_boundary(w, dw));
    const double t_aff = (z + a_aff * dz).dot(w + a_aff * dw) / m;
    const double sigma = std::pow(std::max(0.0, t_aff) / t, 3);
    const Eigen::VectorXd rc =
        Eigen::VectorXd::Constant(m, sigma * t) - z.cwiseProduct(w) - dz.cwiseProduct(dw);
    newton(rc, dv, dz, dw);  // corrector
    const double a = 0.995 * std::min(step_to_boundary(z, dz), step_to_boundary(w, dw));
    v += a * dv;
    z += a * dz;
    w += a * dw;
    ++r.iterations;
  }
  r.complementarity = history.back();
  r.natural_residual = z.cwiseMin(w).cwiseAbs().maxCoeff();
  r.f = F0 * forces(z);
  r.q = (dt2 * U) * v;
  return r;
}

}  // namespace unjam
