#include "unjam/probe/cd_path.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include <Eigen/LU>
#include <Eigen/Sparse>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/cpu_time.hpp"
#include "unjam/core/error.hpp"
#include "unjam/probe/kinematic_probe.hpp"
#include "unjam/solver/interior_point.hpp"
#include "unjam/solver/klu_factor.hpp"

namespace unjam {

namespace {

enum class State : std::int8_t { kOpen, kStick, kSlidePlus, kSlideMinus, kFrictionless };

bool closed(State s) { return s != State::kOpen; }
double slip_sign(State s) { return s == State::kSlidePlus ? 1.0 : s == State::kSlideMinus ? -1.0 : 0.0; }

// One linear function of lambda that a state requires to stay >= 0, and the state the
// contact takes when it would turn negative.
struct Event {
  double lambda = std::numeric_limits<double>::infinity();
  double rate = 0.0;  // |slope| / scale, to break ties at one lambda
  int contact = -1;
  State next = State::kOpen;
};

// The unknowns x = (q / dt^2 over the rows of A, f = (fn_0, ft_0, ...)) and the system
//   M (q / dt^2) - A f = -((1 - lambda) A f0 + lambda b)                   (balance)
//   closed:  a_n^T q / dt^2 + kappa (fn - fref_n) = -(gap - lambda g [probed]) / dt^2
//   stick:   a_t^T q / dt^2 + kappa (ft - fref_t) = 0
//   slide s: w (ft + s mu fn) = 0;   open: w fn = 0, w ft = 0;   mu = 0: w ft = 0
// (w = 1 / mean grain mass scales the algebraic rows like the kinematic ones). The grains'
// rows are eliminated (M_G is diagonal), which leaves the sparse system S in (f, v_p) of
// size 2 N_c + 1: the Delassus operator W = A_G^T M_G^-1 A_G on the kinematic rows, the
// pressure row and column as its border. S is diagonally dominant where K had zero pivots.
class StepPath {
 public:
  StepPath(const CdStepProblem& pb, const Eigen::VectorXd& f0, double kappa, int max_updated_rows)
      : max_updated_rows_(static_cast<std::size_t>(std::max(0, max_updated_rows))), pb_(pb), n_(static_cast<int>(pb.system.A.rows())), nc_(pb.num_contacts()),
        mu_(pb.system.mu), dt2_(pb.dt * pb.dt), kappa_(kappa), fref0_(f0),
        state_(nc_, State::kOpen) {
    w_ = pb.inverse_mass.head(n_ - 1).mean();
    // g_eff(lambda): the probed pair's opening grows from 0 to g; a touching pair without
    // force starts open by a distinct ~1e-9 g that closes by lambda = 1, so that no two
    // such pairs close at one lambda.
    gap0_ = pb.g_eff;
    gap1_ = Eigen::VectorXd::Zero(nc_);
    gap0_[pb.probed] = 0.0;
    gap1_[pb.probed] = -pb.g;
    for (int k = 0; k < nc_; ++k)
      if (k != pb.probed && pb.g_eff[k] <= 0.0 && !(f0[2 * k] > 0.0)) {
        gap0_[k] = 1e-9 * pb.g * (1.0 + static_cast<double>(k) / nc_);
        gap1_[k] = -gap0_[k];
      }
    fref1_ = Eigen::VectorXd::Zero(2 * nc_);
    tgap0_ = tgap1_ = Eigen::VectorXd::Zero(nc_);
    load0_ = pb.system.A * f0;
    load1_ = pb.system.rhs - load0_;
    const Eigen::SparseMatrix<double>& A = pb.system.A;
    Eigen::SparseMatrix<double> A_G = A.topRows(n_ - 1);
    Eigen::VectorXd minv_G = pb.inverse_mass.head(n_ - 1);
    W_ = Eigen::SparseMatrix<double>(A_G.transpose()) * minv_G.asDiagonal() * A_G;
    a_p_ = Eigen::VectorXd(A.row(n_ - 1).transpose());
    Z_.resize(2 * nc_ + 1, static_cast<Eigen::Index>(max_updated_rows_));
    D_.resize(max_updated_rows_);
  }

  const std::vector<State>& states() const { return state_; }
  void start(const std::vector<State>& states) { state_ = states; }

  // Starts the path from a guess instead of the static network: states, forces f (obeying
  // the states' force conditions strictly) and velocities v = q / dt^2 (rows of A). The
  // data at lambda = 0 are made such that (v, f) solves the step of those states exactly,
  // with every displacement condition strict by at least `margin` g: the load on the
  // balance rows is A f - M v, each closed pair's gap and each closed pair's tangential
  // offset cancel its displacement, and an open pair that would close, or a sliding pair
  // that would slip against its force, is offset to `margin` (distinct per contact, to
  // break ties). At lambda = 1 the data are the step's own. This is a homotopy of the
  // right-hand side, like Lemke's covering vector: the path from a guess near the solution
  // is short.
  void start_at(const std::vector<State>& states, const Eigen::VectorXd& f, const Eigen::VectorXd& v,
                double margin) {
    state_ = states;
    fref0_ = f;
    fref1_.setZero();
    const Eigen::SparseMatrix<double>& A = pb_.system.A;
    load0_ = A * f - v.cwiseQuotient(pb_.inverse_mass);
    load1_ = pb_.system.rhs - load0_;
    const Eigen::VectorXd u = A.transpose() * v;  // relative displacements / dt^2
    for (int k = 0; k < nc_; ++k) {
      const double m = margin * pb_.g * (1.0 + static_cast<double>(k) / nc_);
      const double gap = pb_.g_eff[k], un = u[2 * k] * dt2_, ut = u[2 * k + 1] * dt2_;
      const State s = state_[k];
      const double sgn = slip_sign(s);
      gap0_[k] = closed(s) ? -un : std::max(gap, m - un);
      tgap0_[k] = 0.0;                                               // open
      if (s == State::kStick) tgap0_[k] = -ut;                       // no slip
      else if (sgn != 0.0 && sgn * ut < m) tgap0_[k] = sgn * m - ut;  // slip s m
      gap1_[k] = gap - gap0_[k];
      tgap1_[k] = -tgap0_[k];
    }
  }

  // Turns the path into one step of a proximal iteration at lambda = 1 (the opening and the
  // load held at their final values): the reference forces move from the present ones to f
  // (a solution at the present reference) as the path parameter goes from 0 to 1. A solution
  // at fref = f has no compliance displacement, kappa (f - fref) = 0: the rigid step. The
  // states of f satisfy their conditions at 0, and the path follows their changes to 1.
  void proximal_step(const Eigen::VectorXd& f) {
    gap0_ += gap1_;
    gap1_.setZero();
    tgap0_ += tgap1_;
    tgap1_.setZero();
    load0_ += load1_;
    load1_.setZero();
    fref0_ += fref1_;
    fref1_ = f - fref0_;
  }

  // At lambda = 1: the compliance becomes kappa_new, with the reference forces shifted so
  // that forces f (a solution at lambda = 1) stay one, kappa_new (f - fref_new) =
  // kappa (f - fref): fref_new = f - (kappa / kappa_new) (f - fref). S changes on every
  // closed row, so factorize() must follow.
  void set_compliance(double kappa_new, const Eigen::VectorXd& f) {
    proximal_step(f);  // the data held at lambda = 1, fref1 = f - fref0
    fref0_ = f - (kappa_ / kappa_new) * fref1_;
    fref1_.setZero();
    kappa_ = kappa_new;
  }
  double compliance() const { return kappa_; }
  // The path's data at lambda = 1 (held there by proximal_step) with the states of a
  // solution, to go back to after a proximal path that fails.
  struct Held {
    double kappa;
    Eigen::VectorXd fref;
    std::vector<State> states;
  };
  Held held() const { return {kappa_, fref0_ + fref1_, state_}; }
  void restore(const Held& h) {
    kappa_ = h.kappa;
    fref0_ = h.fref;
    fref1_.setZero();
    state_ = h.states;
  }

  // Assembles and factorises the reduced system S of the current states. Its pattern does
  // not depend on the states (inactive entries are stored as zeros), so it is analysed once.
  bool factorize() {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(W_.nonZeros() + 6 * nc_ + 1);
    for (int j = 0; j < W_.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(W_, j); it; ++it)
        t.emplace_back(static_cast<int>(it.row()), j, active(static_cast<int>(it.row())) ? it.value() : 0.0);
    for (int k = 0; k < nc_; ++k) {
      const int rn = 2 * k, rt = rn + 1;
      const State s = state_[k];
      t.emplace_back(rn, rn, closed(s) ? kappa_ : w_);
      t.emplace_back(rt, rt, s == State::kStick ? kappa_ : w_);
      t.emplace_back(rt, rn, slip_sign(s) * mu_ * w_);
    }
    const int p = 2 * nc_;
    for (int r = 0; r < 2 * nc_; ++r) {
      if (a_p_[r] == 0.0) continue;
      t.emplace_back(r, p, active(r) ? a_p_[r] : 0.0);
      t.emplace_back(p, r, -a_p_[r]);
    }
    t.emplace_back(p, p, 1.0 / pb_.inverse_mass[n_ - 1]);
    S_.resize(2 * nc_ + 1, 2 * nc_ + 1);
    S_.setFromTriplets(t.begin(), t.end());
    S_.makeCompressed();
    base_state_ = state_;
    S_rows_ = S_;
    S_abs_ = S_.cwiseAbs();
    slot_.assign(2 * nc_, -1);
    rows_.clear();
    ++stats_factorizations_;
    return lu_.factorize(S_, reuse_pivots_);
  }

