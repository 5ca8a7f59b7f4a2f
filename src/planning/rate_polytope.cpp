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

// The largest factor in (0, 1] that brings C λ within b: C >= 0, so scaling rates down never
// breaks a row they meet.
double factorWithin(const Eigen::MatrixXd& C, const Eigen::VectorXd& b,
                    const Eigen::Ref<const Eigen::VectorXd>& lambda) {
  const Eigen::VectorXd load = C * lambda;
  double scale = 1.0;
  for (Eigen::Index i = 0; i < load.size(); ++i) {
    if (load(i) > b(i)) scale = std::min(scale, b(i) / load(i));
  }
  return scale;
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
  return factorWithin(C, b, lambda) * lambda;
}

Eigen::MatrixXd RatePolytope::projectSchedule(const Eigen::Ref<const Eigen::MatrixXd>& rates,
                                              double interval_length,
                                              const Eigen::VectorXd& energy,
                                              Eigen::VectorXd* budget_multipliers) const {
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
  constexpr double kTolerance = 1e-12;
  Eigen::VectorXd nu = Eigen::VectorXd::Zero(sensors);
  if (budget_multipliers != nullptr && budget_multipliers->size() == sensors) {
    for (const Eigen::Index j : budgeted) nu(j) = std::max(0.0, (*budget_multipliers)(j));
  }
  // First, gradient ascent on the budgets' multipliers alone, each interval projected exactly
  // (project()) at the rates shifted by h ν: the dual φ(ν) is concave with gradient
  // g_j = h Σ_k λ_kj(ν) - E_j, Lipschitz with constant h² K. Barzilai-Borwein steps, projected
  // onto ν >= 0, usually meet the budgets in tens of steps where the sweeps below took
  // thousands (interval rows and budgets both binding); if not, the sweeps go on from its ν.
  const Eigen::MatrixXd base = shifted;
  const auto primalAt = [&](const Eigen::VectorXd& v) {
    Eigen::RowVectorXd shift = Eigen::RowVectorXd::Zero(sensors);
    for (const Eigen::Index j : budgeted) shift(j) = interval_length * v(j);
    Eigen::MatrixXd out(intervals, sensors);
    for (Eigen::Index k = 0; k < intervals; ++k) {
      out.row(k) = project((base.row(k) - shift).transpose()).transpose();
    }
    return out;
  };
  const auto excess = [&](const Eigen::MatrixXd& lambda_at) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(sensors);
    for (const Eigen::Index j : budgeted) {
      g(j) = interval_length * lambda_at.col(j).sum() - energy(j);
    }
    return g;
  };
  const auto met = [&](const Eigen::VectorXd& g, const Eigen::VectorXd& v) {
    for (const Eigen::Index j : budgeted) {
      const double relative = g(j) / energy(j);
      if (relative > kTolerance || (v(j) > 0.0 && std::abs(relative) > kTolerance)) return false;
    }
    return true;
  };
  if (!budgeted.empty()) {
    const double lipschitz = interval_length * interval_length * static_cast<double>(intervals);
    Eigen::MatrixXd at = primalAt(nu);
    Eigen::VectorXd g = excess(at);
    double step = 1.0 / lipschitz;
    for (int it = 0; it < kMaxDualSteps; ++it) {
      if (met(g, nu)) {
        if (budget_multipliers != nullptr) *budget_multipliers = nu;
        for (const Eigen::Index j : budgeted) {  // exact, whatever the rounding
          const double used = interval_length * at.col(j).sum();
          if (used > energy(j)) at.col(j) *= energy(j) / used;
        }
        return at;
      }
      const Eigen::VectorXd next = (nu + step * g).cwiseMax(0.0);
      Eigen::MatrixXd next_at = primalAt(next);
      const Eigen::VectorXd next_g = excess(next_at);
      const Eigen::VectorXd ds = next - nu;
      const double curvature = -ds.dot(next_g - g);
      // Where φ is flat along the step (a sensor with no rate left, whose ν only has to come
      // down), longer steps.
      step = curvature > 0.0 ? std::clamp(ds.squaredNorm() / curvature, 1e-3 / lipschitz,
                                          1e6 / lipschitz)
                             : std::min(4.0 * step, 1e6 / lipschitz);
      nu = next;
      at = std::move(next_at);
      g = next_g;
    }
  }
  Eigen::MatrixXd mu = Eigen::MatrixXd::Zero(intervals, C.rows());
  for (const Eigen::Index j : budgeted) shifted.col(j).array() -= nu(j) * interval_length;
  Eigen::VectorXd z;
  std::vector<std::pair<double, double>> breakpoints;
  Eigen::MatrixXd lambda = shifted.cwiseMax(0.0);
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
  if (budget_multipliers != nullptr) *budget_multipliers = nu;
  // Admissible exactly, whatever the sweeps reached: C >= 0 and h > 0, so scaling an interval
  // or a sensor down leaves every other row as it was or looser.
  for (Eigen::Index k = 0; k < intervals; ++k) {
    lambda.row(k) *= factorWithin(C, b, lambda.row(k).transpose());
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
