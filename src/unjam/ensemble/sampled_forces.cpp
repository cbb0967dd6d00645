#include "unjam/ensemble/sampled_forces.hpp"

#include <limits>

namespace unjam {

SampledForcesAccumulator::SampledForcesAccumulator(Eigen::Index contacts)
    : min_(Eigen::VectorXd::Constant(contacts, std::numeric_limits<double>::infinity())),
      max_(Eigen::VectorXd::Constant(contacts, -std::numeric_limits<double>::infinity())),
      mean_(Eigen::VectorXd::Zero(contacts)),
      m2_(Eigen::VectorXd::Zero(contacts)) {}

void SampledForcesAccumulator::add(const Eigen::VectorXd& fn) {
  ++n_;
  min_ = min_.cwiseMin(fn);
  max_ = max_.cwiseMax(fn);
  const Eigen::VectorXd delta = fn - mean_;
  mean_ += delta / static_cast<double>(n_);
  m2_ += delta.cwiseProduct(fn - mean_);
}

SampledForces SampledForcesAccumulator::result() const {
  SampledForces r;
  r.sample_min = min_;
  r.sample_max = max_;
  r.mean = mean_;
  // Sample standard deviation (n - 1); zero for a single sample.
  r.std = n_ > 1 ? (m2_ / (n_ - 1.0)).cwiseSqrt().eval()
                 : Eigen::VectorXd::Zero(mean_.size()).eval();
  r.mean_fn = mean_.size() > 0 ? mean_.mean() : 0.0;
  r.eta = r.mean_fn > 0.0 ? r.std.mean() / r.mean_fn : 0.0;
  return r;
}

}  // namespace unjam
