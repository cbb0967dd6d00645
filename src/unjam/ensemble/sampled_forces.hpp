#pragma once
// Per-contact statistics of the normal forces of sampled admissible networks, shared by the
// samplers (hit_and_run, random_walk), and the indeterminacy (docs/ensemble.md, "The sampler"):
//   eta = <dF> / <|F|>,  dF_k the standard deviation of fn_k over the ensemble,
//   <.> the mean over contacts (|F| also over samples).
#include <Eigen/Core>

namespace unjam {

struct SampledForces {
  Eigen::VectorXd sample_min, sample_max;  // per contact: extremes of fn over the samples
  Eigen::VectorXd mean, std;               // per contact: mean and standard deviation (n - 1)
  double eta = 0.0;                        // <dF> / <|F|>
  double mean_fn = 0.0;                    // <|F|>: fn over contacts and samples
};

// Running statistics (Welford's update of mean and second moment).
class SampledForcesAccumulator {
 public:
  explicit SampledForcesAccumulator(Eigen::Index contacts);
  void add(const Eigen::VectorXd& fn);
  long long count() const { return n_; }
  SampledForces result() const;

 private:
  long long n_ = 0;
  Eigen::VectorXd min_, max_, mean_, m2_;
};

}  // namespace unjam
