#pragma once
// Lemke's complementary pivoting for a linear complementarity problem LCP(M, q):
//     find z >= 0 with w = M z + q >= 0 and z^T w = 0,
// dense, with the lexicographic minimum-ratio rule (no cycling on degenerate problems) and
// a covering vector d > 0 (by default e = (1, ..., 1)). Lemke's method ends on a solution or on a ray; for the
// step problems of docs/probe.md (copositive matrices of the Stewart-Trinkle form) it ends on
// a solution. It returns one solution; a problem that is not a P-matrix problem may have
// others. Cost: O(n^2) per pivot, a few n pivots: meant for n up to a few thousand.
#include <optional>

#include <Eigen/Core>

namespace unjam {

struct LemkeResult {
  Eigen::VectorXd z;   // the solution (empty if none was found)
  int pivots = 0;
  bool ray = false;    // ended on a secondary ray (no solution found)
};

// Throws unjam::Error if M is not square, if q or d differ from it in size, or if d has an
// entry <= 0. An empty d is e.
LemkeResult solve_lcp_lemke(const Eigen::MatrixXd& M, const Eigen::VectorXd& q,
                            const Eigen::VectorXd& d = {}, int max_pivots = 100000);

}  // namespace unjam
