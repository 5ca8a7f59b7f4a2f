#include "planning_problem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sensornet::planning {
namespace {

// The request's RK4 steps per interval as given: planSchedule chooses them (planner.cpp).
TranscriptionOptions transcriptionOptions(const PlanRequest& request) {
  TranscriptionOptions options;
  options.substeps = request.substeps;
  options.start_time = request.start_time;
  options.start_covariance = request.start_covariance;
  options.delivery = request.delivery;
  return options;
}

}  // namespace

PlanningProblem::PlanningProblem(const Scenario& scenario, const PlanRequest& request,
                                 SurrogateForm form)
    : polytope_(scenario.constraints, request.excluded_sensors),
      transcription_(form, scenario, transcriptionOptions(request)),
      first_interval_(transcription_.firstInterval()),
      rate_unit_(1.0),
      rates_(Eigen::MatrixXd::Zero(scenario.intervals, scenario.sensorCount())),
      interval_length_(scenario.intervalLength()) {
  const Eigen::VectorXd max_rates = polytope_.maxRates();
  double unit = 0.0;
  for (int j = 0; j < scenario.sensorCount(); ++j) {
    if (polytope_.isExcluded(j)) continue;
    in_service_.push_back(j);
    unit = std::max(unit, max_rates(j));
  }
  if (unit > 0.0 && std::isfinite(unit)) rate_unit_ = unit;
  sensor_information_.resize(scenario.sensorCount());
  const std::vector<Eigen::MatrixXd> increments = scenario.informationIncrements();
  for (int j = 0; j < scenario.sensorCount(); ++j) {
    const double trace = increments[static_cast<std::size_t>(j)].trace();
    sensor_information_(j) = std::isfinite(trace) && trace > 0.0 ? trace : 1.0;
  }
  if (request.warm_start) rates_ = request.warm_start->rates();
  if (scenario.constraints.hasEnergyBudgets()) {
    // Spent before the start time: as the request says, or by the rows it keeps.
    const Eigen::VectorXd spent =
        request.energy_spent
            ? *request.energy_spent
            : RateSchedule(scenario.horizon_s, rates_).expectedCounts(0.0, request.start_time);
    energy_left_ = (scenario.constraints.energy - spent).cwiseMax(0.0);
  }
  const bool warm =
      request.warm_start && request.surrogate != PlanSurrogate::Uniform && !request.cold_start;
  if (warm) {
    rates_ = projected(rates_);
  } else {
    rates_.bottomRows(plannedIntervals()) =
        energy_left_.size() > 0
            ? polytope_.uniformSchedule(plannedIntervals(), interval_length_, energy_left_)
            : polytope_.uniformRates().transpose().replicate(plannedIntervals(), 1);
  }
}

Eigen::MatrixXd PlanningProblem::projected(const Eigen::MatrixXd& rates) const {
  Eigen::MatrixXd result = rates;
  if (energy_left_.size() > 0) {
    result.bottomRows(plannedIntervals()) = polytope_.projectSchedule(
        rates.bottomRows(plannedIntervals()), interval_length_, energy_left_, &budget_multipliers_);
    return result;
  }
  for (int k = first_interval_; k < intervals(); ++k) {
    result.row(k) = polytope_.project(rates.row(k).transpose()).transpose();
  }
  return result;
}

double PlanningProblem::largestChange(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const {
  if (plannedIntervals() == 0) return 0.0;
  return (a - b).bottomRows(plannedIntervals()).cwiseAbs().maxCoeff() / rate_unit_;
}

double PlanningProblem::inner(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const {
  return a.bottomRows(plannedIntervals()).cwiseProduct(b.bottomRows(plannedIntervals())).sum();
}

double costUnit(double cost) {
  return std::isfinite(cost) && std::abs(cost) > 0.0 ? std::abs(cost) : 1.0;
}

double projectedGradientResidual(const PlanningProblem& problem, const Eigen::MatrixXd& rates,
                                 const CostGradient& cg) {
  if (problem.variables() == 0) return 0.0;
  if (!std::isfinite(cg.cost)) return std::numeric_limits<double>::infinity();
  const double unit = problem.rateUnit();
  const double step = unit * unit / costUnit(cg.cost);
  return problem.largestChange(rates, problem.projected(rates - step * cg.gradient));
}

}  // namespace sensornet::planning
