#include "unjam/core/nested_dissection.hpp"

#include <algorithm>
#include <csignal>
#include <iostream>  // Eigen's MetisSupport reports METIS errors on std::cerr
#include <mutex>
#include <numeric>

#include <Eigen/MetisSupport>

namespace unjam {

namespace {
// METIS (its GKlib) traps SIGTERM and SIGABRT around every call: it installs its own handler,
// which longjmps back into the call, and on return puts back the handler it found, from a
// per-thread record. The handlers are the process's, not the thread's: two calls at once
// from two threads leave METIS's handler installed after both have returned, and the next
// SIGTERM then jumps into a call that has ended (a crash instead of the clean stop of
// docs/probe.md, "Campaigns"). So one call at a time, and the process's handlers of the two
// signals are put back as they were before it, whatever METIS leaves.
std::mutex metis_mutex;

template <class Call>
void metis_call(Call&& call) {
  const std::lock_guard<std::mutex> lock(metis_mutex);
  struct sigaction term {}, abrt {};
  ::sigaction(SIGTERM, nullptr, &term);
  ::sigaction(SIGABRT, nullptr, &abrt);
  call();
  ::sigaction(SIGTERM, &term, nullptr);
  ::sigaction(SIGABRT, &abrt, nullptr);
}
}  // namespace

std::vector<bool> dense_rows(const std::vector<int>& count) {
  const double entries = std::accumulate(count.begin(), count.end(), 0.0);
  const double n = static_cast<double>(std::max<std::size_t>(count.size(), 1));
  const double dense_count = std::max(100.0, 10.0 * entries / n);
  std::vector<bool> dense(count.size());
  for (std::size_t i = 0; i < count.size(); ++i) dense[i] = count[i] > dense_count;
  return dense;
}

std::vector<int> nested_dissection_order(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& P,
                                         const std::vector<bool>& dense) {
  using Sparse = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  const int n = static_cast<int>(P.rows());
  std::vector<int> sparse_index(static_cast<std::size_t>(n), -1), sparse_rows, dense_last;
  for (int i = 0; i < n; ++i) {
    if (dense[static_cast<std::size_t>(i)]) {
      dense_last.push_back(i);
    } else {
      sparse_index[static_cast<std::size_t>(i)] = static_cast<int>(sparse_rows.size());
      sparse_rows.push_back(i);
    }
  }
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(static_cast<std::size_t>(P.nonZeros()));
  for (int j = 0; j < P.outerSize(); ++j) {
    const int sj = sparse_index[static_cast<std::size_t>(j)];
    if (sj < 0) continue;
    for (Sparse::InnerIterator it(P, j); it; ++it) {
      const int si = sparse_index[static_cast<std::size_t>(it.row())];
      if (si >= 0) entries.emplace_back(si, sj, 1.0);
    }
  }
  const int ns = static_cast<int>(sparse_rows.size());
  Sparse G(ns, ns);
  G.setFromTriplets(entries.begin(), entries.end());
  std::vector<int> permute;
  permute.reserve(static_cast<std::size_t>(n));
  if (ns > 0) {
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> Q;
    metis_call([&] { Eigen::MetisOrdering<int>()(G, Q); });  // Q.indices()[new] = old, as METIS's perm
    if (Q.size() != ns) return {};
    for (int i = 0; i < ns; ++i) permute.push_back(sparse_rows[static_cast<std::size_t>(Q.indices()[i])]);
  }
  permute.insert(permute.end(), dense_last.begin(), dense_last.end());
  return permute;
}

}  // namespace unjam
