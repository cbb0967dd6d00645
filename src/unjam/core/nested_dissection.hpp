#pragma once
// A fill-reducing ordering by METIS's nested dissection, for the sparse factorisations of
// the LP's normal equations (lp/normal_equations) and of the probe's reduced systems
// (solver/klu_factor).
#include <vector>

#include <Eigen/SparseCore>

namespace unjam {

// The dense rows of a matrix whose rows have count[i] entries: more than 10x the mean count
// and more than 100 entries (as a pressure degree of freedom coupled to every contact). In a
// nested dissection they would make every separator large.
std::vector<bool> dense_rows(const std::vector<int>& count);

// The ordering of a symmetric sparsity pattern P (values ignored; the pattern of P + P^T is
// read): permute[new] = old. The rows marked dense are left out of the graph and ordered last,
// in their original order, as a minimum-degree ordering does. Empty if METIS fails.
// Thread-safe: the calls into METIS are made one at a time, and each leaves the process's
// handlers of SIGTERM and SIGABRT as it found them (METIS swaps them during the call).
std::vector<int> nested_dissection_order(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& P,
                                         const std::vector<bool>& dense);

}  // namespace unjam
