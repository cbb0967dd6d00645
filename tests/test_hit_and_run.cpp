// Hit-and-run sampling of the admissible force networks: admissibility of every sample,
// agreement with the LP intervals, a hand-made polytope with a known distribution, seeding.
#include <gtest/gtest.h>

#include <cmath>

#include "unjam/core/error.hpp"
#include "unjam/ensemble/hit_and_run.hpp"
#include "unjam/packing/packing_io.hpp"
#include "fixture_p50.hpp"

namespace {

using unjam::Packing;

using unjam::testing::p50;

// Mean over contacts of (sampled width) / (LP width).
double coverage(const unjam::HitAndRunResult& r, const unjam::ForceBounds& b) {
  double sum = 0.0;
  for (Eigen::Index k = 0; k < b.fn_max.size(); ++k)
    sum += (r.sample_max[k] - r.sample_min[k]) / (b.fn_max[k] - b.fn_min[k]);
  return sum / static_cast<double>(b.fn_max.size());
}

TEST(HitAndRun, EverySampleIsAdmissible) {
  const auto& d = p50();
  const double tol = 1e-9 * d.packing.force_unit();
  unjam::testing::WorstViolation worst{d.sys};
  unjam::HitAndRunOptions options;
  options.samples = 2000;
  options.on_sample = [&](const unjam::ForceNetwork& net) { worst.add(net); };
  const auto result = unjam::sample_hit_and_run(d.sys, d.bounds, options);
  EXPECT_EQ(result.samples, 2000);
  EXPECT_GT(result.dimension, 0);
  EXPECT_LT(worst.residual, 1e-9);
  EXPECT_GE(worst.fn, -tol);
  EXPECT_LE(worst.coulomb, tol);
}

TEST(HitAndRun, SampledRangesLieInsideLpIntervalsAndApproachThem) {
  const auto& d = p50();
  const double tol = 1e-9 * d.packing.force_unit();
  unjam::HitAndRunOptions few, many;
  few.samples = 1000;
  many.samples = 20000;
  const auto r_few = unjam::sample_hit_and_run(d.sys, d.bounds, few);
  const auto r_many = unjam::sample_hit_and_run(d.sys, d.bounds, many);
  for (const auto* r : {&r_few, &r_many})
    for (int k = 0; k < d.sys.num_contacts(); ++k) {
      EXPECT_GE(r->sample_min[k], d.bounds.fn_min[k] - tol) << k;
      EXPECT_LE(r->sample_max[k], d.bounds.fn_max[k] + tol) << k;
      EXPECT_GE(r->mean[k], r->sample_min[k]);
      EXPECT_LE(r->mean[k], r->sample_max[k]);
    }
  const double c_few = coverage(r_few, d.bounds), c_many = coverage(r_many, d.bounds);
  EXPECT_GT(c_many, c_few);
  EXPECT_LE(c_many, 1.0 + 1e-9);
  EXPECT_GT(r_many.eta, 0.0);
}

TEST(HitAndRun, SameSeedSameSamples) {
  const auto& d = p50();
  std::vector<Eigen::VectorXd> first, second, other;
  unjam::HitAndRunOptions options;
  options.samples = 50;
  options.seed = 7;
  options.on_sample = [&](const unjam::ForceNetwork& n) { first.push_back(n.fn); };
  unjam::sample_hit_and_run(d.sys, d.bounds, options);
  options.on_sample = [&](const unjam::ForceNetwork& n) { second.push_back(n.fn); };
  unjam::sample_hit_and_run(d.sys, d.bounds, options);
  options.seed = 8;
  options.on_sample = [&](const unjam::ForceNetwork& n) { other.push_back(n.fn); };
  unjam::sample_hit_and_run(d.sys, d.bounds, options);
  ASSERT_EQ(first.size(), 50u);
  for (std::size_t s = 0; s < first.size(); ++s) EXPECT_EQ(first[s], second[s]);
  EXPECT_NE(first.back(), other.back());
}

// Square lattice of four disks at mu = 0 (see test_force_bounds.cpp): the admissible set is
// the simplex {h_A, h_B, v_A, v_B >= 0, sum = 4}. Uniform on it, each chain force has the
// marginal 4 Beta(1, 3): mean 1, standard deviation sqrt(3/5), so eta = sqrt(3/5).
void expect_uniform_on_hand_made_simplex(int max_dense_columns) {
  Packing p;
  p.cell = {2.0, 2.0};
  p.particles.resize(4);
  p.particles.x = {0.5, 1.5, 0.5, 1.5};
  p.particles.y = {0.5, 0.5, 1.5, 1.5};
  p.particles.radius = {0.5, 0.5, 0.5, 0.5};
  auto contact = [](int a, int b, unjam::Vec2 l) {
    unjam::Contact c;
    c.a = a;
    c.b = b;
    c.l = l;
    c.n = l;
    c.fn = 1.0;
    return c;
  };
  p.contacts = {contact(0, 1, {1, 0}), contact(1, 0, {1, 0}), contact(2, 3, {1, 0}),
                contact(3, 2, {1, 0}), contact(0, 2, {0, 1}), contact(2, 0, {0, 1}),
                contact(1, 3, {0, 1}), contact(3, 1, {0, 1})};
  const auto sys = unjam::build_equilibrium_system(p);
  const auto bounds = unjam::compute_force_bounds(sys);
  unjam::HitAndRunOptions options;
  options.samples = 20000;
  options.max_dense_columns = max_dense_columns;
  const auto r = unjam::sample_hit_and_run(sys, bounds, options);
  EXPECT_EQ(r.dimension, 3);
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(r.mean[k], 1.0, 0.05) << k;
    EXPECT_NEAR(r.std[k], std::sqrt(0.6), 0.05) << k;
  }
  EXPECT_NEAR(r.eta, std::sqrt(0.6), 0.05);
}

