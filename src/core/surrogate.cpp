#include "sensornet/core/surrogate.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/ode.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "surrogate rollout";

using MatrixMap = Eigen::Map<Eigen::MatrixXd>;
using ConstMatrixMap = Eigen::Map<const Eigen::MatrixXd>;

// The integrator state: the n x n symmetric matrix (Ys or Ps) column by column, then the
// running-cost integral ∫ <W, P> dt.
ConstMatrixMap matrixPart(const Eigen::VectorXd& y, Eigen::Index n) {
  return ConstMatrixMap(y.data(), n, n);
}
MatrixMap matrixPart(Eigen::VectorXd& y, Eigen::Index n) { return MatrixMap(y.data(), n, n); }

// The one place where symmetry is restored on purpose: a product such as Y Q Y is symmetric in
// exact arithmetic but not bit for bit. With an exactly symmetric right-hand side, every
// Runge-Kutta combination keeps the state exactly symmetric too.
template <typename Derived>
void symmetrize(Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < j; ++i) {
      const double mean = 0.5 * (m(i, j) + m(j, i));
      m(i, j) = mean;
      m(j, i) = mean;
    }
  }
}

Eigen::MatrixXd symmetrized(const Eigen::MatrixXd& m) { return 0.5 * (m + m.transpose()); }

// The inverse of a symmetric positive definite matrix, or nothing if it is not one.
std::optional<Eigen::MatrixXd> inverseOfPositiveDefinite(const Eigen::MatrixXd& m) {
  const Eigen::LLT<Eigen::MatrixXd> llt(m);
  if (llt.info() != Eigen::Success) return std::nullopt;
  Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(m.rows(), m.cols()));
  symmetrize(inverse);
  return inverse;
}

// The local error of the matrix part measured relative to the matrix itself: with
// L L' = rtol X + atol I (X the state at the start of the step), the error E counts as
// ||L^{-1} E L^{-T}||_F. This bounds the relative error of X in every direction (and, since
// d(X^{-1}) = -X^{-1} dX X^{-1}, the same holds for X^{-1}), so the tolerance means the same for
// Ys and Ps and for well- and ill-conditioned covariances alike. The running-cost integral is
// measured relative to its own size. The larger of the two decides.
class RelativeMatrixNorm {
 public:
  RelativeMatrixNorm(Eigen::Index n, double rtol, double atol)
      : n_(n),
        rtol_(rtol),
        atol_(atol),
        weight_(n, n),
        scaled_(n, n),
        // Factored once here: the norm is copied into a std::function, and copying a
        // default-constructed LLT reads its uninitialized status (UBSan flags it).
        llt_(Eigen::MatrixXd::Identity(n, n)) {}

  double operator()(const Eigen::VectorXd& y_old, const Eigen::VectorXd& y_new,
                    const Eigen::VectorXd& error) {
    const ConstMatrixMap x_old = matrixPart(y_old, n_);
    const ConstMatrixMap e = matrixPart(error, n_);
    weight_ = rtol_ * x_old;
    weight_.diagonal().array() += atol_;
    llt_.compute(weight_);
    double matrix_error = 0.0;
    if (llt_.info() == Eigen::Success) {
      scaled_ = e;
      llt_.matrixL().solveInPlace(scaled_);
      llt_.matrixL().solveInPlace(scaled_.transpose());
      matrix_error = scaled_.norm();
    } else {
      // Not positive definite (never expected): fall back to a plain relative Frobenius error.
      matrix_error = e.norm() / (atol_ + rtol_ * x_old.norm());
    }
    const Eigen::Index c = n_ * n_;
    const double cost_scale = atol_ + rtol_ * std::max(std::abs(y_old(c)), std::abs(y_new(c)));
    return std::max(matrix_error, std::abs(error(c)) / cost_scale);
  }

