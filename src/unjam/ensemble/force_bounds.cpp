#include "unjam/ensemble/force_bounds.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include <coin/ClpSimplex.hpp>
#include <coin/ClpSolve.hpp>
#include <omp.h>

#include "unjam/core/error.hpp"

namespace unjam {

std::vector<ContactState> contact_states(const ForceNetwork& network, double mu, double tol) {
  std::vector<ContactState> states(network.fn.size(), ContactState::closed);
  for (Eigen::Index k = 0; k < network.fn.size(); ++k) {
    if (network.fn[k] <= tol)
      states[k] = ContactState::open;
    else if (mu > 0.0 && mu * network.fn[k] - std::abs(network.ft[k]) <= tol)
      states[k] = ContactState::sliding;
  }
  return states;
}

namespace {

// CLP status codes: 0 optimal, 1 primal infeasible, 2 dual infeasible (unbounded),
// 3 stopped on iterations or time, 4 stopped due to errors.
std::string clp_status_text(int status) {
  switch (status) {
    case 1: return "primal infeasible";
    case 2: return "unbounded";
    case 3: return "stopped on the iteration limit";
    case 4: return "stopped on numerical errors";
    default: return "status " + std::to_string(status);
  }
}

}  // namespace

ForceLP::ForceLP(const EquilibriumSystem& system, LpMethod method, double tolerance)
    : system_(&system),
      method_(method),
      min_model_(std::make_unique<ClpSimplex>()),
      per_contact_(cone_columns_per_contact(system.mu)) {
  if (system.num_contacts() == 0)
    throw Error("no admissible force network: the packing has no contact to carry P_ext");
  const Eigen::SparseMatrix<double> Ay = cone_matrix(system);
  const int rows = static_cast<int>(Ay.rows()), cols = static_cast<int>(Ay.cols());
  std::vector<CoinBigIndex> start(Ay.outerIndexPtr(), Ay.outerIndexPtr() + cols + 1);
  // Columns y >= 0 (the Coulomb cone and fn >= 0); rows: equalities A_y y = rhs.
  const std::vector<double> col_lb(cols, 0.0), col_ub(cols, COIN_DBL_MAX), obj(cols, 0.0);
  const std::vector<double> row_b(system.rhs.data(), system.rhs.data() + rows);
  ClpSimplex& model = *min_model_;
  model.loadProblem(cols, rows, start.data(), Ay.innerIndexPtr(), Ay.valuePtr(),
                    col_lb.data(), col_ub.data(), obj.data(), row_b.data(), row_b.data());
  model.setLogLevel(0);
  model.setPrimalTolerance(tolerance);
  model.setDualTolerance(tolerance);
  // A zero objective is dual feasible: dual simplex finds a first admissible network.
  model.dual();
  iterations_ += model.numberIterations();
  if (model.status() == 1)
    throw Error("no admissible force network: no forces satisfy the balance of the " +
                std::to_string(system.grains.size()) + " grains with the " +
                std::to_string(system.num_contacts()) +
                " contacts, P_in = P_ext, fn >= 0 and |ft| <= mu fn (mu = " +
                std::to_string(system.mu) + "); is the packing static and its contact "
                "list complete (try a larger --gap-tol)?");
  if (model.status() != 0)
    throw Error("force bounds LP: first solve " + clp_status_text(model.status()));
  if (method_ == LpMethod::simplex) max_model_ = std::make_unique<ClpSimplex>(model);
  last_ = &model;
}

ForceLP::ForceLP(const ForceLP& other)
    : system_(other.system_),
      method_(other.method_),
      min_model_(std::make_unique<ClpSimplex>(*other.min_model_)),
      max_model_(other.max_model_ ? std::make_unique<ClpSimplex>(*other.max_model_) : nullptr),
      last_(min_model_.get()),
      per_contact_(other.per_contact_),
      min_k_(other.min_k_),
      max_k_(other.max_k_) {}

ForceLP::~ForceLP() = default;

double ForceLP::optimize(int k, double direction) {
  if (k < 0 || k >= system_->num_contacts())
    throw Error("force bounds LP: contact " + std::to_string(k) + " out of range");
  // The barrier needs no basis: one model serves both senses.
  const bool use_max_model = method_ == LpMethod::simplex && direction < 0.0;
  ClpSimplex& model = use_max_model ? *max_model_ : *min_model_;
  int& objective_k = use_max_model ? max_k_ : min_k_;
  if (k != objective_k) {
    // Objective fn_k: (y_2k + y_2k+1) / 2 for mu > 0, y_k for mu = 0.
    const double weight = 1.0 / per_contact_;
    if (objective_k >= 0)
      for (int j = 0; j < per_contact_; ++j)
        model.setObjectiveCoefficient(per_contact_ * objective_k + j, 0.0);
    for (int j = 0; j < per_contact_; ++j)
      model.setObjectiveCoefficient(per_contact_ * k + j, weight);
    objective_k = k;
  }
  model.setOptimizationDirection(direction);  // +1 minimise, -1 maximise
  if (method_ == LpMethod::barrier) {
    ClpSolve options;
    options.setSolveType(ClpSolve::useBarrierNoCross);
    options.setPresolveType(ClpSolve::presolveOff);
    options.setSpecialOption(2, 1);  // no interrupt handler: thread safe
    model.initialSolve(options);
    iterations_ += model.numberIterations();
    if (model.status() != 0) {  // rare barrier failure: finish by simplex
      model.primal();
      iterations_ += model.numberIterations();
    }
  } else {
    model.primal();
    iterations_ += model.numberIterations();
  }
  if (model.status() != 0)
    throw Error("force bounds LP: " + std::string(direction > 0 ? "min" : "max") +
                " of fn of contact " + std::to_string(k) + " " +
                clp_status_text(model.status()));
  last_ = &model;
  const double* y = model.primalColumnSolution();
  return per_contact_ == 2 ? 0.5 * (y[2 * k] + y[2 * k + 1]) : y[k];
}

double ForceLP::min_fn(int k) { return optimize(k, 1.0); }
double ForceLP::max_fn(int k) { return optimize(k, -1.0); }

ForceNetwork ForceLP::network() const {
  const int cols = last_->numberColumns();
  const Eigen::Map<const Eigen::VectorXd> y(last_->primalColumnSolution(), cols);
  ForceNetwork net;
  cone_to_forces(*system_, y, net.fn, net.ft);
  return net;
}

ForceBounds compute_force_bounds(const EquilibriumSystem& system,
                                 const ForceBoundsOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  const int Nc = system.num_contacts();
  ForceBounds bounds;
  bounds.fn_min.resize(Nc);
  bounds.fn_max.resize(Nc);
  if (options.keep_networks_at_max) bounds.network_at_max.resize(Nc);

  const ForceLP base(system, options.method, options.tolerance);  // throws if the set is empty
  std::atomic<int> done{0};
  std::atomic<long long> iterations{base.iterations()};
  bool any_error = false;
  std::string error;  // first error of any thread
  const int threads = std::max(1, std::min(options.threads, Nc));

#pragma omp parallel num_threads(threads)
  {
    ForceLP lp(base);  // own model and basis, warm-started from the first solve
    const long long before = lp.iterations();
    // Contiguous blocks: neighbouring contacts share grains, so the previous optimum is a
    // good start for the next objective. An exception may not leave the loop, so each
    // thread records the first error and skips the rest.
#pragma omp for schedule(static)
    for (int k = 0; k < Nc; ++k) {
      bool failed = false;
#pragma omp atomic read
      failed = any_error;
      if (failed) continue;
      try {
        bounds.fn_min[k] = lp.min_fn(k);
        bounds.fn_max[k] = lp.max_fn(k);
        if (options.keep_networks_at_max) bounds.network_at_max[k] = lp.network();
      } catch (const std::exception& e) {
#pragma omp critical(unjam_force_bounds_error)
        if (!any_error) {
          error = e.what();
#pragma omp atomic write
          any_error = true;
        }
      }
      const int n_done = ++done;
      if (options.progress && omp_get_thread_num() == 0) options.progress(n_done, Nc);
    }
    iterations += lp.iterations() - before;
  }
  if (any_error) throw Error(error);
  if (options.progress) options.progress(Nc, Nc);
  bounds.iterations = iterations;
  bounds.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return bounds;
}

}  // namespace unjam