TEST(HitAndRun, UniformOnHandMadeSimplex) { expect_uniform_on_hand_made_simplex(4000); }

// Beyond max_dense_columns the walk draws its directions through the sparse projector onto
// null(A) instead of a dense basis: the same distribution, other random numbers.
TEST(HitAndRun, SparseProjectorSamplesTheSameDistribution) {
  expect_uniform_on_hand_made_simplex(0);

  const auto& d = p50();
  const double tol = 1e-9 * d.packing.force_unit();
  constexpr int kBatches = 10, kPerBatch = 500;
  // Batch means of fn per contact (successive samples of the walk are correlated; means of
  // long batches are nearly independent, so their scatter gives an honest error).
  const auto batch_means = [&](int max_dense_columns, unjam::testing::WorstViolation* worst) {
    Eigen::MatrixXd means = Eigen::MatrixXd::Zero(d.sys.num_contacts(), kBatches);
    int s = 0;
    unjam::HitAndRunOptions options;
    options.samples = kBatches * kPerBatch;
    options.max_dense_columns = max_dense_columns;
    options.on_sample = [&](const unjam::ForceNetwork& net) {
      means.col(s++ / kPerBatch) += net.fn / kPerBatch;
      if (worst) worst->add(net);
    };
    const auto r = unjam::sample_hit_and_run(d.sys, d.bounds, options);
    return std::make_pair(r.dimension, means);
  };
  unjam::testing::WorstViolation worst{d.sys};
  const auto [dim_dense, dense] = batch_means(4000, nullptr);
  const auto [dim_sparse, sparse] = batch_means(0, &worst);
  EXPECT_EQ(dim_sparse, dim_dense);
  EXPECT_LT(worst.residual, 1e-9);
  EXPECT_GE(worst.fn, -tol);
  EXPECT_LE(worst.coulomb, tol);
  // z_k = (difference of the two means) / (its error): about 1 in mean square if both walks
  // sample one distribution; a sampler off by its error on every contact would give >= 4.
  double sum_z2 = 0.0;
  for (Eigen::Index k = 0; k < dense.rows(); ++k) {
    const auto var = [&](const Eigen::MatrixXd& m) {
      const double mean = m.row(k).mean();
      return (m.row(k).array() - mean).square().sum() / (kBatches - 1) / kBatches;
    };
    const double diff = sparse.row(k).mean() - dense.row(k).mean();
    sum_z2 += diff * diff / (var(dense) + var(sparse) + 1e-30);
  }
  EXPECT_LT(sum_z2 / static_cast<double>(dense.rows()), 3.0);
}

}  // namespace