 private:
  Eigen::Index n_;
  double rtol_;
  double atol_;
  Eigen::MatrixXd weight_;
  Eigen::MatrixXd scaled_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

// Information-form surrogate, eq. (11): Ẏs = -Ys A - A' Ys - Ys Q Ys + U, U = Σ_j λ_j S_j
// constant on a rate interval, with the running-cost rate <W, Ys^{-1}>.
class InformationFlow {
 public:
  explicit InformationFlow(const Scenario& s)
      : n_(s.stateDim()),
        A_(s.plant.A),
        Q_(s.plant.Q),
        W_(s.cost.W),
        increments_(s.informationIncrements()),
        weighted_(!s.cost.W.isZero(0.0)),
        U_(Eigen::MatrixXd::Zero(n_, n_)),
        ya_(n_, n_),
        yq_(n_, n_),
        solved_(n_, n_) {}

  void useRates(const Eigen::VectorXd& rates_hz) {
    U_.setZero();
    for (Eigen::Index j = 0; j < rates_hz.size(); ++j) {
      if (rates_hz(j) > 0.0) U_ += rates_hz(j) * increments_[static_cast<std::size_t>(j)];
    }
    symmetrize(U_);
  }

  void derivative(const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    const ConstMatrixMap Y = matrixPart(y, n_);
    MatrixMap F = matrixPart(dydt, n_);
    ya_.noalias() = Y * A_;
    yq_.noalias() = Y * Q_;
    F.noalias() = yq_ * Y;
    F = U_ - F - ya_ - ya_.transpose();
    symmetrize(F);
    dydt(n_ * n_) = weighted_ ? runningCostRate(Y) : 0.0;
  }

  [[nodiscard]] Eigen::MatrixXd stateFromCovariance(const Eigen::MatrixXd& P) const {
    auto Y = inverseOfPositiveDefinite(P);
    if (!Y) throw std::runtime_error("information-form rollout: covariance lost definiteness");
    return *Y;
  }
  [[nodiscard]] Eigen::MatrixXd covarianceFromState(const Eigen::MatrixXd& Y) const {
    auto P = inverseOfPositiveDefinite(Y);
    if (!P) throw std::runtime_error("information-form rollout: information lost definiteness");
    return *P;
  }

