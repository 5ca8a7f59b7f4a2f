#include "sensornet/planning/rate_polytope.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

// The μ >= 0 with Σ_j c_j max(0, z_j - c_j μ) <= b and equality when μ > 0: the optimal
// multiplier of one constraint row c'λ <= b when the others are held fixed. The left side is
// continuous, piecewise linear and nonincreasing in μ, with breakpoints z_j / c_j.
double rowMultiplier(const Eigen::Ref<const Eigen::VectorXd>& c, const Eigen::VectorXd& z,
                     double b, std::vector<std::pair<double, double>>& breakpoints) {
  breakpoints.clear();
  double load = 0.0;
  for (Eigen::Index j = 0; j < z.size(); ++j) {
    if (c(j) > 0.0 && z(j) > 0.0) {
      load += c(j) * z(j);
      breakpoints.emplace_back(z(j) / c(j), c(j));
    }
  }
  if (load <= b) return 0.0;
  // Walk the breakpoints from the largest down: on (t_next, t) the active set is fixed and
  // load(μ) = Σ_active c_j z_j - μ Σ_active c_j², linear. A heap yields them in that order
  // without sorting all of them: the root usually lies among the few largest (a sparse plan).
  const auto smaller = [](const auto& l, const auto& r) { return l.first < r.first; };
  std::make_heap(breakpoints.begin(), breakpoints.end(), smaller);
  double intercept = 0.0;  // Σ_active c_j z_j
  double slope = 0.0;      // Σ_active c_j²
  for (auto end = breakpoints.end(); end != breakpoints.begin();) {
    std::pop_heap(breakpoints.begin(), end, smaller);
    --end;
    const auto [t, cj] = *end;
    intercept += cj * cj * t;
    slope += cj * cj;
    const double next = end != breakpoints.begin() ? breakpoints.front().first : 0.0;
    // The root lies in [next, t] when load(next) >= b.
    if (intercept - next * slope >= b) return (intercept - b) / slope;
  }
  return 0.0;  // not reached: load(0) > b was checked above
}

}  // namespace

RatePolytope::RatePolytope(ResourceConstraints constraints, const std::vector<int>& excluded)
    : constraints_(std::move(constraints)),
      excluded_(static_cast<std::size_t>(constraints_.C.cols()), false) {
  for (const int j : excluded) {
    if (j < 0 || j >= sensorCount()) {
      throw InputError("rate polytope", "excluded_sensors",
                       "sensor indices in [0, " + std::to_string(sensorCount() - 1) + "], got " +
                           std::to_string(j));
    }
    excluded_[static_cast<std::size_t>(j)] = true;
  }
}

Eigen::VectorXd RatePolytope::maxRates() const {
  const auto& C = constraints_.C;
  Eigen::VectorXd bound(C.cols());
  for (Eigen::Index j = 0; j < C.cols(); ++j) {
    double r = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < C.rows(); ++i) {
      if (C(i, j) > 0.0) r = std::min(r, constraints_.b(i) / C(i, j));
    }
    bound(j) = isExcluded(static_cast<int>(j)) ? 0.0 : r;
  }
  return bound;
}

Eigen::VectorXd RatePolytope::uniformRates() const {
  Eigen::VectorXd in_service(sensorCount());
  for (int j = 0; j < sensorCount(); ++j) in_service(j) = isExcluded(j) ? 0.0 : 1.0;
  const Eigen::VectorXd load = constraints_.C * in_service;
  double rate = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < load.size(); ++i) {
    if (load(i) > 0.0) rate = std::min(rate, constraints_.b(i) / load(i));
  }
  if (!std::isfinite(rate)) rate = 0.0;  // every sensor excluded
  return rate * in_service;
}

bool RatePolytope::contains(const Eigen::Ref<const Eigen::VectorXd>& rates, double tol) const {
  if (rates.size() != sensorCount() || !rates.allFinite()) return false;
  for (int j = 0; j < sensorCount(); ++j) {
    if (rates(j) < -tol || (isExcluded(j) && rates(j) > tol)) return false;
  }
  return ((constraints_.C * rates - constraints_.b).array() <= tol).all();
}

Eigen::VectorXd RatePolytope::project(const Eigen::Ref<const Eigen::VectorXd>& rates) const {
  const auto& C = constraints_.C;
  const auto& b = constraints_.b;
  Eigen::VectorXd y = rates;
  for (int j = 0; j < sensorCount(); ++j) {
    if (isExcluded(j)) y(j) = 0.0;
  }
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(C.rows());
  Eigen::VectorXd shifted = y;  // y - C' μ
  Eigen::VectorXd z(y.size());
  std::vector<std::pair<double, double>> breakpoints;
  const int max_sweeps = C.rows() == 1 ? 1 : 10000;
  Eigen::VectorXd lambda = y.cwiseMax(0.0);
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    for (Eigen::Index i = 0; i < C.rows(); ++i) {
      z = shifted + mu(i) * C.row(i).transpose();
      mu(i) = rowMultiplier(C.row(i).transpose(), z, b(i), breakpoints);
      shifted = z - mu(i) * C.row(i).transpose();
    }
    lambda = shifted.cwiseMax(0.0);
    // Optimal when primal feasible and complementary: a row with μ_i > 0 is tight.
    const Eigen::ArrayXd slack = (C * lambda - b).array() / b.array();
    const bool complementary = ((mu.array() <= 0.0) || (slack.abs() <= 1e-13)).all();
    if (slack.maxCoeff() <= 1e-13 && complementary) break;
  }
  // Make the result admissible exactly, whatever the sweeps reached: C >= 0, so scaling down
  // never leaves the polytope.
  const Eigen::VectorXd load = C * lambda;
  double scale = 1.0;
  for (Eigen::Index i = 0; i < load.size(); ++i) {
    if (load(i) > b(i)) scale = std::min(scale, b(i) / load(i));
  }
  return scale * lambda;
}

}  // namespace sensornet

