#include "sensornet/planning/planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "planning_problem.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/planning/mc_planner.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "plan request";

// How closely the planner's RK4 transcription must reproduce the accurate rollout's cost
// (relative), at the start point and at the solution, and the most RK4 steps per interval it
// takes to get there. 1e-2 by measurement (bench/README.md): where the transcription is
// stable its error falls 10-20x per doubling, so 1e-2 costs at most one doubling more than a
// looser bound would, while its plans' accurate costs then agree with those planned at 64 steps
// to about 1e-4; a 2-state cov plan at 400 Hz has an infinite cost at 2 steps and 8e-4 at 4, the
// default scenario's info plan is 25% off at 2 steps (its running cost <W, Y^-1> falls from
// 100 within the first interval) and 0.6% at 16. 256 steps bound the cost of a check.
constexpr double kTranscriptionAgreement = 1e-2;
constexpr int kMaxSubsteps = 256;

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
  if (request.energy_spent) {
    const Eigen::VectorXd& spent = *request.energy_spent;
    if (spent.size() != scenario.sensorCount() || !spent.allFinite() ||
        (spent.array() < 0.0).any()) {
      throw InputError(kSource, "energy_spent",
                       std::to_string(scenario.sensorCount()) +
                           " finite expected counts >= 0 (one per sensor)");
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

// The accurate rollout's cost of `rates` (N x M) over [start_time, T]: of the delivered rates
// when the request has delivery factors, as the transcription sees them.
double accurateCost(const Scenario& scenario, const PlanRequest& request, SurrogateForm form,
                    const Eigen::MatrixXd& rates) {
  RolloutOptions accurate;  // relative tolerance 1e-10
  accurate.start_time = request.start_time;
  accurate.start_covariance = request.start_covariance;
  const Eigen::MatrixXd seen = request.delivery ? rates.cwiseProduct(*request.delivery) : rates;
  return rollout(form, scenario, RateSchedule(scenario.horizon_s, seen), accurate).cost;
}

// True when the transcription's cost agrees with the accurate one within
// kTranscriptionAgreement (a non-finite transcription cost never does).
bool transcriptionAgrees(double discretized, double accurate) {
  if (!std::isfinite(discretized)) return false;
  return std::abs(discretized - accurate) <= kTranscriptionAgreement * std::abs(accurate);
}

bool canRefine(const PlanRequest& sized) { return sized.substeps < kMaxSubsteps; }

void refine(PlanRequest& sized) { sized.substeps = std::min(2 * sized.substeps, kMaxSubsteps); }

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

// The transcription's RK4 steps per interval are chosen by measurement rather than by an a priori
// bound on the flow's stiffness (which underestimated the covariance form's P H' R^-1 H P term
// and ignored accuracy): from request.substeps, doubled until the transcription's cost at the
// start point agrees with the accurate rollout's; after the solve, if it does not agree at the
// solution (the rates moved to where the flow is stiffer), doubled again and re-solved from the
// solution, until it agrees or kMaxSubsteps is reached.
PlanResult planSchedule(const Scenario& scenario, const PlanRequest& request) {
  checkRequest(scenario, request);
  if (request.surrogate == PlanSurrogate::MonteCarlo) return planForRealizedCost(scenario, request);
  const auto start = planning::Clock::now();
  const SurrogateForm form = formOf(request.surrogate);
  PlanRequest sized = request;
  sized.substeps = std::clamp(request.substeps, 1, kMaxSubsteps);
  std::optional<planning::PlanningProblem> problem;
  problem.emplace(scenario, sized, form);
  const Eigen::MatrixXd start_rates = problem->rates();
  const double start_accurate = accurateCost(scenario, request, form, start_rates);
  while (!transcriptionAgrees(problem->transcription().cost(start_rates), start_accurate) &&
         canRefine(sized)) {
    refine(sized);
    problem.emplace(scenario, sized, form);
  }

  PlanResult result;
  if (request.surrogate == PlanSurrogate::Uniform || problem->variables() == 0) {
    result.status = PlanStatus::NotOptimized;
    result.kkt_residual = std::numeric_limits<double>::quiet_NaN();
  } else {
    for (;;) {
      const planning::PlanningOutcome outcome =
          request.method == PlanMethod::Ipopt
              ? planning::solveWithIpopt(*problem, sized, start)
              : planning::solveWithProjectedQuasiNewton(*problem, sized, start);
      result.iterations += outcome.iterations;
      result.evaluations += outcome.evaluations;
      result.status = outcome.status;
      result.failure = outcome.failure;
      // Exactly admissible (IPOPT's interior iterates may sit a rounding error outside).
      problem->setRates(problem->projected(problem->rates()));
      const bool resolvable =
          outcome.status == PlanStatus::Optimal || outcome.status == PlanStatus::Acceptable ||
          outcome.status == PlanStatus::Stalled || outcome.status == PlanStatus::Failed;
      if (!resolvable || !canRefine(sized) ||
          transcriptionAgrees(problem->transcription().cost(problem->rates()),
                              accurateCost(scenario, request, form, problem->rates()))) {
        break;
      }
      refine(sized);
      sized.warm_start = RateSchedule(scenario.horizon_s, problem->rates());
      sized.max_iterations = std::max(0, request.max_iterations - result.iterations);
      problem.emplace(scenario, sized, form);
    }
    // A failed solve may end anywhere; never return something worse than where it started.
    if (!(problem->transcription().cost(problem->rates()) <=
          problem->transcription().cost(start_rates))) {
      problem->setRates(start_rates);
    }
  }
  result.substeps = sized.substeps;
  result.solve_seconds = planning::secondsSince(start);

  const CostGradient final_cost = problem->transcription().costAndGradient(problem->rates());
  result.discretized_objective = final_cost.cost;
  if (result.status != PlanStatus::NotOptimized) {
    result.kkt_residual =
        planning::projectedGradientResidual(*problem, problem->rates(), final_cost);
  }
  result.schedule = RateSchedule(scenario.horizon_s, problem->rates());

  RolloutOptions accurate;  // relative tolerance 1e-10
  accurate.start_time = request.start_time;
  accurate.start_covariance = request.start_covariance;
  result.bracket = computeBracket(scenario, result.schedule, accurate);
  result.objective = form == SurrogateForm::Covariance ? result.bracket.cov : result.bracket.info;
  if (request.delivery) {  // what the planner minimized: the cost at the delivered rates
    result.objective = accurateCost(scenario, request, form, result.schedule.rates());
  }
  return result;
}

}  // namespace sensornet
