#include "sensornet/core/planner.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "planning_problem.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/mc_planner.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "plan request";

void checkRequest(const Scenario& scenario, const PlanRequest& request) {
  if (!(request.tolerance > 0.0)) {
    throw InputError(kSource, "tolerance",
                     "a number > 0, got " + std::to_string(request.tolerance));
  }
  if (request.max_iterations < 0) {
    throw InputError(kSource, "max_iterations",
                     "an integer >= 0, got " + std::to_string(request.max_iterations));
  }
  if (!(request.max_seconds > 0.0)) {
    throw InputError(kSource, "max_seconds",
                     "a number > 0, got " + std::to_string(request.max_seconds));
  }
  if (request.delivery) {
    const Eigen::MatrixXd& delivery = *request.delivery;
    if (delivery.rows() != scenario.intervals || delivery.cols() != scenario.sensorCount()) {
      throw InputError(kSource, "delivery",
                       "an " + std::to_string(scenario.intervals) + " x " +
                           std::to_string(scenario.sensorCount()) + " matrix (intervals x sensors)");
    }
    if (!delivery.allFinite() || (delivery.array() < 0.0).any() ||
        (delivery.array() > 1.0).any()) {
      throw InputError(kSource, "delivery", "factors in [0, 1]");
    }
  }
  if (request.warm_start) {
    const RateSchedule& warm = *request.warm_start;
    if (warm.intervals() != scenario.intervals || warm.sensorCount() != scenario.sensorCount() ||
        !(std::abs(warm.horizon() - scenario.horizon_s) <= 1e-12 * scenario.horizon_s)) {
      throw InputError(kSource, "warm_start",
                       "a schedule of " + std::to_string(scenario.intervals) + " intervals x " +
                           std::to_string(scenario.sensorCount()) + " sensors over T = " +
                           std::to_string(scenario.horizon_s));
    }
    if (!warm.rates().allFinite() || (warm.rates().array() < 0.0).any()) {
      throw InputError(kSource, "warm_start", "finite rates >= 0");
    }
  }
}

}  // namespace

SurrogateForm formOf(PlanSurrogate surrogate) {
  return surrogate == PlanSurrogate::Covariance ? SurrogateForm::Covariance
                                                : SurrogateForm::Information;
}

std::string_view describe(PlanSurrogate surrogate) { return wordOf(surrogate); }

double kktResidual(const Scenario& scenario, const RateSchedule& schedule, SurrogateForm form,
                   const PlanRequest& request) {
  PlanRequest at_schedule = request;
  at_schedule.warm_start = schedule;
  checkRequest(scenario, at_schedule);
  planning::PlanningProblem problem(scenario, at_schedule, form);
  problem.setRates(schedule.rates());  // as given (the problem projects a warm start)
  const CostGradient cg = problem.transcription().costAndGradient(problem.rates());
  return planning::projectedGradientResidual(problem, problem.rates(), cg);
}

PlanResult planSchedule(const Scenario& scenario, const PlanRequest& request) {
  checkRequest(scenario, request);
  if (request.surrogate == PlanSurrogate::MonteCarlo) return planForRealizedCost(scenario, request);
  const auto start = planning::Clock::now();
  const SurrogateForm form = formOf(request.surrogate);
  planning::PlanningProblem problem(scenario, request, form);

  PlanResult result;
  if (request.surrogate == PlanSurrogate::Uniform || problem.variables() == 0) {
    result.status = "not_optimized";
    result.kkt_residual = std::numeric_limits<double>::quiet_NaN();
  } else {
    const Eigen::MatrixXd start_rates = problem.rates();
    const double start_cost = problem.transcription().cost(start_rates);
    const planning::PlanningOutcome outcome =
        request.method == PlanMethod::Ipopt
            ? planning::solveWithIpopt(problem, request, start)
            : planning::solveWithProjectedQuasiNewton(problem, request, start);
    result.iterations = outcome.iterations;
    result.evaluations = outcome.evaluations;
    result.status = outcome.status;
    // Exactly admissible (IPOPT's interior iterates may sit a rounding error outside).
    problem.setRates(problem.projected(problem.rates()));
    // A failed solve may end anywhere; never return something worse than where it started.
    if (!(problem.transcription().cost(problem.rates()) <= start_cost)) {
      problem.setRates(start_rates);
    }
  }
  result.solve_seconds = planning::secondsSince(start);

  const CostGradient final_cost = problem.transcription().costAndGradient(problem.rates());
  result.discretized_objective = final_cost.cost;
  if (result.status != "not_optimized") {
    result.kkt_residual =
        planning::projectedGradientResidual(problem, problem.rates(), final_cost);
  }
  result.schedule = RateSchedule(scenario.horizon_s, problem.rates());

  RolloutOptions accurate;  // relative tolerance 1e-10
  accurate.start_time = request.start_time;
  accurate.start_covariance = request.start_covariance;
  result.bracket = computeBracket(scenario, result.schedule, accurate);
  result.objective = form == SurrogateForm::Covariance ? result.bracket.cov : result.bracket.info;
  if (request.delivery) {  // what the planner minimized: the cost at the delivered rates
    const RateSchedule delivered(scenario.horizon_s,
                                 result.schedule.rates().cwiseProduct(*request.delivery));
    result.objective = rollout(form, scenario, delivered, accurate).cost;
  }
  return result;
}

}  // namespace sensornet
