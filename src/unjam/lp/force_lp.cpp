#include "unjam/lp/force_lp.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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

// A dual ray w (CLP's infeasibility ray) checked as a certificate of emptiness by
// proves_no_admissible_network (force_lp.hpp).
bool proves_empty(const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs, const double* ray) {
  return ray != nullptr && proves_no_admissible_network(Ay, rhs, Eigen::Map<const Eigen::VectorXd>(ray, rhs.size()));
}

// What a simplex solve on the admissible set decided, checked (simplex_decides).
enum class Verdict { network, empty, undecided };

// How a simplex solve (`method`: &ClpSimplex::dual for the zero objective of the admissibility
// test, dual feasible from any basis; &ClpSimplex::primal for a min / max LP from the last
// optimum's basis) decides. CLP's verdicts are on the scaled model, and near an empty set they
// may be wrong unscaled: an "optimal" point with cone coordinates of -2e-3 F0 where a ray
// proves the set empty (docs/ensemble.md, "The friction threshold"), or one 4.6e-9 outside a
// cone ("The LP"). So each verdict is checked in the model's own units: a point by
// admissible_point, emptiness by proves_empty on CLP's ray (which CLP does not always leave).
// Where the check fails, the model is solved again without scaling from the basis reached
// (counted in `unscaled`), and that verdict is checked; undecided where neither checks out.
// Throws unjam::Error, the message starting with `what`, where CLP ends neither optimal nor
// infeasible. `iterations` and `unscaled` accumulate; the model's scaling is restored.
Verdict simplex_decides(ClpSimplex& model, int (ClpSimplex::*method)(int, int), const Eigen::SparseMatrix<double>& Ay,
                        const Eigen::VectorXd& rhs, double tolerance, const std::string& what, long long& iterations,
                        long long& unscaled) {
  struct RestoreScaling {
    ClpSimplex& model;
    int flag;
    ~RestoreScaling() { model.scaling(flag); }
  } restore{model, model.scalingFlag()};
  Verdict verdict = Verdict::undecided;
  for (int attempt = 0; attempt < 2 && verdict == Verdict::undecided; ++attempt) {
    if (attempt == 1) {
      model.scaling(0);
      ++unscaled;
    }
    (model.*method)(0, 0);
    iterations += model.numberIterations();
    const int status = model.status();
    if (status == 0) {
      const Eigen::Map<const Eigen::VectorXd> y(model.primalColumnSolution(), Ay.cols());
      if (admissible_point(Ay, rhs, y, tolerance)) verdict = Verdict::network;
    } else if (status == 1) {
      double* ray = model.infeasibilityRay();
      if (proves_empty(Ay, rhs, ray)) verdict = Verdict::empty;
      delete[] ray;
    } else {
      throw Error(what + clp_status_text(status));
    }
  }
  return verdict;
}

// The admissible set decided by its elastic LP, where CLP's own verdicts do not check out (it
// leaves no ray on some infeasible ends):
//   min sum_i (s+_i + s-_i)  over  A_y y + s+ - s- = rhs,  y, s+, s- >= 0,
// feasible from y = 0, dual feasible from the all-slack basis (every cost >= 0), so dual
// simplex reaches its optimum. Its row duals w are a Farkas certificate where the set is empty
// (max rhs . w over A_y^T w <= 0, |w_i| <= 1), checked by proves_no_admissible_network; else its
// y an admissible point, checked by admissible_point. Undecided where neither checks.
Verdict elastic_decides(const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs, double tolerance,
                        const std::string& what, long long& iterations) {
  const int rows = static_cast<int>(Ay.rows()), cols = static_cast<int>(Ay.cols());
  Eigen::SparseMatrix<double> E(rows, cols + 2 * rows);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(Ay.nonZeros() + 2 * rows);
  for (int j = 0; j < cols; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Ay, j); it; ++it)
      entries.emplace_back(static_cast<int>(it.row()), j, it.value());
  for (int i = 0; i < rows; ++i) {
    entries.emplace_back(i, cols + i, 1.0);
    entries.emplace_back(i, cols + rows + i, -1.0);
  }
  E.setFromTriplets(entries.begin(), entries.end());
  E.makeCompressed();
  ClpSimplex model;
  load_admissible_set(model, E, rhs, tolerance);
  for (int j = cols; j < cols + 2 * rows; ++j) model.setObjectiveCoefficient(j, 1.0);
  model.dual();
  iterations += model.numberIterations();
  if (model.status() != 0) throw Error(what + "elastic LP: " + clp_status_text(model.status()));
  // The certificate first: just below the threshold the set is empty while the elastic y
  // balances every row to within the row check (1e-6 of its scale), and emptiness is the one
  // verdict that is exact.
  const Eigen::Map<const Eigen::VectorXd> w(model.dualRowSolution(), rows);
  if (proves_no_admissible_network(Ay, rhs, w)) return Verdict::empty;
  const Eigen::Map<const Eigen::VectorXd> y(model.primalColumnSolution(), cols);
  return admissible_point(Ay, rhs, y, tolerance) ? Verdict::network : Verdict::undecided;
}

