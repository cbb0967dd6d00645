#include "unjam/lp/force_lp.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <coin/ClpSimplex.hpp>

#include "unjam/core/error.hpp"

namespace unjam {

std::vector<ContactState> contact_states(const ForceNetwork& network, double mu, double tol) {
  std::vector<ContactState> states(network.fn.size());
  for (Eigen::Index k = 0; k < network.fn.size(); ++k)
    states[k] = contact_state(network.fn[k], network.ft[k], mu, tol);
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

// Whether the barrier's point y is an admissible network: y >= -tolerance, and every row of
// A_y y = rhs holds to kAdmissibleRowResidual of its own scale (|A_y| |y| + |rhs|)_i. A grain's
// balance row is of the order of its forces (F0) and the pressure row of 2 V P_ext (~1e3 F0 at
// 1000 disks), so a check against max |rhs| alone would pass a point whose grains are out of
// balance by 1e-3 F0. The barrier returns such points where the admissible set is empty or
// nearly so and calls them optimal (docs/ensemble.md, "The LP").
bool admissible_point(const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs,
                      const Eigen::Map<const Eigen::VectorXd>& y, double tolerance) {
  if (!(y.minCoeff() >= -tolerance)) return false;
  // One pass over A_y's entries: residual = A_y y - rhs, scale = |A_y| |y| + |rhs|.
  Eigen::VectorXd residual = -rhs, scale = rhs.cwiseAbs();
  for (int j = 0; j < Ay.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Ay, j); it; ++it) {
      const double term = it.value() * y[j];
      residual[it.row()] += term;
      scale[it.row()] += std::abs(term);
    }
  // A row's scale is at least the mean cone coordinate (a typical force): a grain that carries
  // almost no force has a row scale near 0 and a residual at round-off of the others.
  const double floor = y.cwiseAbs().mean();
  for (Eigen::Index i = 0; i < residual.size(); ++i)
    if (!(std::abs(residual[i]) <= kAdmissibleRowResidual * std::max(scale[i], floor))) return false;
  return true;
}

// Dual simplex on the model's zero objective (dual feasible from the start): whether the
// admissible set has a point. CLP's status 1 (primal infeasible) says it has none, reliably where
// the barrier's points are not (admissible_point); any other end but optimal throws, the message
// starting with `what`.
bool dual_finds_network(ClpSimplex& model, const std::string& what) {
  model.dual();
  if (model.status() == 1) return false;
  if (model.status() != 0) throw Error(what + clp_status_text(model.status()));
  return true;
}

Error no_admissible_network(const EquilibriumSystem& system) {
  return Error("no admissible force network: no forces satisfy the balance of the " +
               std::to_string(system.grains.size()) + " grains with the " +
               std::to_string(system.num_contacts()) +
               " contacts, P_in = P_ext, fn >= 0 and |ft| <= mu fn (mu = " + std::to_string(system.mu) +
               "); is the packing static and its contact list complete (try a larger --gap-tol)?");
}

}  // namespace

void load_admissible_set(ClpSimplex& model, const Eigen::SparseMatrix<double>& Ay,
                         const Eigen::VectorXd& rhs, double tolerance) {
  const int rows = static_cast<int>(Ay.rows()), cols = static_cast<int>(Ay.cols());
  const std::vector<CoinBigIndex> start(Ay.outerIndexPtr(), Ay.outerIndexPtr() + cols + 1);
  const std::vector<double> col_lb(cols, 0.0), col_ub(cols, COIN_DBL_MAX), obj(cols, 0.0);
  const std::vector<double> row_b(rhs.data(), rhs.data() + rows);
  model.loadProblem(cols, rows, start.data(), Ay.innerIndexPtr(), Ay.valuePtr(),
                    col_lb.data(), col_ub.data(), obj.data(), row_b.data(), row_b.data());
  model.setLogLevel(0);
  model.setPrimalTolerance(tolerance);
  model.setDualTolerance(tolerance);
}

bool has_admissible_network(const EquilibriumSystem& system, double tolerance) {
  if (system.num_contacts() == 0) return false;
  ClpSimplex model;
  load_admissible_set(model, cone_matrix(system), system.rhs, tolerance);
  return dual_finds_network(model, "admissible set LP: ");
}