  // Contact k takes state s. That changes S in contact k's two rows only, so S = S_b + E D^T
  // with S_b the last factorised matrix, E the unit columns of the rows changed since and
  // D^T their changes, and (Woodbury)
  //     S^-1 y = z - Z C^-1 D^T z,   z = S_b^-1 y,   Z = S_b^-1 E,   C = I + D^T Z.
  // S is factorised afresh once max_updated_rows rows have changed or C is singular. A C
  // that is merely ill-conditioned is kept: with a compliance-regularised S_b its condition
  // estimate is small on most pieces without the updated solves being inaccurate, and an
  // inaccurate one is caught by the backward-error check of every solve (solve_reduced).
  bool set_state(int k, State s) {
    state_[k] = s;
    if (rows_.size() + 2 > max_updated_rows_) return factorize();
    std::vector<int> added;  // rows changed for the first time since S_b: Z's new columns
    for (const int r : {2 * k, 2 * k + 1}) {
      if (slot_[r] >= 0) continue;
      slot_[r] = static_cast<int>(rows_.size());
      rows_.push_back(r);
      added.push_back(r);
    }
    if (!added.empty()) {
      Eigen::MatrixXd E = Eigen::MatrixXd::Zero(S_.rows(), static_cast<Eigen::Index>(added.size()));
      for (std::size_t j = 0; j < added.size(); ++j) E(added[j], static_cast<Eigen::Index>(j)) = 1.0;
      lu_.solve_in_place(E);
      for (std::size_t j = 0; j < added.size(); ++j) Z_.col(slot_[added[j]]) = E.col(static_cast<Eigen::Index>(j));
    }
    for (const int r : {2 * k, 2 * k + 1}) {
      std::vector<std::pair<int, double>>& d = D_[slot_[r]];
      d.clear();
      row_entries(r, state_[k], 1.0, d);
      row_entries(r, base_state_[k], -1.0, d);
    }
    const int m = static_cast<int>(rows_.size());
    Eigen::MatrixXd C = Eigen::MatrixXd::Identity(m, m);
    for (int i = 0; i < m; ++i)
      for (const auto& [col, v] : D_[i]) C.row(i) += v * Z_.row(col).head(m);
    capacitance_.compute(C);
    if (!(capacitance_.rcond() > kMinCapacitanceRcond)) return factorize();
    return true;
  }

  int factorizations() const { return stats_factorizations_; }
  // A fresh factorisation forced by an inaccurate updated solve failed (the solution is NaN).
  bool singular() const { return singular_; }

  // x(lambda) = x0 + lambda x1 of the current states.
  void solve(Eigen::VectorXd& x0, Eigen::VectorXd& x1) {
    Columns r = Columns::Zero(n_ + 2 * nc_, kColumns);
    r.col(0).head(n_) = -load0_;
    r.col(1).head(n_) = -load1_;
    for (int k = 0; k < nc_; ++k) {
      const int rn = n_ + 2 * k, rt = rn + 1;
      if (!closed(state_[k])) continue;
      r(rn, 0) = -gap0_[k] / dt2_ + kappa_ * fref0_[2 * k];
      r(rn, 1) = -gap1_[k] / dt2_ + kappa_ * fref1_[2 * k];
      if (state_[k] == State::kStick) {
        r(rt, 0) = -tgap0_[k] / dt2_ + kappa_ * fref0_[2 * k + 1];
        r(rt, 1) = -tgap1_[k] / dt2_ + kappa_ * fref1_[2 * k + 1];
      }
    }
    const Eigen::MatrixXd x = solve_full(r);
    x0 = x.col(0);
    x1 = x.col(1);
  }

  // The contact displacements A^T (q / dt^2) of x0 and x1, which the event functions read.
  void displacements(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1) {
    u0_ = pb_.system.A.transpose() * x0.head(n_);
    u1_ = pb_.system.A.transpose() * x1.head(n_);
  }

  // Compliant slip c_t of open contact k (ft = 0) at lambda on the current piece.
  double slip(int k, double lambda) const {
    return u0_[2 * k + 1] + tgap0_[k] / dt2_ + lambda * (u1_[2 * k + 1] + tgap1_[k] / dt2_) -
           kappa_ * (fref0_[2 * k + 1] + lambda * fref1_[2 * k + 1]);
  }

  // Calls fn(a, b, scale, next) for every function a + lambda b >= 0 that contact k's
  // state requires (scale: g / dt^2 for displacements, F0 for forces), with the state the
  // contact takes where it would turn negative.
  template <class Fn>
  void for_each_condition(int k, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, Fn&& fn) const {
    const double u_scale = pb_.g / dt2_, f_scale = pb_.system.F0;
    const int in = n_ + 2 * k, it = in + 1;
    const double fn0 = x0[in], fn1 = x1[in], ft0 = x0[it], ft1 = x1[it];
    switch (state_[k]) {
      case State::kOpen:
        // compliant closing displacement c_n = u_n / dt^2 + kappa (fn - fref_n), fn = 0
        fn(u0_[2 * k] + gap0_[k] / dt2_ - kappa_ * fref0_[2 * k],
           u1_[2 * k] + gap1_[k] / dt2_ - kappa_ * fref1_[2 * k], u_scale,
           mu_ > 0.0 ? State::kStick : State::kFrictionless);
        break;
      case State::kStick:
        fn(mu_ * fn0 - ft0, mu_ * fn1 - ft1, f_scale, State::kSlideMinus);
        fn(mu_ * fn0 + ft0, mu_ * fn1 + ft1, f_scale, State::kSlidePlus);
        fn(fn0, fn1, f_scale, State::kOpen);
        break;
      case State::kSlidePlus:
      case State::kSlideMinus: {
        const double s = slip_sign(state_[k]);
        fn(fn0, fn1, f_scale, State::kOpen);
        // compliant slip c_t = u_t / dt^2 + kappa (ft - fref_t) keeps the sign s
        fn(s * (u0_[2 * k + 1] + tgap0_[k] / dt2_ + kappa_ * (ft0 - fref0_[2 * k + 1])),
           s * (u1_[2 * k + 1] + tgap1_[k] / dt2_ + kappa_ * (ft1 - fref1_[2 * k + 1])),
           u_scale, State::kStick);
        break;
      }
      case State::kFrictionless: fn(fn0, fn1, f_scale, State::kOpen); break;
    }
  }

  // The first event on the path x0 + lambda x1 from lambda_c in the direction sigma (+-1).
  Event next_event(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, double lambda_c,
                   double sigma) const {
    Event best;
    for (int k = 0; k < nc_; ++k)
      for_each_condition(k, x0, x1, [&](double a, double b, double scale, State next) {
        if (!(sigma * b < 0.0)) return;
        const double step = std::max(0.0, sigma * (-a / b - lambda_c)), rate = std::abs(b) / scale;
        if (step < best.lambda || (step == best.lambda && rate > best.rate))
          best = {step, rate, k, next};
      });
    if (best.contact >= 0) best.lambda = lambda_c + sigma * best.lambda;
    return best;
  }

  // The slope in lambda of the condition that contact k's new state frees on leaving
  // `previous`: the one whose crossing would lead back to `previous` (an open pair has one
  // condition). It is zero at the switch; its sign alone says which way the path goes on.
  double freed_slope(int k, State previous, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1) const {
    double slope = 0.0;
    bool found = false;
    for_each_condition(k, x0, x1, [&](double, double b, double scale, State next) {
      if (found) return;
      if (state_[k] == State::kOpen || next == previous ||
          (previous == State::kOpen && next == State::kOpen)) {
        slope = b / scale;
        found = true;
      }
    });
    return slope;
  }

  Eigen::VectorXd forces(const Eigen::VectorXd& x) const { return x.tail(2 * nc_); }

 private:
  // Row r of the force unknowns (fn_k at 2k, ft_k at 2k + 1) holds a kinematic condition.
  static bool active_in(int r, State s) { return r % 2 == 0 ? closed(s) : s == State::kStick; }
  bool active(int r) const { return active_in(r, state_[r / 2]); }

