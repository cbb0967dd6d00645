#include "unjam/solver/interior_point.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "unjam/core/error.hpp"
#include "unjam/solver/klu_factor.hpp"

namespace unjam {

namespace {

// Largest step a in (0, 1] with x + a dx >= 0.
double step_to_boundary(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) {
  double a = 1.0;
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (dx[i] < 0.0) a = std::min(a, -x[i] / dx[i]);
  return a;
}

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
  if (!(s.neighbourhood >= 0.0 && s.neighbourhood < 1.0))
    throw Error("interior point: neighbourhood must be in [0, 1) (got " + std::to_string(s.neighbourhood) + ")");
  if (!(s.short_step >= 0.0 && s.short_step <= 1.0))
    throw Error("interior point: short_step must be in [0, 1] (got " + std::to_string(s.short_step) + ")");
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

  // The Newton matrix [[diag mv, -A_f], [G, N + diag(w / z)]], condensed to the path's
  // reduced system (probe/cd_path): the grains' rows of v are eliminated (their masses are
  // diagonal), which leaves W = A_G^T mv_G^-1 A_G bordered by the pressure dof, and per
  // contact the rows of beta+, beta- and sigma are eliminated locally (docs/probe.md, "An
  // interior-point start"). With D = w / z on the four rows of contact k, x = dU_t and
  // e1 = 1 / D_beta+, e2 = 1 / D_beta-, E = D_sigma + e1 + e2, the tangential rows give
  //     d sigma = (y_sigma + e1 y_beta+ + e2 y_beta- - mu dfn + (e2 - e1) x) / E,
  //     dft = a + b x + c dfn,   a = (D_sigma (e1 y+ - e2 y-) + 2 e1 e2 (y+ - y-) + (e2 - e1) y_sigma) / E,
  //                              b = -(4 e1 e2 + (e1 + e2) D_sigma) / E <= 0,   c = -mu (e2 - e1) / E
  // (written without the differences of large terms that e1 or e2 ~ 1 / D -> infinity would
  // cancel),
  // so the system in (dfn, dft, dv_p) has rows
  //     normal:     (W df)_n + a_p,n dv_p + D_fn dfn = y_fn
  //     tangential: dft - b ((W df)_t + a_p,t dv_p) - c dfn = a          (dft = 0 at mu = 0)
  //     pressure:   mv_p dv_p - a_p . df = -r_p
  // of fixed pattern; its values are W's scaled per row plus the diagonal terms.
  const int nG = n - 1;  // the pressure dof is A's last row
  const Eigen::SparseMatrix<double> A_G = A.topRows(nG);
  const Eigen::VectorXd mv_G = mv.head(nG);
  const Eigen::SparseMatrix<double> W = Eigen::SparseMatrix<double>(A_G.transpose()) * mv_G.cwiseInverse().asDiagonal() * A_G;
  const Eigen::VectorXd a_p = Eigen::VectorXd(A.row(nG).transpose());
  const int nf = 2 * nc;
  std::vector<Eigen::Triplet<double>> tk;
  for (int col = 0; col < W.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(W, col); it; ++it)
      tk.emplace_back(static_cast<int>(it.row()), col, it.value());
  for (int r = 0; r < nf; ++r) {
    tk.emplace_back(r, r, 0.0);
    if (a_p[r] != 0.0) {
      tk.emplace_back(r, nf, a_p[r]);
      tk.emplace_back(nf, r, -a_p[r]);
    }
  }
  for (int k = 0; k < nc; ++k) tk.emplace_back(2 * k + 1, 2 * k, 0.0);
  tk.emplace_back(nf, nf, mv[nG]);
  Eigen::SparseMatrix<double> K(nf + 1, nf + 1);
  K.setFromTriplets(tk.begin(), tk.end());
  K.makeCompressed();
  const Eigen::VectorXd base = Eigen::Map<const Eigen::VectorXd>(K.valuePtr(), K.nonZeros());
  std::vector<double*> diag(static_cast<std::size_t>(nf)), tn(static_cast<std::size_t>(nc));
  for (int r = 0; r < nf; ++r) diag[static_cast<std::size_t>(r)] = &K.coeffRef(r, r);
  for (int k = 0; k < nc; ++k) tn[static_cast<std::size_t>(k)] = &K.coeffRef(2 * k + 1, 2 * k);
  Eigen::VectorXd row_scale = Eigen::VectorXd::Ones(nf + 1);
  // Per contact: e1, e2, E (above), and c of its tangential row (b is its row scale, -b).
  Eigen::VectorXd te1(nc), te2(nc), tE(nc), tc(nc);
  KluFactor lu;

