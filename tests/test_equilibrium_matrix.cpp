// Balance rows of a fixed contact geometry: selection, shape, rank, the packing's own network.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "unjam/core/error.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/lp/rank.hpp"
#include "unjam/packing/packing_io.hpp"

namespace {

using unjam::Packing;

Packing fixture(const char* name) {
  return unjam::read_packing(std::string(UNJAM_FIXTURES_DIR) + "/" + name);
}

int dense_rank(const Eigen::SparseMatrix<double>& A) {
  Eigen::FullPivLU<Eigen::MatrixXd> lu{Eigen::MatrixXd(A)};
  lu.setThreshold(1e-10);
  return static_cast<int>(lu.rank());
}

TEST(EquilibriumMatrix, P50SelectsForceCarryingOrTouchingContacts) {
  const Packing p = fixture("p50-mu0.1");
  const auto sys = unjam::build_equilibrium_system(p);
  EXPECT_EQ(p.contacts.size(), 82u);
  EXPECT_EQ(sys.num_contacts(), 81);  // bounds-reference.csv lists 81 contacts
  EXPECT_EQ(sys.grains.size(), 44u);  // 50 grains, 6 rattlers
  EXPECT_EQ(sys.A.rows(), 3 * 44 + 1);
  EXPECT_EQ(sys.A.cols(), 2 * 81);
}

TEST(EquilibriumMatrix, PackingNetworkSatisfiesBalanceRows) {
  for (const char* name : {"p50-mu0.1", "lattice16"}) {
    const Packing p = fixture(name);
    const auto sys = unjam::build_equilibrium_system(p);
    const Eigen::VectorXd r = sys.A * unjam::packing_forces(p, sys) - sys.rhs;
    const double F0 = p.force_unit();
    EXPECT_LT(r.head(r.size() - 1).cwiseAbs().maxCoeff(), 1e-9 * F0) << name;
    EXPECT_LT(std::abs(r[r.size() - 1]), 1e-9 * sys.rhs[r.size() - 1]) << name;
    EXPECT_NEAR(sys.rhs[sys.pressure_row()], 2.0 * p.cell.area() * p.meta.contact.P_ext, 1e-12);
  }
}

TEST(EquilibriumMatrix, RankAndDimensionMatchDenseLu) {
  for (const char* name : {"p50-mu0.1", "lattice16"}) {
    Packing p = fixture(name);
    const auto sys = unjam::build_equilibrium_system(p);
    const auto info = unjam::equilibrium_rank(sys);
    // Two translation rows are redundant in a periodic cell, no other.
    EXPECT_EQ(info.rank, info.rows - 2) << name;
    EXPECT_EQ(info.rank, dense_rank(unjam::cone_matrix(sys))) << name;
    EXPECT_EQ(info.dimension, 2 * sys.num_contacts() - info.rank) << name;
  }
}

TEST(EquilibriumMatrix, RankOfSubsetsMatchesDenseLu) {
  // Dropping contacts frees grains (mechanisms: a null space of A_y^T) or, once A_y is tall
  // (more rows than cone columns, always at mu = 0 where the torque rows vanish), leaves
  // the null space on the other side. Both sides must give the dense rank.
  const Packing p = fixture("p50-mu0.1");
  for (const int stride : {2, 3, 4, 5, 7}) {
    std::vector<int> kept;
    for (int k = 0; k < static_cast<int>(p.contacts.size()); ++k)
      if (k % stride != 0) kept.push_back(k);
    for (const double mu : {0.1, 0.0}) {
      Packing q = p;
      q.meta.contact.mu = mu;
      const auto sys = unjam::build_equilibrium_system(q, kept);
      const auto info = unjam::equilibrium_rank(sys);
      EXPECT_EQ(info.rank, dense_rank(unjam::cone_matrix(sys))) << "stride " << stride << " mu " << mu;
      EXPECT_EQ(info.dimension, info.columns - info.rank);
    }
  }
}

TEST(EquilibriumMatrix, RankCountsEverySingularValueBelowTheThreshold) {
  // With a threshold in a gap of the spectrum, 18 singular values of lattice16 count as zero:
  // more than the rank's first block of 8 holds, so it must widen its block until the count
  // fits. The reference is the dense SVD of the same (tall) matrix with the same threshold.
  const Packing p = fixture("lattice16");
  const auto sys = unjam::build_equilibrium_system(p);
  const Eigen::MatrixXd Ay(unjam::cone_matrix(sys));
  const Eigen::MatrixXd B = Ay.rows() >= Ay.cols() ? Ay : Eigen::MatrixXd(Ay.transpose());
  const double max_norm = B.colwise().norm().maxCoeff();
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(B).singularValues();  // descending
  const int n = static_cast<int>(s.size());
  // The widest gap s_(c) / s_(c-1) of the ascending spectrum with 5 <= c <= 40.
  int c = 5;
  for (int k = 5; k <= std::min(40, n - 1); ++k)
    if (s[n - 1 - k] / s[n - k] > s[n - 1 - c] / s[n - c]) c = k;
  ASSERT_GT(s[n - 1 - c] / s[n - c], 2.0) << "no clear gap";
  const double threshold = std::sqrt(s[n - 1 - c] * s[n - c]) / max_norm;
  const auto info = unjam::equilibrium_rank(sys, threshold);
  EXPECT_GT(c, 8);
  EXPECT_EQ(info.rank, n - c);
}

TEST(EquilibriumMatrix, ConeCoordinatesReproduceForces) {
  const Packing p = fixture("p50-mu0.1");
  const auto sys = unjam::build_equilibrium_system(p);
  const Eigen::VectorXd x = unjam::packing_forces(p, sys);
  // y_2k = fn + ft/mu, y_2k+1 = fn - ft/mu; A_y y must equal A x.
  Eigen::VectorXd y(x.size());
  for (int k = 0; k < sys.num_contacts(); ++k) {
    y[2 * k] = x[2 * k] + x[2 * k + 1] / sys.mu;
    y[2 * k + 1] = x[2 * k] - x[2 * k + 1] / sys.mu;
  }
  EXPECT_LT((unjam::cone_matrix(sys) * y - sys.A * x).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::VectorXd fn, ft;
  unjam::cone_to_forces(sys, y, fn, ft);
  for (int k = 0; k < sys.num_contacts(); ++k) {
    EXPECT_NEAR(fn[k], x[2 * k], 1e-12);
    EXPECT_NEAR(ft[k], x[2 * k + 1], 1e-12);
  }
}

TEST(EquilibriumMatrix, SelfContactIsRejected) {
  Packing p;
  p.cell = {2.0, 2.0};
  p.particles.resize(1);
  p.particles.radius[0] = 1.0;
  unjam::Contact c;
  c.n = {1, 0};
  c.l = {2, 0};
  c.fn = 1.0;
  p.contacts.push_back(c);
  EXPECT_THROW(unjam::build_equilibrium_system(p), unjam::Error);
}

}  // namespace
