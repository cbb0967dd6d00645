#include "unjam/contact/equilibrium_matrix.hpp"

#include <algorithm>
#include <string>

#include "unjam/core/error.hpp"
#include "unjam/core/units.hpp"

namespace unjam {

std::vector<int> select_contacts(const Packing& packing, const ContactModel& model, double fn_tol) {
  const double F0 = force_unit(packing.mean_radius(), model.P_ext);
  std::vector<int> selected;
  for (std::size_t k = 0; k < packing.contacts.size(); ++k) {
    const Contact& c = packing.contacts[k];
    const ContactClass state = classify_contact(c, model.touch_gap, fn_tol * F0);
    if (state.touching || state.loaded) selected.push_back(static_cast<int>(k));
  }
  return selected;
}

std::vector<int> select_contacts(const Packing& packing, double gap_tol, double fn_tol) {
  return select_contacts(packing, with_touch_gap(packing.meta.contact, gap_tol), fn_tol);
}

EquilibriumSystem build_equilibrium_system(const Packing& packing,
                                           const std::vector<int>& contacts) {
  const int N = static_cast<int>(packing.size());
  EquilibriumSystem sys;
  sys.contacts = contacts;
  sys.mu = packing.meta.contact.mu;
  sys.F0 = packing.force_unit();

  // Row blocks: grains in increasing index order.
  std::vector<int> block(N, -1);
  for (int index : contacts) {
    if (index < 0 || index >= static_cast<int>(packing.contacts.size()))
      throw Error("equilibrium rows: contact index " + std::to_string(index) + " out of range");
    const Contact& c = packing.contacts[index];
    if (c.a < 0 || c.a >= N || c.b < 0 || c.b >= N)
      throw Error("equilibrium rows: contact " + std::to_string(index) +
                  " names a grain out of range");
    if (c.a == c.b)
      throw Error("equilibrium rows: contact " + std::to_string(index) + " joins grain " +
                  std::to_string(c.a) + " to its own periodic image (cell too small)");
    block[c.a] = block[c.b] = 0;
  }
  for (int i = 0; i < N; ++i)
    if (block[i] == 0) {
      block[i] = static_cast<int>(sys.grains.size());
      sys.grains.push_back(i);
    }

  const int rows = 3 * static_cast<int>(sys.grains.size()) + 1;
  const int cols = 2 * static_cast<int>(contacts.size());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(contacts.size() * 11);
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const Contact& c = packing.contacts[contacts[k]];
    const int col_fn = 2 * static_cast<int>(k), col_ft = col_fn + 1;
    const Vec2 t = c.t();
    const int ra = 3 * block[c.a], rb = 3 * block[c.b];
    // Force on b: +fn n + ft t; on a: the negative.
    for (int d = 0; d < 2; ++d) {
      triplets.emplace_back(rb + d, col_fn, c.n[d]);
      triplets.emplace_back(rb + d, col_ft, t[d]);
      triplets.emplace_back(ra + d, col_fn, -c.n[d]);
      triplets.emplace_back(ra + d, col_ft, -t[d]);
    }
    // Torque / R: T_a / R_a = -ft, T_b / R_b = -ft.
    triplets.emplace_back(ra + 2, col_ft, -1.0);
    triplets.emplace_back(rb + 2, col_ft, -1.0);
    // Pressure row: fn |l|.
    triplets.emplace_back(rows - 1, col_fn, c.l.norm());
  }
  sys.A.resize(rows, cols);
  sys.A.setFromTriplets(triplets.begin(), triplets.end());
  sys.A.makeCompressed();
  sys.rhs = Eigen::VectorXd::Zero(rows);
  sys.rhs[rows - 1] = 2.0 * packing.cell.area() * packing.meta.contact.P_ext;
  return sys;
}

EquilibriumSystem build_equilibrium_system(const Packing& packing, double gap_tol,
                                           double fn_tol) {
  return build_equilibrium_system(packing, select_contacts(packing, gap_tol, fn_tol));
}

Eigen::VectorXd packing_forces(const Packing& packing, const EquilibriumSystem& system) {
  Eigen::VectorXd x(2 * system.num_contacts());
  for (int k = 0; k < system.num_contacts(); ++k) {
    const Contact& c = packing.contacts[system.contacts[k]];
    x[2 * k] = c.fn;
    x[2 * k + 1] = c.ft;
  }
  return x;
}

int cone_columns_per_contact(double mu) { return mu > 0.0 ? 2 : 1; }

Eigen::SparseMatrix<double> cone_matrix(const EquilibriumSystem& system) {
  const int Nc = system.num_contacts();
  const int per = cone_columns_per_contact(system.mu);
  // M maps y to (fn, ft): mu > 0: fn = (y0 + y1)/2, ft = mu (y0 - y1)/2; mu = 0: fn = y0.
  std::vector<Eigen::Triplet<double>> triplets;
  for (int k = 0; k < Nc; ++k) {
    if (per == 2) {
      triplets.emplace_back(2 * k, 2 * k, 0.5);
      triplets.emplace_back(2 * k, 2 * k + 1, 0.5);
      triplets.emplace_back(2 * k + 1, 2 * k, 0.5 * system.mu);
      triplets.emplace_back(2 * k + 1, 2 * k + 1, -0.5 * system.mu);
    } else {
      triplets.emplace_back(2 * k, k, 1.0);
    }
  }
  Eigen::SparseMatrix<double> M(2 * Nc, per * Nc);
  M.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SparseMatrix<double> Ay = system.A * M;
  Ay.prune(0.0);
  Ay.makeCompressed();
  return Ay;
}

void cone_to_forces(const EquilibriumSystem& system, const Eigen::VectorXd& y,
                    Eigen::VectorXd& fn, Eigen::VectorXd& ft) {
  const int Nc = system.num_contacts();
  fn.resize(Nc);
  ft.resize(Nc);
  if (cone_columns_per_contact(system.mu) == 2) {
    for (int k = 0; k < Nc; ++k) {
      fn[k] = 0.5 * (y[2 * k] + y[2 * k + 1]);
      ft[k] = 0.5 * system.mu * (y[2 * k] - y[2 * k + 1]);
    }
  } else {
    fn = y.head(Nc);
    ft.setZero();
  }
}

}  // namespace unjam