  // Appends sign x the entries (column, value) of row r of S with contact r / 2 in state s
  // (as factorize() assembles it; a column may appear twice, the values then add).
  void row_entries(int r, State s, double sign, std::vector<std::pair<int, double>>& out) const {
    if (active_in(r, s))
      for (Eigen::SparseMatrix<double>::InnerIterator it(W_, r); it; ++it)  // W is symmetric
        out.emplace_back(static_cast<int>(it.row()), sign * it.value());
    if (r % 2 == 0) {
      out.emplace_back(r, sign * (closed(s) ? kappa_ : w_));
    } else {
      out.emplace_back(r, sign * (s == State::kStick ? kappa_ : w_));
      out.emplace_back(r - 1, sign * slip_sign(s) * mu_ * w_);
    }
    if (a_p_[r] != 0.0 && active_in(r, s)) out.emplace_back(2 * nc_, sign * a_p_[r]);
  }

  using MatrixXld = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;

  // S^-1 Y for the columns of Y (a piece's two right-hand sides, x0 and x1, which share each
  // pass over the factors and over S) by the factors of S_b and the rows changed since (see
  // set_state), refined iteratively with residuals Y - S Z accumulated in extended precision
  // (long double, 64-bit mantissa on x86-64), so that Z is accurate to working precision
  // while cond(S) eps_double < 1. A hyperstatic sticking set leaves S only regularised by
  // the compliance, cond(S) ~ 1 / compliance; without it the forces carry errors ~1e-6 F0
  // along the set's self-stresses, and the events read from them are inconsistent
  // (docs/probe.md, "Accuracy of the pieces"). Where the componentwise backward error
  //     omega = max_i |S z - y|_i / (|S| |z| + |y|)_i
  // of a column still exceeds kMaxBackwardError, S is factorised afresh and that column
  // and the ones after it are solved and refined again (every column is the result of
  // solving the columns one after the other).
  Eigen::MatrixXd solve_reduced(const MatrixXld& Y) {
    const int cols = static_cast<int>(Y.cols());
    Eigen::MatrixXd Z = updated_solve(Y.cast<double>());
    refine(Y, Z, 0);
    if (rows_.empty()) return Z;
    const Eigen::VectorXd omega = backward_errors(Y, Z);
    int first = 0;
    while (first < cols && omega[first] <= kMaxBackwardError) ++first;
    if (first == cols) return Z;
    if (!factorize()) {
      singular_ = true;
      Z.rightCols(cols - first).setConstant(std::numeric_limits<double>::quiet_NaN());
      return Z;
    }
    Z.rightCols(cols - first) = updated_solve(Y.rightCols(cols - first).cast<double>());
    refine(Y, Z, first);
    return Z;
  }

  // Up to kRefinements steps z += S^-1 (y - S z) on the columns from `first` on, each until
  // its correction is below 1e-15 |z|.
  void refine(const MatrixXld& Y, Eigen::MatrixXd& Z, int first) const {
    std::vector<int> cols;
    for (int c = first; c < Z.cols(); ++c) cols.push_back(c);
    for (int step = 0; step < kRefinements && !cols.empty(); ++step) {
      const Eigen::MatrixXd dZ = updated_solve(residual(Y, Z, cols).cast<double>());
      std::vector<int> going_on;
      for (std::size_t j = 0; j < cols.size(); ++j) {
        auto z = Z.col(cols[j]);
        z += dZ.col(static_cast<Eigen::Index>(j));
        if (dZ.col(static_cast<Eigen::Index>(j)).lpNorm<Eigen::Infinity>() > 1e-15 * z.lpNorm<Eigen::Infinity>())
          going_on.push_back(cols[j]);
      }
      cols = std::move(going_on);
    }
  }

  // S^-1 Y by Woodbury's formula on the factors of S_b (one pass of KLU for all columns).
  Eigen::MatrixXd updated_solve(Eigen::MatrixXd Z) const {
    lu_.solve_in_place(Z);
    const int m = static_cast<int>(rows_.size());
    if (m == 0) return Z;
    for (Eigen::Index c = 0; c < Z.cols(); ++c) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(m);
      for (int i = 0; i < m; ++i)
        for (const auto& [col, v] : D_[i]) t[i] += v * Z(col, c);
      Z.col(c).noalias() -= Z_.leftCols(m) * capacitance_.solve(t);
    }
    return Z;
  }

  // The residuals Y - S Z of the columns `cols` (one or two: at most kColumns), accumulated in
  // long double.
  MatrixXld residual(const MatrixXld& Y, const Eigen::MatrixXd& Z, const std::vector<int>& cols) const {
    MatrixXld R = cols.size() == 1 ? residual_rows<1>(Y, Z, cols) : residual_rows<2>(Y, Z, cols);
    for (std::size_t j = 0; j < cols.size(); ++j)
      for (std::size_t i = 0; i < rows_.size(); ++i)
        for (const auto& [col, v] : D_[i])
          R(rows_[i], static_cast<Eigen::Index>(j)) -= static_cast<long double>(v) * Z(col, cols[j]);
    return R;
  }

  // Y - S_b Z on the columns `cols` (N of them), row by row (S_rows_), each row's N sums held
  // in extended-precision registers.
  template <int N>
  MatrixXld residual_rows(const MatrixXld& Y, const Eigen::MatrixXd& Z, const std::vector<int>& cols) const {
    MatrixXld R(Y.rows(), N);
    const int* start = S_rows_.outerIndexPtr();
    const int* col = S_rows_.innerIndexPtr();
    const double* value = S_rows_.valuePtr();
    const double* z[N];
    for (int j = 0; j < N; ++j) z[j] = Z.col(cols[j]).data();
    for (int i = 0; i < S_rows_.outerSize(); ++i) {
      long double sum[N];
      for (int j = 0; j < N; ++j) sum[j] = Y(i, cols[j]);
      for (int e = start[i]; e < start[i + 1]; ++e) {
        const long double v = value[e];
        for (int j = 0; j < N; ++j) sum[j] -= v * z[j][col[e]];
      }
      for (int j = 0; j < N; ++j) R(i, j) = sum[j];
    }
    return R;
  }

  // omega of each column of Z (see solve_reduced).
  Eigen::VectorXd backward_errors(const MatrixXld& Y, const Eigen::MatrixXd& Z) const {
    std::vector<int> cols;
    for (int c = 0; c < Z.cols(); ++c) cols.push_back(c);
    const Eigen::MatrixXd R = residual(Y, Z, cols).cast<double>();
    Eigen::VectorXd omega = Eigen::VectorXd::Zero(Z.cols());
    for (Eigen::Index c = 0; c < Z.cols(); ++c) {
      const auto z = Z.col(c);
      Eigen::VectorXd scale = S_abs_ * z.cwiseAbs() + Y.col(c).cast<double>().cwiseAbs();
      // |S| of a changed row: its entries in the present state (D holds the present entries
      // and the negated ones of S_b; |S_b| |z| over-counts the latter, which only loosens omega).
      for (std::size_t i = 0; i < rows_.size(); ++i)
        for (const auto& [col, v] : D_[i]) scale[rows_[i]] += std::abs(v * z[col]);
      for (Eigen::Index i = 0; i < R.rows(); ++i)
        if (scale[i] > 0.0) omega[c] = std::max(omega[c], std::abs(R(i, c)) / scale[i]);
        else if (R(i, c) != 0.0) omega[c] = std::numeric_limits<double>::infinity();
    }
    return omega;
  }

  // The full system K x = r, x = (v, f), for each column r of R, by the reduced one:
  // v_G = M_G^-1 (r_G + A_G f), so a kinematic row a_r^T v + (D f)_r = r_r reads
  // (a_r^T M_G^-1 A_G + D) f + a_pr v_p = r_r - a_r^T M_G^-1 r_G, and the pressure row
  // m_p v_p - a_p^T f = r_p stays as it is.
  static constexpr int kColumns = 2;  // x0's and x1's
  using Columns = Eigen::Matrix<double, Eigen::Dynamic, kColumns>;
  Eigen::MatrixXd solve_full(const Columns& R) {
    const int p = n_ - 1, cols = kColumns;
    // Y in extended precision: a_r^T M_G^-1 r_G is of the order of the loads (F0 / m),
    // the kinematic terms of g / dt^2; rounded to double, the difference would carry an
    // error that S^-1 amplifies by cond(S) (see solve_reduced).
    MatrixXld T(n_, cols);  // M_G^-1 r_G; the pressure row's entry is not eliminated
    for (int c = 0; c < cols; ++c) {
      for (int i = 0; i < n_; ++i) T(i, c) = static_cast<long double>(pb_.inverse_mass[i]) * R(i, c);
      T(p, c) = 0.0L;
    }
    MatrixXld Y = MatrixXld::Zero(2 * nc_ + 1, cols);
    const Eigen::SparseMatrix<double>& A = pb_.system.A;
    for (int j = 0; j < A.outerSize(); ++j) {
      if (!active(j)) continue;
      long double sum[kColumns] = {0.0L, 0.0L};
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) {
        const long double v = it.value();
        for (int c = 0; c < kColumns; ++c) sum[c] -= v * T(it.row(), c);
      }
      for (int c = 0; c < kColumns; ++c) Y(j, c) = sum[c];
    }
    for (int c = 0; c < cols; ++c) {
      for (int i = 0; i < 2 * nc_; ++i) Y(i, c) += R(n_ + i, c);
      Y(2 * nc_, c) = R(p, c);
    }
    const Eigen::MatrixXd Z = solve_reduced(Y);
    Eigen::MatrixXd X(n_ + 2 * nc_, cols);
    for (int c = 0; c < cols; ++c) {
      const Eigen::VectorXd f = Z.col(c).head(2 * nc_);
      X.col(c).tail(2 * nc_) = f;
      X.col(c).head(n_) = pb_.inverse_mass.cwiseProduct(R.col(c).head(n_) + A * f);
      X(p, c) = Z(2 * nc_, c);
    }
    return X;
  }

