#pragma once
// Private to the planner: the reduced scheduling problem that both optimizers solve (the planned
// intervals k0..N-1 times the sensors in service, over the admissible rates), and the two
// optimizers. Not installed; planner.hpp is the public face.
//
//   PlanningProblem problem(scenario, request, SurrogateForm::Information);
//   const PlanningOutcome outcome = solveWithProjectedQuasiNewton(problem, request, start);
//   problem.rates();  // the solution, N x M

#include <Eigen/Core>
#include <chrono>
#include <string>
#include <vector>

#include "sensornet/planning/planner.hpp"
#include "sensornet/planning/rate_polytope.hpp"
#include "sensornet/planning/surrogate_transcription.hpp"

namespace sensornet::planning {

using Clock = std::chrono::steady_clock;

[[nodiscard]] inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The optimization variables are the planned rows of an N x M rate matrix; rows before the first
// planned interval and columns of excluded sensors are constants.
class PlanningProblem {
 public:
  // The start point: warm_start's rows projected onto the admissible rates (for Uniform, or
  // without a warm start, the uniform rates of the sensors in service).
  PlanningProblem(const Scenario& scenario, const PlanRequest& request, SurrogateForm form);

  [[nodiscard]] int firstInterval() const { return first_interval_; }
  [[nodiscard]] int intervals() const { return static_cast<int>(rates_.rows()); }
  [[nodiscard]] int plannedIntervals() const { return intervals() - first_interval_; }
  [[nodiscard]] int variables() const {
    return plannedIntervals() * static_cast<int>(in_service_.size());
  }
  [[nodiscard]] const std::vector<int>& inService() const { return in_service_; }
  [[nodiscard]] const RatePolytope& polytope() const { return polytope_; }
  [[nodiscard]] const Eigen::MatrixXd& C() const { return polytope_.constraints().C; }
  [[nodiscard]] const Eigen::VectorXd& b() const { return polytope_.constraints().b; }
  [[nodiscard]] SurrogateTranscription& transcription() { return transcription_; }

  // The current rate matrix: the start point, or the last one set.
  [[nodiscard]] const Eigen::MatrixXd& rates() const { return rates_; }
  void setRates(const Eigen::MatrixXd& rates) { rates_ = rates; }

  // `rates` with its planned rows projected onto the admissible rates: every interval's
  // polytope, and with energy budgets, the schedule-level set that adds them.
  [[nodiscard]] Eigen::MatrixXd projected(const Eigen::MatrixXd& rates) const;
  // Per sensor, the energy the planned intervals may spend, Σ_{k >= k0} h λ_kj <= energyLeft()_j:
  // E_j less what was spent before start_time (PlanRequest::energy_spent), that part of
  // interval k0 included, since k0 is re-planned as a whole: so both the schedule as written
  // and the rates in force over the episode meet E_j. +infinity without a budget; empty when
  // the scenario has none.
  [[nodiscard]] const Eigen::VectorXd& energyLeft() const { return energy_left_; }
  [[nodiscard]] double intervalLength() const { return interval_length_; }
  // The unit of rates in the scale-free measures: the largest λ̄_j of a sensor in service.
  [[nodiscard]] double rateUnit() const { return rate_unit_; }
  // max over planned rates of |a - b|, in rate units.
  [[nodiscard]] double largestChange(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const;
  // <a, b> over the planned rows.
  [[nodiscard]] double inner(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const;
  // tr S_j = tr(H_j' R_j^-1 H_j) per sensor (1 where it is not a positive number): how much a
  // unit of rate of sensor j adds to the information, the scale of its rates' curvature.
  [[nodiscard]] const Eigen::VectorXd& sensorInformation() const { return sensor_information_; }

 private:
  RatePolytope polytope_;
  SurrogateTranscription transcription_;
  int first_interval_;
  std::vector<int> in_service_;
  double rate_unit_;
  Eigen::MatrixXd rates_;
  Eigen::VectorXd sensor_information_;
  double interval_length_;
  Eigen::VectorXd energy_left_;
  // The last schedule projection's multipliers, where the next one starts (projected() is
  // const to its callers; each problem is used by one thread).
  mutable Eigen::VectorXd budget_multipliers_;
};

// |J|, the unit of cost in the scale-free measures (1 when J is 0 or not finite).
[[nodiscard]] double costUnit(double cost);

// PlanResult::kkt_residual at `rates` with cost and gradient `cg`: max over planned rates of
// |x - Π(x - ∇f(x))| with x = λ / rateUnit and f = J / |J(λ)|.
[[nodiscard]] double projectedGradientResidual(const PlanningProblem& problem,
                                               const Eigen::MatrixXd& rates,
                                               const CostGradient& cg);

struct PlanningOutcome {
  int iterations = 0;
  PlanStatus status = PlanStatus::Failed;  // as PlanResult::status
  int evaluations = 0;   // cost-and-gradient evaluations of the transcription
  std::string failure{};  // as PlanResult::failure
};

// The default optimizer (projected_quasi_newton.cpp). Leaves its answer in problem.rates().
[[nodiscard]] PlanningOutcome solveWithProjectedQuasiNewton(PlanningProblem& problem,
                                                            const PlanRequest& request,
                                                            Clock::time_point start);

// IPOPT with a limited-memory Hessian (ipopt_rate_solver.cpp). Leaves its answer in
// problem.rates(), not yet projected.
[[nodiscard]] PlanningOutcome solveWithIpopt(PlanningProblem& problem, const PlanRequest& request,
                                             Clock::time_point start);

}  // namespace sensornet::planning
