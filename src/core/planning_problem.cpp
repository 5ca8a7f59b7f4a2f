#include "planning_problem.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

namespace sensornet::planning {
namespace {

// An upper bound on the total rate Σ_j λ_j that the polytope allows the sensors in service:
// b_i / min_j C_ij of a row that weighs every one of them (the budget), else Σ_j λ̄_j.
double totalRateBound(const RatePolytope& polytope) {
  const Eigen::MatrixXd& C = polytope.constraints().C;
  const Eigen::VectorXd& b = polytope.constraints().b;
  const Eigen::VectorXd max_rates = polytope.maxRates();
  double bound = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (Eigen::Index i = 0; i < C.rows(); ++i) {
    double smallest = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < C.cols(); ++j) {
      if (!polytope.isExcluded(static_cast<int>(j))) smallest = std::min(smallest, C(i, j));
    }
    if (smallest > 0.0) bound = std::min(bound, b(i) / smallest);
  }
  if (std::isfinite(bound)) return bound;
  for (Eigen::Index j = 0; j < C.cols(); ++j) {
    if (!polytope.isExcluded(static_cast<int>(j)) && std::isfinite(max_rates(j))) sum += max_rates(j);
  }
  return sum;
}

// RK4 steps per interval: the request's, or more where the surrogate's flow is stiff for the
// interval length. Its linearization has eigenvalues of size at most 2 ||A|| (the Lyapunov part)
// plus the total rate (each measurement term's derivative is at most λ_j in norm), and classical
// RK4 is stable on the negative real axis for h |μ| < 2.78, so a step keeps h (2 ||A|| + Σ λ)
// <= 2. Coarse intervals with high rates (T = 2 in 4 intervals, budget 12) otherwise overflow.
int substepsFor(const Scenario& scenario, const PlanRequest& request,
                const RatePolytope& polytope) {
  const double interval = scenario.horizon_s / scenario.intervals;
  const double norm_a = Eigen::JacobiSVD<Eigen::MatrixXd>(scenario.plant.A).singularValues()(0);
  const double stiffness = 2.0 * norm_a +
                           totalRateBound(polytope);
  const double needed = std::ceil(interval * stiffness / 2.0);
  if (!std::isfinite(needed)) return request.substeps;
  return std::max(request.substeps, static_cast<int>(std::min(needed, 1000.0)));
}

TranscriptionOptions transcriptionOptions(const Scenario& scenario, const PlanRequest& request,
                                          const RatePolytope& polytope) {
  TranscriptionOptions options;
  options.substeps = substepsFor(scenario, request, polytope);
  options.start_time = request.start_time;
  options.start_covariance = request.start_covariance;
  options.delivery = request.delivery;
  return options;
}

}  // namespace

PlanningProblem::PlanningProblem(const Scenario& scenario, const PlanRequest& request,
                                 SurrogateForm form)
    : polytope_(scenario.constraints, request.excluded_sensors),
      transcription_(form, scenario, transcriptionOptions(scenario, request, polytope_)),
      first_interval_(transcription_.firstInterval()),
      rate_unit_(1.0),
      rates_(Eigen::MatrixXd::Zero(scenario.intervals, scenario.sensorCount())) {
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
  const bool warm = request.warm_start && request.surrogate != PlanSurrogate::Uniform;
  const Eigen::VectorXd uniform = polytope_.uniformRates();
  for (int k = first_interval_; k < intervals(); ++k) {
    const Eigen::VectorXd start = warm ? polytope_.project(rates_.row(k).transpose()) : uniform;
    rates_.row(k) = start.transpose();
  }
}

Eigen::MatrixXd PlanningProblem::projected(const Eigen::MatrixXd& rates) const {
  Eigen::MatrixXd result = rates;
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