  std::size_t max_updated_rows_;
  const CdStepProblem& pb_;
  int n_, nc_;
  double mu_, dt2_, kappa_, w_ = 1.0;
  Eigen::VectorXd u0_, u1_;
  // The path's data, linear in its parameter lambda: g_eff = gap0 + lambda gap1, the load
  // on the balance rows load0 + lambda load1, the compliance's reference fref0 + lambda fref1.
  // tangential offset of closed pairs tgap0 + lambda tgap1 (zero in the step itself; a
  // start from a guess uses it, see start_at).
  Eigen::VectorXd gap0_, gap1_, tgap0_, tgap1_, load0_, load1_, fref0_, fref1_;
  std::vector<State> state_;
  Eigen::SparseMatrix<double> W_;  // A_G^T M_G^-1 A_G: the Delassus operator of the grains
  Eigen::VectorXd a_p_;            // the pressure row of A
  Eigen::SparseMatrix<double> S_;  // S_b: the matrix last factorised
  mutable KluFactor lu_;
  bool reuse_pivots_ = true;
  // The rows changed since S_b (see set_state): their slots, Z = S_b^-1 E, D^T, C's LU.
  static constexpr double kMinCapacitanceRcond = 0.0;  // i.e. only a singular C
  std::vector<State> base_state_;
  std::vector<int> slot_;
  std::vector<int> rows_;
  Eigen::MatrixXd Z_;
  std::vector<std::vector<std::pair<int, double>>> D_;
  Eigen::PartialPivLU<Eigen::MatrixXd> capacitance_;
  int stats_factorizations_ = 0;
  bool singular_ = false;
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  RowMatrix S_rows_;                   // S_b by rows (the residual's sums)
  Eigen::SparseMatrix<double> S_abs_;  // |S_b|, entrywise
  static constexpr double kMaxBackwardError = 1e-14;
  static constexpr int kRefinements = 2;  // extended-precision refinement steps per solve
};

// A 64-bit hash of the state set and the direction (collisions: ~pieces^2 / 2^64).
std::size_t state_key(const std::vector<State>& states, double sigma) {
  std::string key(states.size() + 1, '\0');
  for (std::size_t k = 0; k < states.size(); ++k) key[k] = static_cast<char>(states[k]);
  key.back() = sigma > 0.0 ? '+' : '-';
  return std::hash<std::string>{}(key);
}


// The pieces a probe has taken over all its paths, against CdPathSettings::max_probe_pieces.
struct PieceBudget {
  long long used = 0, limit = 0;  // limit 0: none
  bool spent() const { return limit > 0 && used > limit; }
};

// Follows the path from a solution at lambda = 0 (the current states, x0 and x1 solved) to
// lambda = 1 by parametric principal pivoting; false where it fails (stats.failure says why).
// Every piece is counted in `budget`; the piece past its limit is not taken (failure
// "budget"). With stall_pieces > 0 the path is cut where lambda has not passed the largest
// value it reached for that many pieces (failure "stall"; CdPathSettings::interior_states_stall).
// Polls `cancel` (may be empty) before every piece and throws Cancelled once it holds.
bool follow_path(StepPath& path, const CdStepProblem& pb, const CdPathSettings& ps, Eigen::VectorXd& x0,
                 Eigen::VectorXd& x1, CdPathStats& stats, PieceBudget& budget, const std::function<bool()>& cancel,
                 int stall_pieces = 0) {
  const int max_pieces = ps.max_pieces > 0 ? ps.max_pieces : 50 * pb.num_contacts() + 1000;
  // sigma = -1 where the path turns back in lambda (a fold: the step has several solutions
  // there, as the dynamics from rest would pass them by).
  double lambda = 0.0, sigma = 1.0;
  std::unordered_set<std::size_t> visited;
  const std::size_t start_key = state_key(path.states(), sigma);
  stats.lambda_max = 0.0;
  int last_growth = 0;  // the piece on which lambda last passed lambda_max
  while (true) {
    if (cancel && cancel()) throw Cancelled();
    const Event e = path.next_event(x0, x1, lambda, sigma);
    if (e.contact < 0 && sigma < 0.0) {  // a ray: no solution on this path
      stats.failure = "ray";
      return false;
    }
    if (e.contact < 0 || (sigma > 0.0 && e.lambda >= 1.0)) {
      stats.lambda_max = 1.0;
      return true;
    }
    // The path comes back to a state set it has left. Where that is the start's, with the
    // start's direction, the branch of solutions through the start is a closed curve: it
    // turns back at a fold below lambda = 1 (stats.lambda_max) and returns through lambda < 0
    // to the start from the other side ("loop"; docs/probe.md, "Why a path fails"). Elsewhere
    // the pivoting cycles at a degenerate point, several conditions tight at one lambda.
    ++budget.used;
    if (budget.spent()) {
      stats.failure = "budget";
      return false;
    }
    const std::size_t key = state_key(path.states(), sigma);
    if (++stats.pieces > max_pieces || !visited.insert(key).second) {
      stats.failure = stats.pieces > max_pieces ? "pieces" : key == start_key ? "loop" : "cycle";
      return false;
    }
    if (e.lambda > stats.lambda_max) {
      stats.lambda_max = e.lambda;
      last_growth = stats.pieces;
    } else if (stall_pieces > 0 && stats.pieces - last_growth > stall_pieces) {
      stats.failure = "stall";
      return false;
    }
    if (e.lambda == lambda) ++stats.degenerate;
    lambda = e.lambda;
    const State previous = path.states()[e.contact];
    // The contact crosses into the neighbouring piece of Coulomb's law: the cone's edge
    // (stick <-> slide), the pair opening while sliding (slide <-> open) or closing, where
    // it slides along its slip at closure. Where that piece's conditions do not hold beyond
    // lambda, the path turns back in lambda (Lemke's rule: the path is one curve).
    State next = e.next;
    if (previous == State::kOpen && pb.system.mu > 0.0)
      next = path.slip(e.contact, lambda) >= 0.0 ? State::kSlidePlus : State::kSlideMinus;
    if (!path.set_state(e.contact, next)) {
      stats.failure = "singular";
      return false;
    }
    path.solve(x0, x1);
    if (path.singular()) {
      stats.failure = "singular";
      return false;
    }
    path.displacements(x0, x1);
    if (sigma * path.freed_slope(e.contact, previous, x0, x1) < 0.0) sigma = -sigma;
  }
}

// The states of a guess, and its forces made to obey them strictly: a touching pair (or the
// probed one) is closed where the guess says so (CdStepGuess::closed), else where fn is above
// 1e-7 F0 (the lp probe's state tolerance), otherwise open with f = 0; a closed pair slides
// against its force (ft = -s mu fn) where the guess says so (CdStepGuess::sliding), else where
// it is within 1e-7 F0 of the cone's edge, otherwise it sticks. The path then starts at the
// guess (StepPath::start_at).
void start_from_guess(StepPath& path, const CdStepProblem& pb, const CdStepGuess& guess, double margin) {
  const int nc = pb.num_contacts();
  const double mu = pb.system.mu, F0 = pb.system.F0, dt2 = pb.dt * pb.dt;
  std::vector<State> states(nc, State::kOpen);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * nc);
  const bool read = !guess.closed.empty();  // the guess's own states (CdStepGuess)
  for (int k = 0; k < nc; ++k) {
    const double fn = guess.f[2 * k], ft = guess.f[2 * k + 1];
    const std::size_t ks = static_cast<std::size_t>(k);
    const bool touching = read ? guess.closed[ks] : fn > 1e-7 * F0;
    if (!(k == pb.probed || (touching && pb.g_eff[k] <= 0.0))) continue;
    f[2 * k] = std::max(fn, 1e-9 * F0);
    if (mu == 0.0) {
      states[k] = State::kFrictionless;
    } else if (read ? guess.sliding[ks] : mu * f[2 * k] - std::abs(ft) <= 1e-7 * F0) {
      states[k] = ft > 0.0 ? State::kSlideMinus : State::kSlidePlus;
      f[2 * k + 1] = -slip_sign(states[k]) * mu * f[2 * k];
    } else {
      states[k] = State::kStick;
      f[2 * k + 1] = ft;
    }
  }
  path.start_at(states, f, guess.q / dt2, margin);
}