 private:
  // <W, Ys^{-1}>_F = tr(Ys^{-1} W).
  double runningCostRate(const ConstMatrixMap& Y) {
    llt_.compute(Y);
    if (llt_.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    solved_ = W_;
    llt_.solveInPlace(solved_);
    return solved_.trace();
  }

  Eigen::Index n_;
  const Eigen::MatrixXd& A_;
  const Eigen::MatrixXd& Q_;
  const Eigen::MatrixXd& W_;
  std::vector<Eigen::MatrixXd> increments_;
  bool weighted_;
  Eigen::MatrixXd U_;
  Eigen::MatrixXd ya_, yq_, solved_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

// Covariance-form surrogate, eq. (15): Ṗs = A Ps + Ps A' + Q - Σ_j λ_j g_j(Ps) with
// g_j(X) = X H_j' (H_j X H_j' + R_j)^{-1} H_j X, so Σ_j λ_j g_j(P) = (H P)' K (H P) for the
// block-diagonal K = diag(λ_j (H_j P H_j' + R_j)^{-1}). Only sensors with λ_j > 0 on the current
// interval take part; single-row sensors (the common case) are handled together, row-wise.
class CovarianceFlow {
 public:
  explicit CovarianceFlow(const Scenario& s)
      : n_(s.stateDim()),
        A_(s.plant.A),
        Q_(s.plant.Q),
        W_(s.cost.W),
        sensors_(s.sensors),
        weighted_(!s.cost.W.isZero(0.0)),
        ap_(n_, n_) {}

  void useRates(const Eigen::VectorXd& rates_hz) {
    Eigen::Index scalar_count = 0;
    for (Eigen::Index j = 0; j < rates_hz.size(); ++j) {
      if (rates_hz(j) > 0.0 && sensorAt(j).H.rows() == 1) ++scalar_count;
    }
    scalar_H_.resize(scalar_count, n_);
    scalar_R_.resize(scalar_count);
    scalar_rate_.resize(scalar_count);
    scalar_HP_.resize(scalar_count, n_);
    weighted_HP_.resize(scalar_count, n_);
    scalar_weight_.resize(scalar_count);
    blocks_.clear();
    Eigen::Index row = 0;
    for (Eigen::Index j = 0; j < rates_hz.size(); ++j) {
      if (!(rates_hz(j) > 0.0)) continue;
      const SensorModel& sensor = sensorAt(j);
      if (sensor.H.rows() == 1) {
        scalar_H_.row(row) = sensor.H;
        scalar_R_(row) = sensor.R(0, 0);
        scalar_rate_(row) = rates_hz(j);
        ++row;
      } else {
        blocks_.push_back({&sensor, rates_hz(j)});
      }
    }
  }

  void derivative(const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    const ConstMatrixMap P = matrixPart(y, n_);
    MatrixMap F = matrixPart(dydt, n_);
    ap_.noalias() = A_ * P;
    F = ap_ + ap_.transpose() + Q_;
    if (scalar_H_.rows() > 0) {
      // Coefficient-based products: at these sizes (tens of rows, a handful of columns) the
      // blocked kernels spend more time packing than multiplying.
      scalar_HP_.noalias() = scalar_H_.lazyProduct(P);
      // λ_j / (h_j P h_j' + r_j) for every active single-row sensor j.
      scalar_weight_ =
          scalar_rate_.array() /
          ((scalar_HP_.array() * scalar_H_.array()).rowwise().sum() + scalar_R_.array());
      weighted_HP_ = scalar_HP_.array().colwise() * scalar_weight_;
      F.noalias() -= scalar_HP_.transpose().lazyProduct(weighted_HP_);
    }
    for (const ActiveBlock& block : blocks_) {
      const Eigen::MatrixXd hp = block.sensor->H * P;
      const Eigen::MatrixXd innovation = hp * block.sensor->H.transpose() + block.sensor->R;
      F.noalias() -= block.rate_hz * (hp.transpose() * innovation.llt().solve(hp));
    }
    symmetrize(F);
    dydt(n_ * n_) = weighted_ ? W_.cwiseProduct(P).sum() : 0.0;
  }

  [[nodiscard]] Eigen::MatrixXd stateFromCovariance(const Eigen::MatrixXd& P) const { return P; }
  [[nodiscard]] Eigen::MatrixXd covarianceFromState(const Eigen::MatrixXd& P) const { return P; }

 private:
  struct ActiveBlock {
    const SensorModel* sensor;
    double rate_hz;
  };
  const SensorModel& sensorAt(Eigen::Index j) const {
    return sensors_[static_cast<std::size_t>(j)];
  }

  Eigen::Index n_;
  const Eigen::MatrixXd& A_;
  const Eigen::MatrixXd& Q_;
  const Eigen::MatrixXd& W_;
  const std::vector<SensorModel>& sensors_;
  bool weighted_;
  Eigen::MatrixXd ap_;
  Eigen::MatrixXd scalar_H_, scalar_HP_, weighted_HP_;
  Eigen::VectorXd scalar_R_, scalar_rate_;
  Eigen::ArrayXd scalar_weight_;
  std::vector<ActiveBlock> blocks_;
};

std::string shapeOf(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + " x " + std::to_string(m.cols());
}

// Only the shapes, which would otherwise be undefined behaviour deep in Eigen; definiteness and
// the rest are validateScenario's job.
void checkShapes(const Scenario& s) {
  const Eigen::Index n = s.plant.A.rows();
  auto require = [&](const Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols,
                     const std::string& field) {
    if (m.rows() != rows || m.cols() != cols) {
      throw InputError(kSource, field,
                       "a " + std::to_string(rows) + " x " + std::to_string(cols) +
                           " matrix, got " + shapeOf(m));
    }
  };
  if (n < 1) throw InputError(kSource, "plant.A", "a non-empty square matrix");
  require(s.plant.A, n, n, "plant.A");
  require(s.plant.Q, n, n, "plant.Q");
  require(s.plant.P0, n, n, "plant.P0");
  require(s.cost.W, n, n, "cost.W");
  require(s.cost.WT, n, n, "cost.WT");
  for (std::size_t j = 0; j < s.sensors.size(); ++j) {
    const std::string field = "sensors[" + std::to_string(j) + "]";
    const Eigen::Index p = s.sensors[j].H.rows();
    if (p < 1) throw InputError(kSource, field + ".H", "at least one row");
    require(s.sensors[j].H, p, n, field + ".H");
    require(s.sensors[j].R, p, p, field + ".R");
  }
}

void checkSchedule(const Scenario& scenario, const RateSchedule& schedule) {
  if (schedule.sensorCount() != scenario.sensorCount()) {
    throw InputError(kSource, "schedule",
                     "one rate column per sensor (" + std::to_string(scenario.sensorCount()) +
                         "), got " + std::to_string(schedule.sensorCount()));
  }
  if (schedule.intervals() < 1) throw InputError(kSource, "schedule", "at least one interval");
  if (!(std::abs(schedule.horizon() - scenario.horizon_s) <= 1e-12 * scenario.horizon_s)) {
    throw InputError(kSource, "schedule.horizon",
                     "the scenario's horizon " + std::to_string(scenario.horizon_s) + ", got " +
                         std::to_string(schedule.horizon()));
  }
  for (int k = 0; k < schedule.intervals(); ++k) {
    for (int j = 0; j < schedule.sensorCount(); ++j) {
      const double rate = schedule.rate(k, j);
      if (!std::isfinite(rate) || rate < 0.0) {
        throw InputError(kSource,
                         "schedule.rates[" + std::to_string(k) + "][" + std::to_string(j) + "]",
                         "a finite rate >= 0, got " + std::to_string(rate));
      }
    }
  }
}

// The covariance at start_time, checked and symmetrized, after checking the other options.
Eigen::MatrixXd startCovariance(const Scenario& scenario, const RolloutOptions& options) {
  if (!std::isfinite(options.relative_tolerance) || options.relative_tolerance <= 0.0) {
    throw InputError(kSource, "options.relative_tolerance",
                     "a finite number > 0, got " + std::to_string(options.relative_tolerance));
  }
  if (!std::isfinite(options.absolute_tolerance) || options.absolute_tolerance < 0.0) {
    throw InputError(kSource, "options.absolute_tolerance",
                     "a finite number >= 0, got " + std::to_string(options.absolute_tolerance));
  }
  const double horizon = scenario.horizon_s;
  if (!std::isfinite(options.start_time) || options.start_time < 0.0 ||
      options.start_time > horizon) {
    throw InputError(kSource, "options.start_time",
                     "a time in [0, " + std::to_string(horizon) + "], got " +
                         std::to_string(options.start_time));
  }
  if (options.end_time &&
      !(*options.end_time >= options.start_time && *options.end_time <= horizon)) {
    throw InputError(kSource, "options.end_time",
                     "a time in [start_time, " + std::to_string(horizon) + "], got " +
                         std::to_string(*options.end_time));
  }
  if (!options.start_covariance) {
    if (options.start_time > 0.0) {
      throw InputError(kSource, "options.start_covariance",
                       "the covariance at start_time when start_time > 0");
    }
    return scenario.plant.P0;
  }
  const Eigen::MatrixXd& P = *options.start_covariance;
  const Eigen::Index n = scenario.stateDim();
  if (P.rows() != n || P.cols() != n) {
    throw InputError(
        kSource, "options.start_covariance",
        "a " + std::to_string(n) + " x " + std::to_string(n) + " matrix, got " + shapeOf(P));
  }
  if (!P.allFinite()) {
    throw InputError(kSource, "options.start_covariance", "finite numbers");
  }
  const double scale = std::max(P.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    throw InputError(kSource, "options.start_covariance", "a symmetric matrix");
  }
  Eigen::MatrixXd start = symmetrized(P);
  if (Eigen::LLT<Eigen::MatrixXd>(start).info() != Eigen::Success) {
    throw InputError(kSource, "options.start_covariance", "a positive definite matrix");
  }
  return start;
}

struct Segment {
  double start;
  double end;
  int interval;
};

// The pieces of [start_time, end_time] on which the rates are constant.
std::vector<Segment> segmentsOf(const RateSchedule& schedule, double start_time,
                                double end_time) {
  const int count = schedule.intervals();
  const double horizon = schedule.horizon();
  const double rounding = 1e-12 * horizon;
  auto boundary = [&](int k) { return k >= count ? horizon : schedule.intervalStart(k); };
  std::vector<Segment> segments;
  if (!(end_time - start_time > rounding)) return segments;
  int k = schedule.intervalAt(start_time);
  // A start time within rounding of the next boundary starts the next interval, rather than
  // leaving a sliver of the previous one; likewise an end time ends at a boundary near it.
  while (k + 1 < count && boundary(k + 1) - start_time <= rounding) ++k;
  for (double from = start_time; k < count && end_time - from > rounding; ++k) {
    const double to = boundary(k + 1) - end_time > -rounding ? end_time : boundary(k + 1);
    segments.push_back({from, to, k});
    from = to;
  }
  return segments;
}

// Checked before a flow is built from the scenario.
void checkModel(const Scenario& scenario, const RateSchedule& schedule) {
  checkShapes(scenario);
  checkSchedule(scenario, schedule);
}

template <typename Flow>
SurrogateRollout rolloutWith(Flow& flow, const char* form_name, const Scenario& scenario,
                             const RateSchedule& schedule, const RolloutOptions& options) {
  const Eigen::MatrixXd start = startCovariance(scenario, options);
  const Eigen::Index n = scenario.stateDim();

  Eigen::VectorXd y(n * n + 1);
  matrixPart(y, n) = flow.stateFromCovariance(start);
  y(n * n) = 0.0;

  SurrogateRollout result;
  result.times.push_back(options.start_time);
  result.covariances.push_back(start);

  OdeOptions ode;
  ode.relative_tolerance = options.relative_tolerance;
  ode.absolute_tolerance = options.absolute_tolerance;
  ode.error_norm = RelativeMatrixNorm(n, options.relative_tolerance, options.absolute_tolerance);
  const OdeRightHandSide rhs = [&flow](double, const Eigen::VectorXd& state,
                                       Eigen::VectorXd& dydt) { flow.derivative(state, dydt); };

  // Restarted at every boundary: the right-hand side jumps there, and a step across a jump
  // would be rejected until it lands on it anyway. The step size carries over as a first guess.
  const double end_time = options.end_time.value_or(scenario.horizon_s);
  for (const Segment& segment : segmentsOf(schedule, options.start_time, end_time)) {
    flow.useRates(schedule.rates().row(segment.interval).transpose());
    OdeSolution solution =
        integrateDormandPrince(rhs, segment.start, segment.end, std::move(y), ode);
    if (solution.status != OdeStatus::Success) {
      throw std::runtime_error(std::string(form_name) +
                               " rollout stopped at t = " + std::to_string(solution.t) +
                               " in interval " + std::to_string(segment.interval) + ": " +
                               std::string(describe(solution.status)));
    }
    y = std::move(solution.y);
    ode.initial_step = solution.next_step;
    result.steps += solution.accepted_steps;
    result.times.push_back(segment.end);
    result.covariances.push_back(flow.covarianceFromState(matrixPart(y, n)));
  }

  result.running_cost = y(n * n);
  result.terminal_cost = end_time == scenario.horizon_s
                             ? scenario.cost.WT.cwiseProduct(result.covariances.back()).sum()
                             : 0.0;
  result.cost = result.running_cost + result.terminal_cost;
  return result;
}

}  // namespace

SurrogateRollout rolloutInformationForm(const Scenario& scenario, const RateSchedule& schedule,
                                        const RolloutOptions& options) {
  checkModel(scenario, schedule);
  InformationFlow flow(scenario);
  return rolloutWith(flow, "information-form", scenario, schedule, options);
}

SurrogateRollout rolloutCovarianceForm(const Scenario& scenario, const RateSchedule& schedule,
                                       const RolloutOptions& options) {
  checkModel(scenario, schedule);
  CovarianceFlow flow(scenario);
  return rolloutWith(flow, "covariance-form", scenario, schedule, options);
}

SurrogateRollout rollout(SurrogateForm form, const Scenario& scenario, const RateSchedule& schedule,
                         const RolloutOptions& options) {
  switch (form) {
    case SurrogateForm::Information:
      return rolloutInformationForm(scenario, schedule, options);
    case SurrogateForm::Covariance:
      return rolloutCovarianceForm(scenario, schedule, options);
  }
  throw std::invalid_argument("rollout: unknown SurrogateForm");
}

CostBracket computeBracket(const Scenario& scenario, const RateSchedule& schedule,
                           const RolloutOptions& options) {
  return {rolloutInformationForm(scenario, schedule, options).cost,
          rolloutCovarianceForm(scenario, schedule, options).cost};
}

}  // namespace sensornet