  InteriorPointResult r;
  std::vector<double> history;
  for (;;) {
    const double t = z.dot(w) / m;
    history.push_back(t);
    r.centrality.push_back(z.cwiseProduct(w).minCoeff() / t);
    if (t < s.target) break;
    if (r.iterations >= s.max_iterations) {
      r.stalled = true;
      break;
    }
    const std::size_t h = history.size();
    // Stalled: near the end of the path (t below stall_below), t has not halved over
    // stall_iterations iterations. Early on t may stay put for a while before it falls.
    if (t < s.stall_below && h > static_cast<std::size_t>(s.stall_iterations) &&
        !(t < 0.5 * history[h - 1 - static_cast<std::size_t>(s.stall_iterations)])) {
      r.stalled = true;
      break;
    }
    // The row scales and diagonal terms of this iterate (D = w / z).
    const Eigen::VectorXd D = w.cwiseQuotient(z);
    for (int k = 0; k < nc; ++k) {
      if (p == 1) {  // dft = 0
        row_scale[2 * k + 1] = tc[k] = 0.0;
        continue;
      }
      const int j = p * k;
      const double e1 = 1.0 / D[j + 1], e2 = 1.0 / D[j + 2], E = D[j + 3] + e1 + e2;
      te1[k] = e1, te2[k] = e2, tE[k] = E;
      row_scale[2 * k + 1] = (4.0 * e1 * e2 + (e1 + e2) * D[j + 3]) / E;  // -b
      tc[k] = -mu * (e2 - e1) / E;
    }
    {
      double* value = K.valuePtr();
      const int* inner = K.innerIndexPtr();
      for (Eigen::Index e = 0; e < K.nonZeros(); ++e) value[e] = row_scale[inner[e]] * base[e];
      for (int k = 0; k < nc; ++k) {
        *diag[static_cast<std::size_t>(2 * k)] += D[p * k];
        *diag[static_cast<std::size_t>(2 * k + 1)] += 1.0;
        *tn[static_cast<std::size_t>(k)] -= tc[k];
      }
    }
    if (!lu.factorize(K)) {
      r.stalled = true;
      break;
    }
    const Eigen::VectorXd rb = balance_residual(v, z);
    const Eigen::VectorXd rw = w - complements(v, z);
    const Eigen::VectorXd rG = rb.head(nG).cwiseQuotient(mv_G);
    const Eigen::VectorXd ArG = A_G.transpose() * rG;
    Eigen::VectorXd GrG = Eigen::VectorXd::Zero(m);  // G_G rG in the rows of z
    for (int k = 0; k < nc; ++k) {
      GrG[p * k] = ArG[2 * k];
      if (p == 1) continue;
      GrG[p * k + 1] = ArG[2 * k + 1];
      GrG[p * k + 2] = -ArG[2 * k + 1];
    }
    // Solves for (dv, dz) with complementarity right-hand side rc; dw follows.
    const auto newton = [&](const Eigen::VectorXd& rc, Eigen::VectorXd& dv, Eigen::VectorXd& dz, Eigen::VectorXd& dw) {
      const Eigen::VectorXd y = rc.cwiseQuotient(z) + rw + GrG;  // the rows of z
      Eigen::VectorXd d = Eigen::VectorXd::Zero(nf + 1);  // the right-hand side, then the solution
      for (int k = 0; k < nc; ++k) {
        const int j = p * k;
        d[2 * k] = y[j];
        if (p == 1) continue;
        const double e1 = te1[k], e2 = te2[k];
        d[2 * k + 1] = (D[j + 3] * (e1 * y[j + 1] - e2 * y[j + 2]) + 2.0 * e1 * e2 * (y[j + 1] - y[j + 2]) +
                        (e2 - e1) * y[j + 3]) / tE[k];  // a
      }
      d[nf] = -rb[nG];
      // One step of iterative refinement where the factors keep the diagonal's pivots (KluPivoting).
      const bool refine = lu.diagonal_pivots();
      const Eigen::VectorXd rhs = refine ? d : Eigen::VectorXd();
      lu.solve_in_place(d);
      if (refine) {
        Eigen::VectorXd correction = rhs - K * d;
        lu.solve_in_place(correction);
        d += correction;
      }
      const Eigen::VectorXd df = d.head(nf);
      const Eigen::VectorXd dU = W * df + a_p * d[nf];
      dz.resize(m);
      for (int k = 0; k < nc; ++k) {
        const int j = p * k;
        dz[j] = df[2 * k];
        if (p == 1) continue;
        const double e1 = te1[k], e2 = te2[k], E = tE[k], x = dU[2 * k + 1];
        const double dsigma = (y[j + 3] + e1 * y[j + 1] + e2 * y[j + 2] - mu * df[2 * k] + (e2 - e1) * x) / E;
        // the beta with the smaller e from its row, the other from dft = dbeta+ - dbeta-
        if (e1 >= e2) {
          dz[j + 2] = e2 * (y[j + 2] + x - dsigma);
          dz[j + 1] = df[2 * k + 1] + dz[j + 2];
        } else {
          dz[j + 1] = e1 * (y[j + 1] - x - dsigma);
          dz[j + 2] = dz[j + 1] - df[2 * k + 1];
        }
        dz[j + 3] = dsigma;
      }
      dv.resize(n);
      dv.head(nG) = (A_G * forces(dz) - rb.head(nG)).cwiseQuotient(mv_G);
      dv[nG] = d[nf];
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
    double a = 0.995 * std::min(step_to_boundary(z, dz), step_to_boundary(w, dw));
    if (s.neighbourhood > 0.0) {
      // The wide neighbourhood: min z w >= gamma mean z w at the new iterate (header).
      const double gamma = std::min(s.neighbourhood, r.centrality.back());
      const auto cut = [&](double step) {
        for (; step > 1e-8; step *= 0.7) {
          const Eigen::VectorXd zw = (z + step * dz).cwiseProduct(w + step * dw);
          if (zw.minCoeff() >= gamma * zw.mean()) break;
        }
        return step;
      };
      a = cut(a);
      if (a < s.short_step) {  // plain Newton steps towards sigma t in its place
        ++r.short_steps;
        for (const double towards : {0.3, 0.6, 0.9, 1.0}) {
          newton(Eigen::VectorXd::Constant(m, towards * t) - z.cwiseProduct(w), dv, dz, dw);
          a = cut(0.995 * std::min(step_to_boundary(z, dz), step_to_boundary(w, dw)));
          if (a >= 0.5) break;
        }
      }
    }
    v += a * dv;
    z += a * dz;
    w += a * dw;
    ++r.iterations;
  }
  r.complementarity = history.back();
  r.natural_residual = z.cwiseMin(w).cwiseAbs().maxCoeff();
  r.closed.assign(static_cast<std::size_t>(nc), false);
  r.sliding.assign(static_cast<std::size_t>(nc), false);
  for (int k = 0; k < nc; ++k) {
    const int j = p * k;
    r.closed[static_cast<std::size_t>(k)] = z[j] > w[j];
    if (p == 4) r.sliding[static_cast<std::size_t>(k)] = z[j + 3] > w[j + 3];
  }
  r.f = F0 * forces(z);
  r.q = (dt2 * U) * v;
  return r;
}

}  // namespace unjam