// The step followed at compliance `compliance` from the static network or from `guess`, then
// brought to the rigid step at compliance `rigid` (both as fractions of g / (dt^2 F0), see
// CdPathSettings); f empty where the first path fails. stall_pieces: the first path's cut where
// it stops gaining ground (follow_path). Every path polls `cancel` (follow_path).
CdStepSolution follow(const CdStepProblem& pb, const Packing& packing, const CdPathSettings& ps,
                      const CdStepGuess* guess, double compliance, double rigid, CdPathStats& stats,
                      PieceBudget& budget, const std::function<bool()>& cancel, int stall_pieces = 0) {
  const int nc = pb.num_contacts(), contact = pb.probed;
  const double F0 = pb.system.F0, dt2 = pb.dt * pb.dt;
  // A compliance of CdPathSettings (a fraction of g / (dt^2 F0)) as kappa, and back.
  const auto kappa_of = [&](double c) { return c * pb.g / (dt2 * F0); };
  const auto compliance_of = [&](double kappa) { return kappa * dt2 * F0 / pb.g; };
  // The static network, its tangential forces drawn into the cone's interior by distinct
  // relative amounts ~1e-9: a contact at the cone's edge (fully mobilised) starts sticking
  // and its event happens at its own lambda, so that no two events tie at lambda = 0. The
  // path starts from that network's own balance A f0 (the balance rows' lambda term).
  Eigen::VectorXd f0 = packing_forces(packing, pb.system);
  for (int k = 0; k < nc; ++k) f0[2 * k + 1] *= 1.0 - 1e-9 * (1.0 + static_cast<double>(k) / nc);
  StepPath path(pb, f0, kappa_of(compliance), ps.max_updated_rows);

  if (guess) {
    start_from_guess(path, pb, *guess, ps.guess_margin);
  } else {
    // The static network: loaded pairs closed (sticking), every other pair open.
    std::vector<State> start(nc, State::kOpen);
    for (int k = 0; k < nc; ++k)
      if ((f0[2 * k] > 0.0 && pb.g_eff[k] <= 0.0) || k == contact)
        start[k] = pb.system.mu > 0.0 ? State::kStick : State::kFrictionless;
    path.start(start);
  }

  CdStepSolution sol;
  Eigen::VectorXd x0, x1;
  if (!path.factorize()) {
    stats.failure = "singular";
    return sol;
  }
  path.solve(x0, x1);
  path.displacements(x0, x1);
  if (!follow_path(path, pb, ps, x0, x1, stats, budget, cancel, stall_pieces)) {
    stats.factorizations += path.factorizations();
    return sol;
  }

  // lambda = 1. The compliance's own displacements (kappa dt^2 |f - f0|, ~ compliance g)
  // are removed by proximal steps: the reference forces move to the solution, along a path
  // of their own (StepPath::proximal_step), while that lowers the step's residual. A path
  // followed at a compliance above `rigid` (CdPathStart::compliant) first lowers it by
  // ps.compliance_factor per proximal step down to `rigid`, from the latest solution on
  // (StepPath::set_compliance); the lowest residual met is kept.
  sol.f = path.forces(x0 + x1);
  sol.residual = cd_step_residual(pb, sol.f);
  // Forces that have lost their digits (CdPathSettings::lost_factor) are not lowered.
  if (ps.lost_factor > 0.0 &&
      !(sol.residual.max() <= ps.lost_factor * std::max(compliance_of(path.compliance()), 1e-3))) {
    stats.failure = "lost";
    stats.factorizations += path.factorizations();
    return CdStepSolution{};
  }
  std::vector<State> states = path.states();  // those of sol.f
  Eigen::VectorXd f_latest = sol.f;  // the latest solution (the next proximal step's reference)
  // Lowered far enough: a residual of 1e-3 of the exact one, or an exact one at or below the
  // compliance where the user takes the forces as settled (CdPathSettings::settle_compliance).
  const auto settled = [&] {
    return sol.residual.max() <= kExactStepTolerance &&
           path.compliance() <= kappa_of(ps.settle_compliance) * (1.0 + 1e-12);
  };
  const auto exact_enough = [&] { return sol.residual.max() <= 1e-3 * kExactStepTolerance || settled(); };
  // Keeps forces f (the path's present solution) where they lower the residual.
  const auto keep_if_better = [&](const Eigen::VectorXd& f) {
    const CdStepResidual res = cd_step_residual(pb, f);
    if (!(res.max() < sol.residual.max())) return false;
    sol.f = f;
    sol.residual = res;
    states = path.states();
    return true;
  };
  // One proximal path from f_latest at the present compliance; false (and why in `failure`)
  // where it does not reach its end.
  std::string failure;
  const auto proximal_path = [&] {
    path.proximal_step(f_latest);
    path.solve(x0, x1);
    path.displacements(x0, x1);
    ++stats.refinements;
    CdPathStats proximal;
    const bool reached = follow_path(path, pb, ps, x0, x1, proximal, budget, cancel);
    stats.pieces += proximal.pieces;
    stats.degenerate += proximal.degenerate;
    failure = proximal.failure;
    return reached;
  };

  // The compliance lowered to `rigid` (CdPathStart::compliant; nothing to do otherwise). A
  // lowering whose proximal path fails is taken again from the latest solution with the
  // factor's square root (a smaller step), up to ps.lowering_retries times in a row.
  const double kappa_rigid = kappa_of(rigid);
  double factor = ps.compliance_factor;
  int failed = 0;
  bool given_up = false;
  StepPath::Held held = path.held();
  while (!exact_enough() && path.compliance() > kappa_rigid * (1.0 + 1e-12)) {
    path.set_compliance(std::max(kappa_rigid, factor * path.compliance()), f_latest);
    ++stats.lowerings;
    const bool factorized = path.factorize();
    if (factorized && proximal_path()) {
      f_latest = path.forces(x0 + x1);
      held = path.held();
      failed = 0;
      factor = ps.compliance_factor;
      keep_if_better(f_latest);
    } else if (factorized && !budget.spent() && ++failed <= ps.lowering_retries) {
      path.restore(held);
      factor = std::sqrt(factor);
    } else {  // the lowering stops here (probe_cd_path restarts below it)
      stats.failure = factorized ? failure : "singular";
      stats.compliance_end = compliance_of(path.compliance());
      given_up = true;
      break;
    }
  }
  // At the rigid compliance: proximal steps while they lower the residual.
  for (int r = 0; !given_up && r < ps.refinements && !exact_enough(); ++r) {
    if (!proximal_path()) break;
    f_latest = path.forces(x0 + x1);
    if (!keep_if_better(f_latest)) break;
  }
  // Ended by the settle rule (not by a residual of 1e-3 of the exact one).
  if (!given_up && settled() && sol.residual.max() > 1e-3 * kExactStepTolerance)
    stats.compliance_settled = compliance_of(path.compliance());
  stats.factorizations += path.factorizations();
  for (int k = 0; k < nc; ++k) {
    if (states[k] == State::kOpen && k != contact) ++stats.open;
    if (states[k] == State::kSlidePlus || states[k] == State::kSlideMinus) ++stats.sliding;
  }
  return sol;
}

}  // namespace

namespace {

// A probe's field as the step's displacement q: each grain's displacement and rotation times
// radius, and the cell's lambda dt in the pressure row (the order of pb's system).
Eigen::VectorXd step_displacements(const Packing& packing, const CdStepProblem& pb, const ProbeResult& r) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(pb.system.A.rows());
  for (std::size_t i = 0; i < pb.system.grains.size(); ++i) {
    const int id = pb.system.grains[i];
    q[3 * i] = r.u[id].x();
    q[3 * i + 1] = r.u[id].y();
    q[3 * i + 2] = r.u_rot[id] * packing.particles.radius[id];
  }
  q[pb.system.pressure_row()] = r.lambda_dt;
  return q;
}

}  // namespace

CdStepGuess lp_optimum_guess(const Packing& packing, const CdStepProblem& pb, const ProbeSettings& settings) {
  KinematicProbeSettings ks;
  ks.g = pb.g;
  ks.model = settings.model;  // the model of the step (build_cd_step)
  KinematicProbe probe(packing, ks);
  // The step's system holds every contact of the packing in order (build_cd_step), so a
  // packing contact's index is its position there.
  const ProbeResult r = probe.probe(pb.probed);
  const ForceNetwork net = probe.network();
  const EquilibriumSystem& sys = probe.system();
  CdStepGuess guess;
  guess.f = Eigen::VectorXd::Zero(2 * pb.num_contacts());
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const int kc = sys.contacts[k];
    guess.f[2 * kc] = net.fn[k];
    guess.f[2 * kc + 1] = sys.mu > 0.0 ? net.ft[k] : 0.0;
  }
  guess.q = step_displacements(packing, pb, r);
  return guess;
}