namespace sensornet {

Eigen::MatrixXd RatePolytope::projectSchedule(const Eigen::Ref<const Eigen::MatrixXd>& rates,
                                              double interval_length,
                                              const Eigen::VectorXd& energy) const {
  const auto& C = constraints_.C;
  const auto& b = constraints_.b;
  const Eigen::Index intervals = rates.rows();
  const Eigen::Index sensors = rates.cols();
  const Eigen::VectorXd weights = Eigen::VectorXd::Constant(intervals, interval_length);
  // The energy rows that can bind; a budget of 0 leaves the sensor nothing.
  std::vector<Eigen::Index> budgeted;
  Eigen::MatrixXd shifted = rates;  // Y - Σ μ_ki C_i (in row k) - Σ ν_j h (in column j)
  for (Eigen::Index j = 0; j < sensors; ++j) {
    if (isExcluded(static_cast<int>(j)) || !(energy(j) > 0.0)) {
      shifted.col(j).setZero();
    } else if (energy(j) < std::numeric_limits<double>::infinity()) {
      budgeted.push_back(j);
    }
  }
  Eigen::MatrixXd mu = Eigen::MatrixXd::Zero(intervals, C.rows());
  Eigen::VectorXd nu = Eigen::VectorXd::Zero(sensors);
  Eigen::VectorXd z;
  std::vector<std::pair<double, double>> breakpoints;
  Eigen::MatrixXd lambda = shifted.cwiseMax(0.0);
  constexpr double kTolerance = 1e-12;
  for (int sweep = 0; sweep < kMaxScheduleSweeps; ++sweep) {
    for (Eigen::Index k = 0; k < intervals; ++k) {
      for (Eigen::Index i = 0; i < C.rows(); ++i) {
        z = shifted.row(k).transpose() + mu(k, i) * C.row(i).transpose();
        mu(k, i) = rowMultiplier(C.row(i).transpose(), z, b(i), breakpoints);
        shifted.row(k) = (z - mu(k, i) * C.row(i).transpose()).transpose();
      }
    }
    for (const Eigen::Index j : budgeted) {
      z = shifted.col(j) + nu(j) * weights;
      nu(j) = rowMultiplier(weights, z, energy(j), breakpoints);
      shifted.col(j) = z - nu(j) * weights;
    }
    lambda = shifted.cwiseMax(0.0);
    // Optimal when primal feasible and complementary: a row with a positive multiplier is tight.
    bool optimal = true;
    for (Eigen::Index k = 0; k < intervals && optimal; ++k) {
      const Eigen::ArrayXd slack =
          (C * lambda.row(k).transpose() - b).array() / b.array();
      optimal = slack.maxCoeff() <= kTolerance &&
                ((mu.row(k).transpose().array() <= 0.0) || (slack.abs() <= kTolerance)).all();
    }
    for (std::size_t e = 0; e < budgeted.size() && optimal; ++e) {
      const Eigen::Index j = budgeted[e];
      const double slack = (interval_length * lambda.col(j).sum() - energy(j)) / energy(j);
      optimal = slack <= kTolerance && (nu(j) <= 0.0 || std::abs(slack) <= kTolerance);
    }
    if (optimal) break;
  }
  // Admissible exactly, whatever the sweeps reached: C >= 0 and h > 0, so scaling an interval
  // or a sensor down leaves every other row as it was or looser.
  for (Eigen::Index k = 0; k < intervals; ++k) {
    const Eigen::VectorXd load = C * lambda.row(k).transpose();
    double scale = 1.0;
    for (Eigen::Index i = 0; i < load.size(); ++i) {
      if (load(i) > b(i)) scale = std::min(scale, b(i) / load(i));
    }
    lambda.row(k) *= scale;
  }
  for (const Eigen::Index j : budgeted) {
    const double used = interval_length * lambda.col(j).sum();
    if (used > energy(j)) lambda.col(j) *= energy(j) / used;
  }
  return lambda;
}

Eigen::MatrixXd RatePolytope::uniformSchedule(int intervals, double interval_length,
                                              const Eigen::VectorXd& energy) const {
  const Eigen::VectorXd uniform = uniformRates();
  Eigen::MatrixXd rates(intervals, sensorCount());
  for (int j = 0; j < sensorCount(); ++j) {
    const double cap = energy.size() > 0 ? std::max(0.0, energy(j)) / (intervals * interval_length)
                                         : std::numeric_limits<double>::infinity();
    rates.col(j).setConstant(std::min(uniform(j), cap));
  }
  return rates;
}

}  // namespace sensornet
