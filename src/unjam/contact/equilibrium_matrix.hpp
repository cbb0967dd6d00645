#pragma once
// The balance rows of a fixed contact geometry (docs/ensemble.md, "Which contacts and
// rows enter").
//
// Unknowns: the forces (fn_k, ft_k) of the contacts that enter, columns 2k and 2k + 1.
// Rows, three per grain i that has a contact in the list (block g = position of i in `grains`):
//   3g     sum of x-forces on i            = 0
//   3g + 1 sum of y-forces on i            = 0
//   3g + 2 sum of torques on i divided by R_i (a force, so every row has force units) = 0
// and one last row, the pressure bath P_in = P_ext at rest:
//   sum_k fn_k |l_k| = 2 V P_ext,   V = Lx Ly.
// Contact k = (a, b) puts fn n + ft t on b and -(fn n + ft t) on a; its torques are
// T_a = -R_a ft and T_b = -R_b ft, so both torque rows get the coefficient -1 for ft.
// In a periodic cell the x- and y-rows summed over all grains vanish identically (global
// translation): at least two rows are redundant.
//
// Coulomb-cone coordinates. In 2D the Coulomb cone |ft| <= mu fn is the set of nonnegative
// combinations of its two edges, so every admissible network is A_y y = rhs with y >= 0:
//   mu > 0: y_2k = fn_k + ft_k / mu,  y_2k+1 = fn_k - ft_k / mu   (each >= 0; fn >= 0 follows)
//           fn_k = (y_2k + y_2k+1) / 2,  ft_k = mu (y_2k - y_2k+1) / 2;
//   mu = 0: y_k = fn_k, ft_k = 0 (one column per contact).
// y_2k = 0 means ft_k = -mu fn_k (sliding with negative ft), y_2k+1 = 0 means ft_k = mu fn_k,
// both zero means the contact is open. The map y -> (fn, ft) is linear and, for mu > 0,
// invertible, so a uniform distribution in y is uniform in (fn, ft) too.
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

// Contacts that enter the admissible set under `model`: those classify_contact
// (packing/contact_model.hpp) marks touching (gap < model.touch_gap, units of R_max) or loaded
// (fn > fn_tol F0, F0 = 2 R_avg model.P_ext). Returns indices into packing.contacts, in order.
std::vector<int> select_contacts(const Packing& packing, const ContactModel& model,
                                 double fn_tol = 1e-9);

// The same under the packing's own model (packing.meta.contact) with touch_gap = gap_tol.
std::vector<int> select_contacts(const Packing& packing, double gap_tol = 1e-9,
                                 double fn_tol = 1e-9);

struct EquilibriumSystem {
  std::vector<int> contacts;   // indices into packing.contacts; column pair 2k, 2k + 1
  std::vector<int> grains;     // grains with a contact in the list; row block 3g .. 3g + 2
  Eigen::SparseMatrix<double> A;  // (3 N_g + 1) x (2 N_c), columns (fn_k, ft_k)
  Eigen::VectorXd rhs;            // zero except the pressure row: 2 V P_ext
  double mu = 0.0;                // Coulomb friction coefficient of the packing
  double F0 = 1.0;                // force unit 2 R_avg P_ext

  int num_contacts() const { return static_cast<int>(contacts.size()); }
  int pressure_row() const { return static_cast<int>(A.rows()) - 1; }
};

// Builds the balance rows of the listed contacts. Throws unjam::Error for a contact of a
// grain with itself or an index out of range.
EquilibriumSystem build_equilibrium_system(const Packing& packing,
                                           const std::vector<int>& contacts);

// Convenience: select_contacts + build_equilibrium_system.
EquilibriumSystem build_equilibrium_system(const Packing& packing, double gap_tol = 1e-9,
                                           double fn_tol = 1e-9);

// The packing's own network as a column vector (fn_0, ft_0, fn_1, ft_1, ...).
Eigen::VectorXd packing_forces(const Packing& packing, const EquilibriumSystem& system);

// Columns per contact in Coulomb-cone coordinates: 2 if mu > 0, 1 if mu = 0.
int cone_columns_per_contact(double mu);

// The balance rows in cone coordinates: A_y = A M, with (fn, ft) = M y.
Eigen::SparseMatrix<double> cone_matrix(const EquilibriumSystem& system);

// (fn, ft) of every contact from cone coordinates y.
void cone_to_forces(const EquilibriumSystem& system, const Eigen::VectorXd& y,
                    Eigen::VectorXd& fn, Eigen::VectorXd& ft);

}  // namespace unjam