// Two restarts of the continuation whose lambda_max / compliance agree within this (relative)
// are one path scaled (probe_cd_path).
constexpr double kScaledRestartTolerance = 0.01;

namespace {

// The interior-point method's iterates for CdPathStart::interior_point (docs/probe.md, "An
// interior-point start", "Keeping the iterates centred"): plain Mehrotra's and, where it ends
// above interior_again_above with interior_neighbourhood on, the second run's in the wide
// neighbourhood. `start` is the one with the lower natural residual, `other` the one left.
struct InteriorIterates {
  InteriorPointResult start;
  std::optional<InteriorPointResult> other;
  bool again_kept = false;  // the second run's iterate is the start
  const InteriorPointResult& plain() const { return other && again_kept ? *other : start; }
  const InteriorPointResult* again() const { return !other ? nullptr : again_kept ? &start : &*other; }
};

InteriorIterates interior_iterates(const CdStepProblem& pb, const CdPathSettings& ps) {
  if (!(ps.interior_compliance > 0.0) || !(ps.interior_rigid > 0.0) || ps.interior_rigid > ps.interior_compliance)
    throw Error("cd path: interior_compliance and interior_rigid must be > 0, interior_rigid <= interior_compliance (got " +
                std::to_string(ps.interior_compliance) + ", " + std::to_string(ps.interior_rigid) + ")");
  if (ps.interior_path_pieces < 1)
    throw Error("cd path: interior_path_pieces must be >= 1 (got " + std::to_string(ps.interior_path_pieces) + ")");
  if (!(ps.interior_states_pieces >= 0.0) || !std::isfinite(ps.interior_states_pieces))
    throw Error("cd path: interior_states_pieces must be >= 0 (got " + std::to_string(ps.interior_states_pieces) + ")");
  if (ps.interior_states_retries < 0)
    throw Error("cd path: interior_states_retries must be >= 0 (got " + std::to_string(ps.interior_states_retries) + ")");
  if (ps.interior_states_stall < 0)
    throw Error("cd path: interior_states_stall must be >= 0 (got " + std::to_string(ps.interior_states_stall) + ")");
  if (!(ps.interior_neighbourhood >= 0.0 && ps.interior_neighbourhood < 1.0))
    throw Error("cd path: interior_neighbourhood must be in [0, 1) (got " + std::to_string(ps.interior_neighbourhood) + ")");
  if (!(ps.interior_again_above >= 0.0))
    throw Error("cd path: interior_again_above must be >= 0 (got " + std::to_string(ps.interior_again_above) + ")");
  InteriorPointSettings is;
  is.velocity_scale = pb.g / (pb.dt * pb.dt);
  is.max_iterations = ps.interior_max_iterations;
  InteriorIterates it{interior_point_step(pb, is), std::nullopt, false};
  // Plain Mehrotra may drive a few pairs to the boundary ahead of the others and stall far
  // from a solution; the wide neighbourhood prevents that, but on other probes it ends
  // further away than plain Mehrotra does.
  if (ps.interior_neighbourhood > 0.0 && it.start.natural_residual > ps.interior_again_above) {
    is.neighbourhood = ps.interior_neighbourhood;
    it.other = interior_point_step(pb, is);
    it.again_kept = it.other->natural_residual < it.start.natural_residual;
    if (it.again_kept) std::swap(it.start, *it.other);
  }
  return it;
}

// The interior-point method's runs, as CdPathStats reports them.
void record_interior(const InteriorIterates& it, CdPathStats& stats) {
  stats.interior_iterations = it.plain().iterations;
  stats.interior_residual = it.plain().natural_residual;
  if (const InteriorPointResult* again = it.again()) {
    stats.interior_again_iterations = again->iterations;
    stats.interior_again_short_steps = again->short_steps;
    stats.interior_again_residual = again->natural_residual;
    stats.interior_again_kept = it.again_kept;
  }
}

// probe_cd_path on its step pb (build_cd_step) from ps.start alone; for the interior-point
// start, from `iterate` (of interior_iterates: other_iterate where it is not the start).
CdStepSolution probe_from_start(const Packing& packing, const CdStepProblem& pb, const ProbeSettings& settings,
                                const CdPathSettings& ps, CdPathStats* stats_out,
                                const InteriorPointResult* iterate = nullptr, bool other_iterate = false,
                                const CdStepGuess* from = nullptr) {
  if (ps.start == CdPathStart::lp_optimum && settings.window > 0.0)
    throw Error("cd path: the lp optimum's start is the whole packing's; it does not go with a window");
  CdStepGuess start_guess;  // the lp optimum or the interior-point iterate
  const CdStepGuess* guess = from;  // a guess of the caller's (the inertial start's stages)
  if (ps.start == CdPathStart::lp_optimum) {
    start_guess = lp_optimum_guess(packing, pb, settings);
    guess = &start_guess;
  }
  if (ps.start == CdPathStart::interior_point) {
    if (!iterate) throw Error("cd path: the interior-point start needs its iterate");
    start_guess = {iterate->f, iterate->q, iterate->closed, iterate->sliding};
    guess = &start_guess;
  }
  // The compliance trades the conditioning of the sticking set's system against its own
  // displacements; where the path at ps.compliance is not exact, it is followed again at ten
  // times it, then a tenth of it, and the solution with the lowest residual is kept.
  // The compliant continuation fails where its lowering stops at a compliance c: the
  // proximal paths there close on themselves, i.e. the branch of soft solutions it follows
  // turns back in the compliance. It is then followed afresh from the static network at
  // c / restart_divisor, whose path reaches a solution on another branch, and lowered from
  // there (docs/probe.md, "Where the path starts").
  const bool soft = ps.start == CdPathStart::compliant && ps.compliant_start > ps.compliance;
  if (soft && !(ps.restart_divisor > 1.0))
    throw Error("cd path: restart_divisor must be > 1 (got " + std::to_string(ps.restart_divisor) + ")");
  if (soft && ps.lowering_retries < 0)
    throw Error("cd path: lowering_retries must be >= 0 (got " + std::to_string(ps.lowering_retries) + ")");
  if (soft && ps.softer_starts < 0)
    throw Error("cd path: softer_starts must be >= 0 (got " + std::to_string(ps.softer_starts) + ")");
  if (soft && ps.softer_starts > 0 && !(ps.softer_factor > 1.0))
    throw Error("cd path: softer_factor must be > 1 (got " + std::to_string(ps.softer_factor) + ")");
  if (ps.max_probe_pieces < 0)
    throw Error("cd path: max_probe_pieces must be >= 0 (got " + std::to_string(ps.max_probe_pieces) + ")");
  if (!(ps.accept_residual >= kExactStepTolerance && ps.accept_residual <= kMaxPathResidual))
    throw Error("cd path: accept_residual must be in [" + std::to_string(kExactStepTolerance) + ", " +
                std::to_string(kMaxPathResidual) + "] g (got " + std::to_string(ps.accept_residual) + ")");
  if (!(ps.settle_compliance >= 0.0 && std::isfinite(ps.settle_compliance)))
    throw Error("cd path: settle_compliance must be >= 0 and finite (got " + std::to_string(ps.settle_compliance) + ")");
  if (!(ps.lost_factor >= 0.0 && std::isfinite(ps.lost_factor)))
    throw Error("cd path: lost_factor must be >= 0 and finite (got " + std::to_string(ps.lost_factor) + ")");
  if (!(ps.restart_floor >= 0.0 && std::isfinite(ps.restart_floor)))
    throw Error("cd path: restart_floor must be >= 0 and finite (got " + std::to_string(ps.restart_floor) + ")");
  PieceBudget budget{0, ps.max_probe_pieces};
  CdStepSolution best;
  CdPathStats best_stats;
  // From the interior-point iterate (docs/probe.md, "An interior-point start"): first from its
  // own states (InteriorPointResult::closed, sliding) at interior_compliance, lowered to
  // interior_rigid, that path cut at interior_states_pieces x (number of contacts) pieces or
  // where it stalls, and where it is not exact again at 10, 100, ... times interior_compliance
  // (interior_states_retries of them); then from the states of its forces, at
  // interior_compliance, and the retry of that at 10 times both compliances, each path at most
  // interior_path_pieces x (number of contacts) pieces (a path from a guess near the solution
  // is short; one that wanders is cut, and the compliant continuation follows).
  const bool from_interior = ps.start == CdPathStart::interior_point;
  const double compliances[] = {ps.compliance, 10.0 * ps.compliance, 0.1 * ps.compliance};  // static, lp
  const bool states_first = from_interior && ps.interior_states_pieces > 0.0;
  CdStepGuess forces_guess;  // the iterate's forces, their states read by tolerances
  if (from_interior) forces_guess = {start_guess.f, start_guess.q, {}, {}};
  const int states_attempts = states_first ? 1 + ps.interior_states_retries : 0;
  const int first_retry = states_attempts + 1;  // the attempts from here on are retries
  const int attempts = soft ? 1 + std::max(0, ps.max_restarts) : from_interior ? first_retry + 1 : 3;
  // The continuation's starting compliances: compliant_start, then softer ones (softer_factor
  // times the one before) where it ends without an exact solution (docs/probe.md, "Where the
  // path starts").
  const int starts = soft && ps.retry ? 1 + ps.softer_starts : 1;
  std::vector<CdPathAttempt> paths;
  const auto exact = [&] { return best.f.size() > 0 && best.residual.max() <= kExactStepTolerance; };
  // Good enough to end the search: exact, or within the residual the user accepts.
  const auto enough = [&] { return best.f.size() > 0 && best.residual.max() <= ps.accept_residual; };
  for (int from = 0; from < starts && !enough() && !budget.spent(); ++from) {
    double start = ps.compliant_start * std::pow(ps.softer_factor, from);  // soft: the next path's compliance
    double scaled = 0.0;  // lambda_max / compliance of the last restart that stopped short of lambda = 1
    for (int attempt = 0; attempt < attempts; ++attempt) {
      if (attempt >= first_retry && (!ps.retry || (soft && !(start > ps.compliance)))) break;
      // below restart_floor a restart is not followed: the next softer start is
      if (soft && attempt >= first_retry && start < ps.restart_floor) break;
      if (attempt > 0 && budget.spent()) break;
      CdPathStats stats;
      CdPathSettings at = ps;
      const CdStepGuess* from_guess = guess;
      double path_compliance = at.compliance;
      const bool iterate_states = attempt < states_attempts;  // interior: from the iterate's own states
      if (from_interior) {
        const double scale = attempt == first_retry ? 10.0 : 1.0;
        at.compliance = ps.interior_rigid * scale;
        path_compliance = ps.interior_compliance * (iterate_states ? std::pow(10.0, attempt) : scale);
        const int nc = pb.num_contacts();
        const int cap = iterate_states ? std::max(1, static_cast<int>(std::ceil(ps.interior_states_pieces * nc)))
                                       : std::max(1, ps.interior_path_pieces * nc);
        at.max_pieces = ps.max_pieces == 0 ? cap : ps.max_pieces;
        if (iterate_states) at.max_pieces = std::min(at.max_pieces, cap);  // its cut holds under any max_pieces
        else from_guess = &forces_guess;
      } else if (soft) {
        path_compliance = start;
      } else {
        at.compliance = compliances[attempt];
        path_compliance = at.compliance;
      }
      const int stall = iterate_states ? ps.interior_states_stall : 0;
      const double cpu_start = thread_cpu_seconds();
      CdStepSolution sol =
          follow(pb, packing, at, from_guess, path_compliance, at.compliance, stats, budget, settings.cancel, stall);
      paths.push_back({path_compliance, stats.compliance_end, stats.lambda_max,
                       sol.f.size() > 0 ? sol.residual.max() : kNoSolution, stats.pieces, stats.lowerings,
                       stats.failure, iterate_states, other_iterate, stats.compliance_settled, stats.factorizations,
                       thread_cpu_seconds() - cpu_start});
      // restart_divisor below where this lowering stopped (or this path's start, where it failed),
      // never below the rigid compliance itself: a path there is the static start's.
      if (soft)
        start = std::max((stats.compliance_end > 0.0 ? stats.compliance_end : start) / ps.restart_divisor, ps.compliance);
      const bool better = sol.f.size() > 0 && (best.f.size() == 0 || sol.residual.max() < best.residual.max());
      if (better || paths.size() == 1) {
        best = std::move(sol);
        best_stats = stats;
      }
      if (enough()) break;
      // A restart below a path that lost its digits would be stiffer still: the next softer
      // start is followed instead (CdPathSettings::lost_factor).
      if (soft && stats.failure == "lost") break;
      // Where the static network sticks, a restart's path is the one before it scaled: it
      // stops at lambda_max proportional to its compliance (forces ~ lambda / compliance; docs/
      // probe.md, "Where the path starts"). Two restarts in a row so, and the ones below would
      // repeat them: the next starting compliance is tried instead.
      if (soft && ps.softer_starts > 0 && attempt > 0) {
        const double ratio = stats.lambda_max < 1.0 ? stats.lambda_max / path_compliance : 0.0;
        if (ratio > 0.0 && scaled > 0.0 && std::abs(ratio / scaled - 1.0) <= kScaledRestartTolerance) break;
        scaled = ratio;
      }
    }
  }
  best_stats.pieces_all = budget.used;
  best_stats.budget_spent = budget.spent();
  // The budget stopped the probe short of an exact solution: that is why it has none.
  if (best_stats.budget_spent && !exact()) best_stats.failure = "budget";
  best_stats.paths = std::move(paths);
  best_stats.attempts = int(best_stats.paths.size());
  best_stats.restarts = soft ? best_stats.attempts - 1 : 0;  // every attempt after the first
  // A path that ends on a nearly singular state set returns forces far from any solution;
  // those are no solution, not a probe to average.
  if (best.f.size() > 0 && !(best.residual.max() <= kMaxPathResidual)) {
    best.f.resize(0);
    best_stats.failure = "inexact";
  }
  best.result = cd_step_result(pb, packing, settings, best.f);
  best.result.sweeps = best_stats.pieces_all;
  if (stats_out) *stats_out = best_stats;
  return best;
}

}  // namespace