ForceLP::ForceLP(const EquilibriumSystem& system, LpMethod method, double tolerance)
    : system_(&system),
      method_(method),
      tolerance_(tolerance),
      min_model_(std::make_unique<ClpSimplex>()),
      per_contact_(cone_columns_per_contact(system.mu)) {
  if (system.num_contacts() == 0)
    throw Error("no admissible force network: the packing has no contact to carry P_ext");
  Ay_ = cone_matrix(system);
  const int cols = static_cast<int>(Ay_.cols());
  ClpSimplex& model = *min_model_;
  load_admissible_set(model, Ay_, system.rhs, tolerance);
  // A first admissible network. The barrier method needs no basis and finds one fastest
  // (0.2 s against 5 s of dual simplex at 2000 disks); the simplex method needs the basis,
  // and a zero objective is dual feasible: dual simplex. The barrier may call an empty set
  // optimal, so its point is checked (admissible_point); when it fails, dual simplex decides,
  // which classifies an empty set reliably.
  bool admissible = false;
  if (method == LpMethod::barrier) {
    const BarrierEnd end = barrier_.solve(model);
    iterations_ += model.numberIterations();
    const Eigen::Map<const Eigen::VectorXd> y(model.primalColumnSolution(), cols);
    admissible = end != BarrierEnd::failed && admissible_point(Ay_, system.rhs, y, tolerance_);
  }
  if (!admissible) {
    const bool found = dual_finds_network(model, "force bounds LP: first solve ");
    iterations_ += model.numberIterations();
    if (!found) throw no_admissible_network(system);
  }
  if (method_ == LpMethod::simplex) max_model_ = std::make_unique<ClpSimplex>(model);
  last_ = &model;
}

ForceLP::ForceLP(const ForceLP& other)
    : system_(other.system_),
      method_(other.method_),
      tolerance_(other.tolerance_),
      Ay_(other.Ay_),
      barrier_(other.barrier_),
      min_model_(std::make_unique<ClpSimplex>(*other.min_model_)),
      max_model_(other.max_model_ ? std::make_unique<ClpSimplex>(*other.max_model_) : nullptr),
      last_(min_model_.get()),
      per_contact_(other.per_contact_),
      min_objective_(other.min_objective_),
      max_objective_(other.max_objective_) {}

ForceLP::~ForceLP() = default;

double ForceLP::optimize(int k, double direction) {
  if (k < 0 || k >= system_->num_contacts())
    throw Error("force bounds LP: contact " + std::to_string(k) + " out of range");
  // The barrier needs no basis: one model serves both senses.
  const bool use_max_model = method_ == LpMethod::simplex && direction < 0.0;
  ClpSimplex& model = use_max_model ? *max_model_ : *min_model_;
  int& objective = use_max_model ? max_objective_ : min_objective_;
  if (k != objective) {
    // Objective fn_k: (y_2k + y_2k+1) / 2 for mu > 0, y_k for mu = 0.
    for (int j = 0; j < per_contact_; ++j) {
      if (objective >= 0) model.setObjectiveCoefficient(per_contact_ * objective + j, 0.0);
      model.setObjectiveCoefficient(per_contact_ * k + j, 1.0 / per_contact_);
    }
    objective = k;
  }
  model.setOptimizationDirection(direction);  // +1 minimise, -1 maximise
  bool solved = false;
  last_loosened_ = false;
  if (method_ == LpMethod::barrier) {
    const BarrierEnd end = barrier_.solve(model);
    iterations_ += model.numberIterations();
    last_loosened_ = end == BarrierEnd::optimal_loosened;
    loosened_solves_ += last_loosened_;
    // An optimum the barrier reports at a point that is not admissible is a failure too.
    const Eigen::Map<const Eigen::VectorXd> y(model.primalColumnSolution(), model.numberColumns());
    solved = end != BarrierEnd::failed && admissible_point(Ay_, system_->rhs, y, tolerance_);
    simplex_finishes_ += !solved;
  }
  if (!solved) {  // the simplex method, or a barrier failure finished by simplex
    model.primal();
    iterations_ += model.numberIterations();
    solved = model.status() == 0;
  }
  // An empty set that the first solve took for admissible (dual simplex within its tolerance
  // from the barrier's point) shows here.
  if (model.status() == 1) throw no_admissible_network(*system_);
  if (!solved)
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

}  // namespace unjam