// Whether the admissible set of the loaded `model` has a point: simplex_decides by dual simplex, then
// elastic_decides where that is undecided. Throws unjam::Error where both are.
bool decides_network(ClpSimplex& model, const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs,
                     double tolerance, const std::string& what, long long& iterations) {
  long long unscaled = 0;
  Verdict verdict = simplex_decides(model, &ClpSimplex::dual, Ay, rhs, tolerance, what, iterations, unscaled);
  if (verdict == Verdict::undecided) verdict = elastic_decides(Ay, rhs, tolerance, what, iterations);
  if (verdict == Verdict::undecided)
    throw Error(what + "undecided: neither CLP's point nor a certificate of emptiness checks out in the "
                       "model's own units (with scaling, without, and by the elastic LP)");
  return verdict == Verdict::network;
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

// The pressure row's coefficients are positive (|l_k| / 2 per cone column, |l_k| without
// friction), so every point of the set has 0 <= y_j <= ub_j = rhs_P / (A_y)_{Pj}, and
// w . rhs = (A_y^T w) . y >= -sum_j max(0, -(A_y^T w)_j) ub_j. With the sign of w that makes
// w . rhs < 0, a w whose w . rhs lies below that bound, by more than the round-off of A_y^T w,
// admits no point.
bool proves_no_admissible_network(const Eigen::SparseMatrix<double>& Ay, const Eigen::VectorXd& rhs,
                                  const Eigen::Ref<const Eigen::VectorXd>& w) {
  if (w.size() != rhs.size() || Ay.rows() != rhs.size()) return false;
  const Eigen::Index P = rhs.size() - 1;
  const double w_rhs = w.dot(rhs);
  if (!(std::isfinite(w_rhs) && w_rhs != 0.0)) return false;
  const double sign = w_rhs < 0.0 ? 1.0 : -1.0;
  double lowest = 0.0;  // the bound on w . rhs (sign applied) over the set, minus round-off
  for (int j = 0; j < Ay.outerSize(); ++j) {
    double c = 0.0, magnitude = 0.0, a_P = 0.0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(Ay, j); it; ++it) {
      c += sign * it.value() * w[it.row()];
      magnitude += std::abs(it.value() * w[it.row()]);
      if (it.row() == P) a_P = it.value();
    }
    const double roundoff = 1e-14 * magnitude;
    if (!(a_P > 0.0)) {  // y_j unbounded: only a column with A_y^T w >= 0 is allowed
      if (c < -roundoff) return false;
      continue;
    }
    lowest -= (std::max(0.0, -c) + roundoff) * (rhs[P] / a_P);
  }
  return sign * w_rhs < lowest;
}

void check_lp_tolerance(double tolerance, const std::string& prefix) {
  if (tolerance >= kMinLpTolerance && tolerance <= kMaxLpTolerance) return;
  char why[96];
  std::snprintf(why, sizeof why, "the LP tolerance must be in [%g, %g] (got %g)", kMinLpTolerance, kMaxLpTolerance,
                tolerance);
  throw Error(prefix + why);
}

bool has_admissible_network(const EquilibriumSystem& system, double tolerance) {
  SimplexBasis none;
  return has_admissible_network(system, tolerance, none);
}

bool has_admissible_network(const EquilibriumSystem& system, double tolerance, SimplexBasis& basis) {
  if (system.num_contacts() == 0) return false;
  ClpSimplex model;
  const Eigen::SparseMatrix<double> Ay = cone_matrix(system);
  load_admissible_set(model, Ay, system.rhs, tolerance);
  const std::size_t size = static_cast<std::size_t>(model.numberColumns()) + model.numberRows();
  if (basis.status.size() == size) model.copyinStatus(basis.status.data());
  basis.iterations = 0;
  const std::string what = "admissible set LP at mu = " + std::to_string(system.mu) + ": ";
  const bool found = decides_network(model, Ay, system.rhs, tolerance, what, basis.iterations);
  basis.status.assign(model.statusArray(), model.statusArray() + size);
  return found;
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
  // its verdict checked in the model's own units (decides_network).
  bool admissible = false;
  if (method == LpMethod::barrier) {
    const BarrierEnd end = barrier_.solve(model);
    iterations_ += model.numberIterations();
    const Eigen::Map<const Eigen::VectorXd> y(model.primalColumnSolution(), cols);
    admissible = end != BarrierEnd::failed && admissible_point(Ay_, system.rhs, y, tolerance_);
  }
  if (!admissible) {
    if (!decides_network(model, Ay_, system.rhs, tolerance_, "force bounds LP: first solve ", iterations_))
      throw no_admissible_network(system);
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
  const auto what = [&] {  // the start of an error message, made only where one may be needed
    return "force bounds LP: " + std::string(direction > 0 ? "min" : "max") + " of fn of contact " +
           std::to_string(k) + " ";
  };
  if (!solved) {  // the simplex method, or a barrier point finished by simplex
    // The set is not empty (the constructor found a checked point): an empty verdict here is
    // the band below a friction threshold where a point passes the row check while no network
    // exists (docs/ensemble.md), and it is reported as such.
    const Verdict v = simplex_decides(model, &ClpSimplex::primal, Ay_, system_->rhs, tolerance_, what(),
                                      iterations_, unscaled_solves_);
    if (v == Verdict::empty) throw no_admissible_network(*system_);
    solved = v == Verdict::network;
  }
  if (!solved)
    throw Error(what() + "ends " + clp_status_text(model.status()) +
                (model.status() == 0 ? " at a point that is not admissible in the model's own units "
                                       "(with scaling and without)"
                                     : ""));
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