// The interior-point start is followed, where its paths find no exact solution (with friction
// the path from the iterate may close on itself; docs/probe.md, "An interior-point start"), by
// the paths from its other iterate where it ran twice ("Keeping the iterates centred"), then by
// the compliant continuation, each within what is left of the budget; the lowest residual is
// kept and every path is listed.
namespace {

// With continuation false, the interior-point start's paths only, without the compliant
// continuation that follows them (the inertial start's stages).
CdStepSolution probe_cd_direct(const Packing& packing, int contact, const ProbeSettings& settings,
                               const CdPathSettings& ps, CdPathStats* stats_out, bool continuation = true) {
  const CdStepProblem pb = build_cd_step(packing, contact, settings);
  std::optional<InteriorIterates> iterates;
  const double interior_cpu_start = thread_cpu_seconds();
  if (ps.start == CdPathStart::interior_point) iterates = interior_iterates(pb, ps);
  const double interior_cpu = thread_cpu_seconds() - interior_cpu_start;
  CdPathStats kept;
  CdStepSolution sol = probe_from_start(packing, pb, settings, ps, &kept, iterates ? &iterates->start : nullptr);
  if (iterates) {
    std::vector<CdPathAttempt> paths = kept.paths;
    long long used = kept.pieces_all;
    bool spent = kept.budget_spent;
    const auto residual = [](const CdStepSolution& x) { return x.f.size() > 0 ? x.residual.max() : kNoSolution; };
    // Where not exact yet: the paths from `iterate` (or the compliant continuation), within
    // what is left of the budget; the lower residual is kept.
    const auto follow_on = [&](CdPathSettings at, const InteriorPointResult* iterate) {
      if (residual(sol) <= ps.accept_residual || spent) return;
      if (ps.max_probe_pieces > 0) at.max_probe_pieces = std::max(1LL, ps.max_probe_pieces - used);
      CdPathStats next;
      CdStepSolution alt = probe_from_start(packing, pb, settings, at, &next, iterate, iterate != nullptr);
      paths.insert(paths.end(), next.paths.begin(), next.paths.end());
      used += next.pieces_all;
      spent = next.budget_spent;
      if (residual(alt) < residual(sol)) {
        sol = std::move(alt);
        kept = std::move(next);
      }
    };
    if (iterates->other) follow_on(ps, &*iterates->other);
    CdPathSettings compliant = ps;
    compliant.start = CdPathStart::compliant;
    if (continuation) follow_on(compliant, nullptr);
    kept.paths = std::move(paths);
    kept.attempts = static_cast<int>(kept.paths.size());
    kept.pieces_all = used;
    kept.budget_spent = spent;
    record_interior(*iterates, kept);
    kept.interior_cpu_seconds = interior_cpu;
    sol.result.sweeps = kept.pieces_all;
  }
  kept.accepted = sol.f.size() > 0 && !sol.result.converged && !kept.budget_spent &&
                  sol.residual.max() <= ps.accept_residual;
  if (stats_out) *stats_out = std::move(kept);
  return sol;
}

// The solution `sol` of step pb as the start of a path on a step of the same contacts and
// grains (another dt): its forces and the grains' displacements (q: peculiar displacement,
// rotation times radius, the cell's lambda dt), as lp_optimum_guess reads the lp optimum.
CdStepGuess solution_guess(const Packing& packing, const CdStepProblem& pb, const CdStepSolution& sol) {
  CdStepGuess guess;
  guess.f = sol.f;
  guess.q = step_displacements(packing, pb, sol.result);
  return guess;
}

// CdPathStart::inertial (CdPathSettings::inertial_factor and the settings after it; docs/probe.md,
// "The quasi-static step as the limit of vanishing inertia"): the step at more inertia by the
// interior-point start, continued in dt to the probe's own, then the interior-point start at
// the probe's dt where the continuation does not get there.
CdStepSolution probe_cd_inertial(const Packing& packing, int contact, const ProbeSettings& settings,
                                 const CdPathSettings& ps, CdPathStats* stats_out) {
  if (!(ps.inertial_factor > 1.0) || !std::isfinite(ps.inertial_factor))
    throw Error("cd path: inertial_factor must be > 1 (got " + std::to_string(ps.inertial_factor) + ")");
  if (ps.inertial_stages < 1)
    throw Error("cd path: inertial_stages must be >= 1 (got " + std::to_string(ps.inertial_stages) + ")");
  if (ps.inertial_halvings < 0)
    throw Error("cd path: inertial_halvings must be >= 0 (got " + std::to_string(ps.inertial_halvings) + ")");
  if (ps.inertial_retries < 0)
    throw Error("cd path: inertial_retries must be >= 0 (got " + std::to_string(ps.inertial_retries) + ")");
  if (!(ps.interior_share > 0.0 && ps.interior_share < 1.0))
    throw Error("cd path: interior_share must be in (0, 1) (got " + std::to_string(ps.interior_share) + ")");
  if (ps.inertial_jumps < 0)
    throw Error("cd path: inertial_jumps must be >= 0 (got " + std::to_string(ps.inertial_jumps) + ")");
  CdPathStats all;
  std::vector<CdPathAttempt> paths;
  long long used = 0;
  const auto exact = [](const CdStepSolution& x) { return x.f.size() > 0 && x.residual.max() <= kExactStepTolerance; };
  // Each stage within what is left of the budget; its paths listed with their dt (0: the
  // probe's own). The returned stage's statistics are the probe's, its paths all of them.
  const auto account = [&](CdPathStats& st, double dt) {
    for (CdPathAttempt& a : st.paths) a.dt = dt == settings.dt ? 0.0 : dt;
    paths.insert(paths.end(), st.paths.begin(), st.paths.end());
    used += st.pieces_all;
    all.budget_spent = all.budget_spent || st.budget_spent;
  };
  const auto budgeted = [&](CdPathSettings at) {
    if (ps.max_probe_pieces > 0) at.max_probe_pieces = std::max(1LL, ps.max_probe_pieces - used);
    return at;
  };
  const auto spent = [&] { return all.budget_spent || (ps.max_probe_pieces > 0 && used >= ps.max_probe_pieces); };
  CdPathSettings interior = ps;
  interior.start = CdPathStart::interior_point;
  // The stages before the probe's own dt take the interior-point start's paths only; its
  // compliant continuation, which may spend most of a budget, is kept for the last fallback.
  const auto interior_at = [&](double dt, CdPathStats& st) {
    ProbeSettings s = settings;
    s.dt = dt;
    CdStepSolution x = probe_cd_direct(packing, contact, s, budgeted(interior), &st, dt == settings.dt);
    account(st, dt);
    return x;
  };
  // CdPathStart::interior_inertial: the interior-point start at the probe's dt first, within
  // interior_share of the budget; where it is exact (or within accept_residual), that is the
  // probe's result, else the continuation in dt below within what is left, and where that does
  // not reach the probe's dt exactly, the interior-point start's result.
  const bool interior_first = ps.start == CdPathStart::interior_inertial;
  CdStepSolution first;
  CdPathStats first_stats;
  if (interior_first) {
    CdPathSettings at = interior;
    if (ps.max_probe_pieces > 0)
      at.max_probe_pieces = std::max(1LL, std::llround(ps.interior_share * static_cast<double>(ps.max_probe_pieces)));
    first = probe_cd_direct(packing, contact, settings, at, &first_stats);
    account(first_stats, settings.dt);
    // Its statistics in terms of the probe's budget, not the share's: where its paths stopped at
    // the share and the probe's budget is not spent, its failure is "share".
    all.budget_spent = ps.max_probe_pieces > 0 && used >= ps.max_probe_pieces;
    first_stats.budget_spent = all.budget_spent;
    if (first_stats.failure == "budget" && !all.budget_spent) first_stats.failure = "share";
    if (first.f.size() > 0 && first.residual.max() <= ps.accept_residual) {
      first_stats.accepted = !exact(first) && !all.budget_spent;
      first_stats.paths = std::move(paths);
      first_stats.attempts = static_cast<int>(first_stats.paths.size());
      if (stats_out) *stats_out = std::move(first_stats);
      return first;
    }
  }
  // The first stage: the step at more inertia.
  const double target = std::log(settings.dt);
  double log_dt = target - std::log(ps.inertial_factor);
  CdStepSolution sol;
  CdPathStats kept;
  for (int r = 0; r <= ps.inertial_retries && !spent(); ++r) {
    if (r > 0) log_dt -= 0.5 * std::log(10.0);
    CdPathStats st;
    sol = interior_at(std::exp(log_dt), st);
    kept = std::move(st);
    if (exact(sol)) break;
  }
  all.inertial_dt_start = std::exp(log_dt);
  CdPathSettings stage = ps;
  stage.start = CdPathStart::static_network;  // with a guess: the path from the last stage's solution
  if (exact(sol)) {
    all.inertial_dt_reached = std::exp(log_dt);
    const double h0 = (target - log_dt) / ps.inertial_stages;
    double h = h0;
    int halvings = 0;
    while (log_dt < target && !spent()) {
      const double next = h >= target - log_dt ? target : log_dt + h;
      ProbeSettings s = settings;
      s.dt = next == target ? settings.dt : std::exp(next);
      const CdStepProblem pb = build_cd_step(packing, contact, s);
      const CdStepGuess guess = solution_guess(packing, pb, sol);
      CdPathStats st;
      CdStepSolution x = probe_from_start(packing, pb, s, budgeted(stage), &st, nullptr, false, &guess);
      account(st, s.dt);
      ++all.inertial_stages;
      if (!exact(x) && halvings < ps.inertial_halvings) {  // a smaller step in dt
        h *= 0.5;
        ++halvings;
        continue;
      }
      if (!exact(x)) {  // a fold of the branch in dt: the interior-point start jumps to another branch
        // (Not at the probe's dt: there the jump would be the interior-point start that follows
        // the loop, or that interior_inertial ran first.)
        if (spent() || all.inertial_jumps >= ps.inertial_jumps || s.dt == settings.dt) break;
        st = CdPathStats{};
        x = interior_at(s.dt, st);
        ++all.inertial_jumps;
        if (!exact(x)) break;
      }
      sol = std::move(x);
      kept = std::move(st);
      log_dt = next;
      all.inertial_dt_reached = s.dt;
      h = std::min(h0, 1.5 * h);
      halvings = 0;
    }
  }
  // Where the continuation ends short of the probe's dt: the interior-point start there (or
  // its result from before the continuation: interior_inertial).
  if (interior_first && !(exact(sol) && all.inertial_dt_reached == settings.dt)) {
    all.inertial_fallback = true;
    sol = std::move(first);
    kept = std::move(first_stats);
  } else if (!(exact(sol) && all.inertial_dt_reached == settings.dt)) {
    all.inertial_fallback = true;
    if (!spent()) {
      CdPathStats st;
      sol = interior_at(settings.dt, st);  // its result is the probe's, with or without a solution
      kept = std::move(st);
    } else {  // the budget is spent: no solution of the probe's step
      sol = CdStepSolution{};
      sol.result = cd_step_result(build_cd_step(packing, contact, settings), packing, settings, sol.f);
    }
  }
  kept.paths = std::move(paths);
  kept.attempts = static_cast<int>(kept.paths.size());
  kept.budget_spent = all.budget_spent;
  kept.inertial_dt_start = all.inertial_dt_start;
  kept.inertial_dt_reached = all.inertial_dt_reached;
  kept.inertial_stages = all.inertial_stages;
  kept.inertial_jumps = all.inertial_jumps;
  kept.inertial_fallback = all.inertial_fallback;
  if (kept.budget_spent && !exact(sol)) kept.failure = "budget";
  kept.accepted = sol.f.size() > 0 && !sol.result.converged && !kept.budget_spent &&
                  sol.residual.max() <= ps.accept_residual;
  sol.result.sweeps = kept.budget_spent ? std::max(used, ps.max_probe_pieces + 1) : used;
  kept.pieces_all = sol.result.sweeps;
  if (stats_out) *stats_out = std::move(kept);
  return sol;
}

}  // namespace

CdStepSolution probe_cd_path(const Packing& packing, int contact, const ProbeSettings& settings,
                             const CdPathSettings& ps, CdPathStats* stats_out) {
  if (ps.start == CdPathStart::inertial || ps.start == CdPathStart::interior_inertial)
    return probe_cd_inertial(packing, contact, settings, ps, stats_out);
  return probe_cd_direct(packing, contact, settings, ps, stats_out);
}

}  // namespace unjam
