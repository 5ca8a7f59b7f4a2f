#include "sensornet/core/rate_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace sensornet {

RateSchedule::RateSchedule(double horizon_s, Eigen::MatrixXd rates_hz)
    : horizon_s_(horizon_s), rates_hz_(std::move(rates_hz)) {}

int RateSchedule::intervalAt(double t) const {
  const int k = static_cast<int>(std::floor(t / intervalLength()));
  return std::clamp(k, 0, intervals() - 1);
}

Eigen::VectorXd RateSchedule::expectedCounts(double t0, double t1) const {
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(sensorCount());
  const double h = intervalLength();
  for (int k = 0; k < intervals(); ++k) {
    const double overlap = std::min(t1, (k + 1) * h) - std::max(t0, k * h);
    if (overlap > 0.0) counts += overlap * rates_hz_.row(k).transpose();
  }
  return counts;
}

Feasibility checkFeasibility(const RateSchedule& schedule, const Scenario& scenario, double tol) {
  Feasibility result;
  // Keeps the first reason and the largest violation.
  auto fail = [&result](double violation, std::string reason) {
    if (result.feasible) result.reason = std::move(reason);
    result.feasible = false;
    result.max_violation = std::max(result.max_violation, violation);
  };
  if (schedule.intervals() != scenario.intervals ||
      schedule.sensorCount() != scenario.sensorCount()) {
    std::ostringstream reason;
    reason << "shape " << schedule.intervals() << " x " << schedule.sensorCount()
           << " does not match the scenario's " << scenario.intervals << " intervals x "
           << scenario.sensorCount() << " sensors";
    result.feasible = false;
    result.max_violation = std::numeric_limits<double>::infinity();
    result.reason = reason.str();
    return result;
  }
  if (std::abs(schedule.horizon() - scenario.horizon_s) > 1e-12 * scenario.horizon_s) {
    result.feasible = false;
    result.max_violation = std::numeric_limits<double>::infinity();
    result.reason = "horizon " + std::to_string(schedule.horizon()) +
                    " does not match the scenario's " + std::to_string(scenario.horizon_s);
    return result;
  }
  const auto& C = scenario.constraints.C;
  const auto& b = scenario.constraints.b;
  for (int k = 0; k < schedule.intervals(); ++k) {
    const Eigen::VectorXd lambda = schedule.rates().row(k).transpose();
    for (int j = 0; j < lambda.size(); ++j) {
      if (!std::isfinite(lambda(j))) {
        fail(std::numeric_limits<double>::infinity(),
             "interval " + std::to_string(k) + ", sensor " + std::to_string(j) +
                 ": rate is not a finite number");
      } else if (lambda(j) < -tol) {
        fail(-lambda(j), "interval " + std::to_string(k) + ", sensor " + std::to_string(j) +
                             ": negative rate " + std::to_string(lambda(j)));
      }
    }
    const Eigen::VectorXd slack = C * lambda - b;
    for (int i = 0; i < slack.size(); ++i) {
      if (slack(i) > tol) {
        fail(slack(i), "interval " + std::to_string(k) + ", constraint row " + std::to_string(i) +
                           ": C*lambda exceeds b by " + std::to_string(slack(i)));
      }
    }
  }
  const Eigen::VectorXd& energy = scenario.constraints.energy;
  if (energy.size() == schedule.sensorCount()) {
    const Eigen::VectorXd used = schedule.expectedCounts(0.0, schedule.horizon());
    for (int j = 0; j < energy.size(); ++j) {
      // The tolerance is a rate's, so the same schedule passes at any horizon.
      const double over = used(j) - energy(j);
      if (over > tol * std::max(1.0, schedule.horizon())) {
        fail(over, "sensor " + std::to_string(j) + ": expected measurements over the horizon " +
                       std::to_string(used(j)) + " exceed its energy budget " +
                       std::to_string(energy(j)));
      }
    }
  }
  return result;
}

RateSchedule uniformSchedule(const Scenario& scenario) {
  const Eigen::VectorXd row_sums = scenario.constraints.C.rowwise().sum();
  double rate = std::numeric_limits<double>::infinity();
  for (int i = 0; i < row_sums.size(); ++i) {
    if (row_sums(i) > 0.0) rate = std::min(rate, scenario.constraints.b(i) / row_sums(i));
  }
  Eigen::MatrixXd rates =
      Eigen::MatrixXd::Constant(scenario.intervals, scenario.sensorCount(), rate);
  const Eigen::VectorXd& energy = scenario.constraints.energy;
  for (Eigen::Index j = 0; j < energy.size(); ++j) {
    rates.col(j) = rates.col(j).cwiseMin(energy(j) / scenario.horizon_s);
  }
  return RateSchedule(scenario.horizon_s, std::move(rates));
}

}  // namespace sensornet
